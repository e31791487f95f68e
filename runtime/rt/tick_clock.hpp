// Tick clocks: what the control loop waits on between ticks. The loop's logic sees only the tick
// index; the clock decides when a tick starts.
//
//   FreeRunningClock  absolute deadlines start + k * period on CLOCK_MONOTONIC
//                     (clock_nanosleep TIMER_ABSTIME: no drift). A tick that starts after its
//                     deadline's successor is a deadline miss: the clock counts it, does not sleep,
//                     and skips whole periods that have already passed (no catch-up burst).
//                     Wake-up jitter = actual wake - deadline.
//   LockStepClock     the tick advances when a driver (a simulator in lock-step) calls Advance().
//   PacedClock        the next tick starts when the last one ended: the transport paces the loop
//                     (a CAN transport in lock-step waits for each tick's replies).
//
// Wait() allocates nothing and takes no lock; it blocks, by design, until the tick is due.
#pragma once

#include <atomic>
#include <cstdint>

#include "runtime/core/clock.hpp"

namespace pbppo::rt {

struct TickTiming {
  std::uint64_t tick = 0;        // 0, 1, 2, ...
  std::int64_t deadline_ns = 0;  // when the tick was due
  std::int64_t wake_ns = 0;      // when Wait returned
  std::int64_t jitter_ns = 0;    // wake - deadline (free-running only)
  bool missed = false;           // the tick started late (the previous one overran)
  std::uint32_t consecutive_misses = 0;
};

class TickClock {
 public:
  virtual ~TickClock() = default;
  // Blocks until the next tick is due and describes it; false once Stop() was called.
  virtual bool Wait(TickTiming& t) noexcept = 0;
  // Any thread, async-signal-safe: the current or next Wait returns false.
  virtual void Stop() noexcept = 0;
  virtual std::uint64_t deadline_misses() const noexcept = 0;
};

class FreeRunningClock final : public TickClock {
 public:
  explicit FreeRunningClock(std::int64_t period_ns) noexcept : period_ns_(period_ns > 0 ? period_ns : 1) {}
  // The first tick is due at start_ns (default: now).
  void Start(std::int64_t start_ns = -1) noexcept;
  bool Wait(TickTiming& t) noexcept override;
  void Stop() noexcept override { stop_.store(true, std::memory_order_relaxed); }
  std::uint64_t deadline_misses() const noexcept override { return misses_.load(std::memory_order_relaxed); }
  std::uint64_t skipped_periods() const noexcept { return skipped_.load(std::memory_order_relaxed); }
  std::int64_t period_ns() const noexcept { return period_ns_; }

 private:
  std::int64_t period_ns_;
  std::int64_t next_ns_ = 0;
  std::uint64_t tick_ = 0;
  bool started_ = false;
  std::uint32_t consecutive_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> misses_{0}, skipped_{0};
};

class LockStepClock final : public TickClock {
 public:
  // Driver side: allow one more tick.
  void Advance() noexcept;
  bool Wait(TickTiming& t) noexcept override;
  void Stop() noexcept override;
  std::uint64_t deadline_misses() const noexcept override { return 0; }
  // Ticks the loop has started.
  std::uint64_t started() const noexcept { return started_.load(std::memory_order_acquire); }

 private:
  std::atomic<std::uint64_t> allowed_{0};
  std::atomic<std::uint64_t> started_{0};
  std::atomic<bool> stop_{false};
};

class PacedClock final : public TickClock {
 public:
  bool Wait(TickTiming& t) noexcept override;
  void Stop() noexcept override { stop_.store(true, std::memory_order_relaxed); }
  std::uint64_t deadline_misses() const noexcept override { return 0; }

 private:
  std::uint64_t tick_ = 0;
  std::atomic<bool> stop_{false};
};

}  // namespace pbppo::rt
