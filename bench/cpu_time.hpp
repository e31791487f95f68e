// What the project's own bench programs measure with: the calling thread's CPU time (other load on
// the machine does not count) and the median of repeated rounds.
#pragma once

#include <time.h>

#include <algorithm>
#include <vector>

namespace pbppo::bench {

inline double CpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

inline double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace pbppo::bench
