#include "runtime/rt/tick_profiler.hpp"

#include <cstdio>
#include <nlohmann/json.hpp>

namespace pbppo::rt {

const char* ToString(Stage s) noexcept {
  switch (s) {
    case Stage::kReceive: return "receive";
    case Stage::kObserve: return "observe";
    case Stage::kInfer: return "infer";
    case Stage::kSupervise: return "supervise";
    case Stage::kSend: return "send";
    case Stage::kTick: return "tick";
    case Stage::kJitter: return "jitter";
  }
  return "unknown";
}

void TickProfiler::Reset() noexcept {
  for (auto& h : hist_) h.Reset();
  misses_.store(0, std::memory_order_relaxed);
}

ProfileReport TakeReport(const TickProfiler& p) {
  ProfileReport r;
  for (std::size_t i = 0; i < kStageCount; ++i) {
    r.snapshots[i] = p.histogram(static_cast<Stage>(i)).Snapshot();
    r.stats[i] = r.snapshots[i].Stats();
  }
  r.deadline_misses = p.deadline_misses();
  return r;
}

std::string FormatText(const ProfileReport& r) {
  std::string out;
  char line[200];
  std::snprintf(line, sizeof line, "%-10s %10s %9s %9s %9s %9s %9s %9s %9s  (us)\n", "stage", "count", "min", "avg",
                "p50", "p99", "p99.9", "p99.99", "max");
  out += line;
  auto us = [](double ns) { return ns / 1000.0; };
  for (std::size_t i = 0; i < kStageCount; ++i) {
    const LatencyStats& s = r.stats[i];
    if (s.count == 0) continue;
    std::snprintf(line, sizeof line, "%-10s %10llu %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f\n",
                  ToString(static_cast<Stage>(i)), static_cast<unsigned long long>(s.count),
                  us(static_cast<double>(s.min_ns)), us(s.mean_ns), us(static_cast<double>(s.p50_ns)),
                  us(static_cast<double>(s.p99_ns)), us(static_cast<double>(s.p999_ns)),
                  us(static_cast<double>(s.p9999_ns)), us(static_cast<double>(s.max_ns)));
    out += line;
  }
  std::snprintf(line, sizeof line, "deadline misses: %llu\n", static_cast<unsigned long long>(r.deadline_misses));
  out += line;
  return out;
}

std::string FormatJson(const ProfileReport& r) {
  nlohmann::json j;
  j["unit"] = "ns";
  j["deadline_misses"] = r.deadline_misses;
  nlohmann::json stages = nlohmann::json::object();
  for (std::size_t i = 0; i < kStageCount; ++i) {
    const LatencyStats& s = r.stats[i];
    stages[ToString(static_cast<Stage>(i))] = {{"count", s.count},     {"min", s.min_ns}, {"mean", s.mean_ns},
                                               {"p50", s.p50_ns},      {"p99", s.p99_ns}, {"p99.9", s.p999_ns},
                                               {"p99.99", s.p9999_ns}, {"max", s.max_ns}};
  }
  j["stages"] = stages;
  return j.dump(2) + "\n";
}

}  // namespace pbppo::rt
