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

}  // namespace pbppo
