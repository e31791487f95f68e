// The clocks of the runtime, read without a system call (vDSO). Everything that measures time
// (tick clocks, latencies, transport ages, logs) uses these two. Each is one clock_gettime call and
// nothing else, so both are async-signal-safe (pbppo train's SIGINT handler reads MonotonicNs).
#pragma once

#include <cstdint>
#include <ctime>

namespace pbppo {

// CLOCK_MONOTONIC in nanoseconds: durations, deadlines, ages.
inline constexpr std::int64_t kNsPerS = 1'000'000'000;

std::int64_t MonotonicNs() noexcept;
// CLOCK_REALTIME in nanoseconds: time stamps meant for people and other machines (candump logs).
std::int64_t RealtimeNs() noexcept;
// Advances an absolute CLOCK_MONOTONIC deadline by `ns` (a sleeper's next period).
void AddNs(timespec* t, std::int64_t ns) noexcept;

}  // namespace pbppo
