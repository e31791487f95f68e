// Per-stage latency of the control tick: receive, observe, infer, supervise, send, the whole
// tick, and the wake-up jitter, each in a LatencyHistogram, plus the deadline-miss count.
// The tick records (noexcept, no allocation, no lock); a non-real-time thread takes a report and
// formats it as a cyclictest-style text table or JSON (report/ draws it as a PNG).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <string>

#include "runtime/rt/latency_histogram.hpp"

namespace pbppo::rt {

enum class Stage : std::uint8_t { kReceive, kObserve, kInfer, kSupervise, kSend, kTick, kJitter };
inline constexpr std::size_t kStageCount = 7;
const char* ToString(Stage s) noexcept;

class TickProfiler {
 public:
  void Record(Stage s, std::int64_t ns) noexcept { hist_[static_cast<std::size_t>(s)].Record(ns); }
  void CountDeadlineMiss() noexcept {
    misses_.store(misses_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  }
  std::uint64_t deadline_misses() const noexcept { return misses_.load(std::memory_order_relaxed); }
  const LatencyHistogram& histogram(Stage s) const noexcept { return hist_[static_cast<std::size_t>(s)]; }
  void Reset() noexcept;  // writer thread only

 private:
  std::array<LatencyHistogram, kStageCount> hist_;
  std::atomic<std::uint64_t> misses_{0};
};

struct ProfileReport {
  std::array<LatencySnapshot, kStageCount> snapshots;
  std::array<LatencyStats, kStageCount> stats;
  std::uint64_t deadline_misses = 0;
};

ProfileReport TakeReport(const TickProfiler& p);

// cyclictest-style table in microseconds: stage, count, min, avg, p50, p99, p99.9, p99.99, max.
std::string FormatText(const ProfileReport& r);
// {"unit": "ns", "deadline_misses": n, "stages": {"receive": {"count", "min", "mean", "p50", ...}}}
std::string FormatJson(const ProfileReport& r);

}  // namespace pbppo::rt
