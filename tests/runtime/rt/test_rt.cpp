// runtime/rt: histogram quantiles against exact sorted data within the bucket resolution, a
// concurrent reader while the writer records, the clocks (absolute deadlines, misses, jitter,
// lock-step), the real-time set-up's graceful fallback, and the profiler's reports (text and JSON;
// tests/report draws them).
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>
#include <thread>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/rt/latency_histogram.hpp"
#include "runtime/rt/rt_setup.hpp"
#include "runtime/rt/tick_clock.hpp"
#include "runtime/rt/tick_profiler.hpp"

using namespace pbppo::rt;

TEST_CASE("latency histogram: buckets tile the range with at most 1/64 relative width") {
  std::int64_t next = 0;
  for (std::uint32_t b = 0; b < LatencyHistogram::kBuckets; ++b) {
    REQUIRE(LatencyHistogram::BucketLower(b) == next);
    REQUIRE(LatencyHistogram::BucketOf(next) == b);
    REQUIRE(LatencyHistogram::BucketOf(next + LatencyHistogram::BucketWidth(b) - 1) == b);
    if (next >= 64) REQUIRE(LatencyHistogram::BucketWidth(b) * 64 <= next);
    next += LatencyHistogram::BucketWidth(b);
  }
  CHECK(next == (std::int64_t{1} << 31));
  CHECK(LatencyHistogram::BucketOf(std::int64_t{1} << 40) == LatencyHistogram::kBuckets - 1);
  CHECK(LatencyHistogram::BucketOf(-5) == 0);
}

TEST_CASE("latency histogram: quantiles match sorted exact data within the bucket resolution") {
  std::mt19937_64 rng(11);
  std::lognormal_distribution<double> dist(std::log(20000.0), 1.2);  // ~20 us, long tail
  LatencyHistogram h;
  std::vector<std::int64_t> exact;
  for (int i = 0; i < 200000; ++i) {
    auto v = static_cast<std::int64_t>(dist(rng));
    if (i % 1000 == 0) v = static_cast<std::int64_t>(rng() % 50);  // some exact small values
    exact.push_back(v);
    h.Record(v);
  }
  std::sort(exact.begin(), exact.end());
  const LatencySnapshot s = h.Snapshot();
  CHECK(s.count() == exact.size());
  for (double q : {0.0, 0.001, 0.25, 0.5, 0.9, 0.99, 0.999, 0.9999, 1.0}) {
    const auto rank =
        std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(q * static_cast<double>(exact.size()))));
    const std::int64_t truth = exact[rank - 1];
    const std::int64_t got = s.Quantile(q);
    // Midpoint of the bucket holding the true value: within half a bucket, <= 0.8 % above 64 ns.
    CHECK_MESSAGE(std::abs(got - truth) <= std::max<std::int64_t>(0, truth / 128 + 1), "q=" << q);
  }
  const LatencyStats st = s.Stats();
  CHECK(st.min_ns == exact.front());
  CHECK(st.max_ns == exact.back());
  double sum = 0;
  for (auto v : exact) sum += static_cast<double>(v);
  CHECK(st.mean_ns == doctest::Approx(sum / static_cast<double>(exact.size())));
  CHECK(st.p50_ns <= st.p99_ns);
  CHECK(st.p99_ns <= st.p999_ns);
  CHECK(st.p9999_ns <= st.max_ns);
}

TEST_CASE("latency histogram: recording allocates nothing") {
  LatencyHistogram h;
  pbppo::AllocationScope scope;
  for (std::int64_t i = 0; i < 100000; ++i) h.Record(i * 977);
  CHECK(scope.count() == 0);
}

TEST_CASE("latency histogram: a reader takes consistent snapshots while the writer records") {
  LatencyHistogram h;
  std::atomic<bool> done{false}, reading{false};
  constexpr std::int64_t kN = 300000;
  std::thread writer([&] {
    while (!reading.load()) std::this_thread::yield();
    for (std::int64_t i = 1; i <= kN; ++i) h.Record(1000 + (i % 5000));
    done.store(true);
  });
  std::uint64_t last = 0;
  int snapshots = 0;
  reading.store(true);
  while (!done.load() || snapshots == 0) {
    const LatencySnapshot s = h.Snapshot();
    CHECK(s.count() >= last);  // monotonic
    last = s.count();
    if (s.count() > 0) {
      const std::int64_t p50 = s.Quantile(0.5);
      CHECK(p50 >= 1000);
      CHECK(p50 <= 6000);
    }
    ++snapshots;
  }
  writer.join();
  const LatencyStats st = h.Snapshot().Stats();
  CHECK(st.count == static_cast<std::uint64_t>(kN));
  CHECK(st.min_ns == 1000);
  CHECK(st.max_ns == 5999);
  CHECK(snapshots > 0);
}

