// The quadruped rig's per-phase report over a long schedule (sim/quadruped_rig.hpp,
// ReportOfTrace): every phase is reported, however many there are. A trace of 300 phases of 1 s
// at 1 kHz, each phase commanding its own speed and measured 0.01 m/s slower; from the 128th
// phase on the phase index used to wrap (8 bits) and the report printed zeros.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "runtime/loop/schedule.hpp"
#include "sim_hil/quadruped_rig.hpp"

using namespace pbppo;

namespace {

constexpr int kPhases = 300;
constexpr int kTicksPerPhase = 1000;
constexpr double kTick = 0.001;

double CommandOf(int phase) {
  return 0.1 + 0.001 * phase;
}

}  // namespace

TEST_CASE("rig report: 300 phases, each with its own command and error, after the 127th too") {
  loop::Schedule schedule;
  for (int p = 0; p < kPhases; ++p) {
    loop::SchedulePhase ph;
    ph.name = "phase " + std::to_string(p);
    ph.start_s = p * 1.0;
    ph.duration_s = 1.0;
    schedule.phases.push_back(ph);
  }
  std::vector<sim::RigSample> trace;
  trace.reserve(static_cast<std::size_t>(kPhases) * kTicksPerPhase + 10);
  for (std::uint64_t tick = 0; tick < static_cast<std::uint64_t>(kPhases) * kTicksPerPhase + 10; ++tick) {
    sim::RigSample s;
    // The harness's convention: the sample after tick k is at (k + 1) ticks, its phase at k.
    const double t = static_cast<double>(tick) * kTick;
    s.t_s = static_cast<double>(tick + 1) * kTick;
    s.schedule_phase = schedule.PhaseAt(t);
    const int p = s.schedule_phase;
    if (p >= 0) {
      s.cmd_vx = static_cast<float>(CommandOf(p));
      s.vx_mps = static_cast<float>(CommandOf(p) - 0.01);
    }
    trace.push_back(s);
  }
  CHECK(trace.back().schedule_phase == -1);
  CHECK(trace[200 * kTicksPerPhase + 5].schedule_phase == 200);

  const sim::RigReport r = sim::ReportOfTrace(trace, schedule, 0.5, false);
  REQUIRE(r.phases.size() == kPhases);
  for (int p = 0; p < kPhases; ++p) {
    const sim::PhaseTracking& t = r.phases[static_cast<std::size_t>(p)];
    CAPTURE(p);
    CHECK(t.samples >= 499);
    CHECK(t.samples <= 501);
    CHECK(t.command[0] == doctest::Approx(CommandOf(p)).epsilon(1e-6));
    CHECK(t.mean_abs_error[0] == doctest::Approx(0.01).epsilon(1e-3));
    CHECK(t.mean_measured[0] == doctest::Approx(CommandOf(p) - 0.01).epsilon(1e-5));
  }
  CHECK(r.max_planar_error == doctest::Approx(0.01).epsilon(1e-3));
  CHECK_FALSE(r.fell);
}

TEST_CASE("rig report: a sample's time keeps the tick after a day of 1 kHz ticks") {
  // 3 days of ticks: a float time would step by 15.6 ms here, a double by the tick.
  const std::uint64_t tick = 3ull * 86400ull * 1000ull;
  sim::RigSample a, b;
  a.t_s = static_cast<double>(tick) * kTick;
  b.t_s = static_cast<double>(tick + 1) * kTick;
  CHECK(b.t_s - a.t_s == doctest::Approx(kTick).epsilon(1e-6));
}
