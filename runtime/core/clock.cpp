#include "runtime/core/clock.hpp"

#include <time.h>

namespace pbppo {
namespace {

std::int64_t Read(clockid_t id) noexcept {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

std::int64_t MonotonicNs() noexcept {
  return Read(CLOCK_MONOTONIC);
}

std::int64_t RealtimeNs() noexcept {
  return Read(CLOCK_REALTIME);
}

void AddNs(timespec* t, std::int64_t ns) noexcept {
  const std::int64_t n = t->tv_nsec + ns;
  t->tv_sec += static_cast<time_t>(n / 1'000'000'000);
  t->tv_nsec = static_cast<long>(n % 1'000'000'000);
}

}  // namespace pbppo