TEST_CASE("free-running clock: absolute deadlines without drift, jitter measured, misses counted") {
  // 20 ms: a tick counts as missed only when it starts a whole period late, so a loaded machine
  // (a parallel build, sanitizers) does not turn scheduling delay into a false miss.
  constexpr std::int64_t kPeriod = 20000000;
  FreeRunningClock c(kPeriod);
  const std::int64_t start = pbppo::MonotonicNs() + 1000000;
  c.Start(start);
  TickTiming t;
  for (int k = 0; k < 10; ++k) {
    REQUIRE(c.Wait(t));
    CHECK(t.tick == static_cast<std::uint64_t>(k));
    CHECK(t.deadline_ns == start + k * kPeriod);  // no drift: deadlines are start + k * period
    CHECK(t.jitter_ns >= 0);
    CHECK(t.wake_ns >= t.deadline_ns);
    CHECK_FALSE(t.missed);
  }
  CHECK(c.deadline_misses() == 0);
  // A tick that overruns by 3.5 periods: the next tick starts late, at once; passed periods skipped.
  std::this_thread::sleep_for(std::chrono::milliseconds(70));
  REQUIRE(c.Wait(t));
  CHECK(t.missed);
  CHECK(t.consecutive_misses == 1);
  CHECK(c.deadline_misses() == 1);
  CHECK(c.skipped_periods() >= 2);
  CHECK((t.deadline_ns - start) % kPeriod == 0);
  REQUIRE(c.Wait(t));
  CHECK_FALSE(t.missed);
  CHECK(t.consecutive_misses == 0);
  c.Stop();
  CHECK_FALSE(c.Wait(t));
}

TEST_CASE("lock-step clock: a tick starts only when the driver advances - Stop releases the waiter") {
  LockStepClock c;
  std::atomic<int> ticks{0};
  std::thread loop([&] {
    TickTiming t;
    while (c.Wait(t)) {
      CHECK(t.tick == static_cast<std::uint64_t>(ticks.load()));
      ticks.fetch_add(1);
    }
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  CHECK(ticks.load() == 0);
  for (int k = 1; k <= 5; ++k) {
    c.Advance();
    while (ticks.load() < k) std::this_thread::yield();
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(10));
  CHECK(ticks.load() == 5);
  c.Stop();
  loop.join();
  CHECK(c.started() == 5);
}

TEST_CASE("real-time set-up: applies what is permitted, warns naming the step and the reason otherwise") {
  std::thread t([] {
    RtOptions o;
    o.fifo_priority = 80;
    o.cpu = 0;
    o.lock_memory = false;  // a test must not lock the whole runner's memory
    const RtSetupResult r = SetUpRealTime(o);
    CHECK(r.stack_prefaulted);
    CHECK(r.pinned);
    CHECK(r.cpu == 0);
    if (!r.fifo) {
      REQUIRE(r.warnings.size() == 1);
      CHECK(r.warnings[0].rfind("SCHED_FIFO 80: ", 0) == 0);
      CHECK(r.Summary().find("SCHED_OTHER") != std::string::npos);
    }
    o.fifo_priority = 150;
    o.cpu = 100000;
    const RtSetupResult bad = SetUpRealTime(o);
    CHECK_FALSE(bad.fifo);
    CHECK_FALSE(bad.pinned);
    REQUIRE(bad.warnings.size() == 2);
    CHECK(bad.warnings[0].find("SCHED_FIFO 150: priority outside [1, 99]") == 0);
    CHECK(bad.warnings[1].find("CPU affinity 100000: this machine has") == 0);
  });
  t.join();
}

TEST_CASE("tick profiler: text and JSON from the recorded stages") {
  TickProfiler p;
  for (int i = 0; i < 10000; ++i) {
    p.Record(Stage::kReceive, 300 + i % 50);
    p.Record(Stage::kInfer, 9000 + (i % 100) * 10);
    p.Record(Stage::kTick, 12000 + (i % 100) * 10);
    p.Record(Stage::kJitter, 5000 + i % 700);
  }
  p.CountDeadlineMiss();
  const ProfileReport r = TakeReport(p);
  const std::string text = FormatText(r);
  CHECK(text.find("stage") == 0);
  CHECK(text.find("infer") != std::string::npos);
  CHECK(text.find("observe") == std::string::npos);  // nothing recorded there
  CHECK(text.find("deadline misses: 1") != std::string::npos);
  const auto j = nlohmann::json::parse(FormatJson(r));
  CHECK(j["deadline_misses"] == 1);
  CHECK(j["stages"]["infer"]["count"] == 10000);
  CHECK(j["stages"]["infer"]["min"] == 9000);
  CHECK(j["stages"]["infer"]["max"] == 9990);
  CHECK(j["stages"]["observe"]["count"] == 0);
  const std::int64_t p50 = j["stages"]["infer"]["p50"];
  CHECK(std::abs(p50 - 9495) <= 9495 / 64);
}
