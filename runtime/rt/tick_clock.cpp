#include "runtime/rt/tick_clock.hpp"

#include <time.h>

#include <cerrno>

namespace pbppo::rt {

void FreeRunningClock::Start(std::int64_t start_ns) noexcept {
  next_ns_ = start_ns >= 0 ? start_ns : MonotonicNs();
  tick_ = 0;
  consecutive_ = 0;
  started_ = true;
}

bool FreeRunningClock::Wait(TickTiming& t) noexcept {
  if (!started_) Start();
  if (stop_.load(std::memory_order_relaxed)) return false;
  const std::int64_t deadline = next_ns_;
  const std::int64_t now = MonotonicNs();
  bool missed = false;
  if (tick_ > 0 && now >= deadline + period_ns_) {
    // The previous tick ran past this deadline's successor: start at once, skip the passed periods.
    missed = true;
    if (consecutive_ < 0xffffffffu) ++consecutive_;  // saturates (a run of 2^32 misses stays one)
    misses_.store(misses_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    const std::int64_t behind = (now - deadline) / period_ns_;
    skipped_.store(skipped_.load(std::memory_order_relaxed) + static_cast<std::uint64_t>(behind),
                   std::memory_order_relaxed);
    next_ns_ = deadline + behind * period_ns_;
  } else {
    consecutive_ = 0;
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(deadline / 1000000000);
    ts.tv_nsec = static_cast<long>(deadline % 1000000000);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
      if (stop_.load(std::memory_order_relaxed)) return false;
    }
  }
  if (stop_.load(std::memory_order_relaxed)) return false;
  t.tick = tick_++;
  t.deadline_ns = next_ns_;
  t.wake_ns = MonotonicNs();
  t.jitter_ns = t.wake_ns - t.deadline_ns;
  t.missed = missed;
  t.consecutive_misses = consecutive_;
  next_ns_ += period_ns_;
  return true;
}

void LockStepClock::Advance() noexcept {
  allowed_.fetch_add(1, std::memory_order_release);
  allowed_.notify_one();
}

void LockStepClock::Stop() noexcept {
  stop_.store(true, std::memory_order_release);
  allowed_.fetch_add(1, std::memory_order_release);  // wake a waiter
  allowed_.notify_one();
}

bool LockStepClock::Wait(TickTiming& t) noexcept {
  const std::uint64_t k = started_.load(std::memory_order_relaxed);
  for (;;) {
    if (stop_.load(std::memory_order_acquire)) return false;
    const std::uint64_t a = allowed_.load(std::memory_order_acquire);
    if (a > k) break;
    allowed_.wait(a, std::memory_order_acquire);
  }
  t.tick = k;
  t.wake_ns = t.deadline_ns = MonotonicNs();
  t.jitter_ns = 0;
  t.missed = false;
  t.consecutive_misses = 0;
  started_.store(k + 1, std::memory_order_release);
  return true;
}

bool PacedClock::Wait(TickTiming& t) noexcept {
  if (stop_.load(std::memory_order_relaxed)) return false;
  t.tick = tick_++;
  t.wake_ns = t.deadline_ns = MonotonicNs();
  t.jitter_ns = 0;
  t.missed = false;
  t.consecutive_misses = 0;
  return true;
}

}  // namespace pbppo::rt
