// The supervisor on an AUV-like model (two speed set-points with rate limits, one sensor stream):
// limits and rate limits, every cause with its reason text, latching modes, reset only while
// disarmed, and the output invariant on random and hostile inputs.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/safety/supervisor.hpp"
#include "tests/support/auv_supervisor_model.hpp"

using namespace pbppo::safety;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The AUV-like model (tests/support/auv_supervisor_model.hpp); overruns 2 / 5.
SupervisorModel Model() {
  return pbppo::test::AuvLikeSupervisorModel();
}

struct In {
  double v = 0, w = 0;
  bool sample = true;  // one has arrived
  std::uint32_t age = 0;
  std::int32_t invalid = -1;  // the sample check's finding (an input index)
  double invalid_value = 0;
  bool peer_lost = false;
  std::uint32_t misses = 0;
  bool estop = false;
};

struct Rig {
  SupervisorModel m = Model();
  SupervisorState s = MakeSupervisorState(m);
  std::vector<double> out = std::vector<double>(2);
  Decision d;

  const Decision& Run(const In& in, int ticks = 1) {
    const double cmd[2] = {in.v, in.w};
    const StreamState stream{in.sample, in.age, in.invalid, in.invalid_value};
    TransportHealth link;
    link.lost = in.peer_lost;
    SupervisorInput x;
    x.command = cmd;
    x.streams = {&stream, 1};
    x.transports = {&link, 1};
    x.consecutive_deadline_misses = in.misses;
    x.estop_request = in.estop;
    for (int k = 0; k < ticks; ++k) d = Supervise(m, x, s.ticks, s, out);
    return d;
  }
  double v() const { return out[0]; }
  double w() const { return out[1]; }
  std::string Reason() const { return Describe(m, d); }
};

}  // namespace

TEST_CASE("auv supervisor: the model validates - bad ones are refused naming the field") {
  SupervisorModel m = Model();
  CHECK(ValidateSupervisorModel(m).ok());
  m.commands[0].min = m.commands[0].degraded_min = 0.2;
  CHECK(ValidateSupervisorModel(m).error().message ==
        "supervisor: command 'v': limits [0.2, 1.5] exclude zero (stopping must be allowed)");
  m = Model();
  m.commands[1].rate = kNaN;
  CHECK(ValidateSupervisorModel(m).error().message.find("command 'omega': rate = nan: must be > 0") !=
        std::string::npos);
  m = Model();
  m.commands[0].stop_rate = 0.05;
  CHECK(ValidateSupervisorModel(m).error().message.find("command 'v': stop_rate = 0.05: must be > 0 and >= the rate") !=
        std::string::npos);
  // Magnitudes no vehicle has (a unit error) are refused; the fuzzer found that limits near
  // DBL_MAX make a ramp step of the stop rate inexact.
  m = Model();
  m.commands[0].max = m.commands[0].degraded_max = 1.4e306;
  m.commands[0].stop_rate = 5e303;
  CHECK(ValidateSupervisorModel(m).error().message ==
        "supervisor: command 'v': max = 1.4e+306: magnitude must be <= 1000");
  m = Model();
  m.commands[1].stop_rate = 2000.0;
  CHECK(ValidateSupervisorModel(m).error().message ==
        "supervisor: command 'omega': stop_rate = 2000: magnitude must be <= 1000");
}

TEST_CASE("auv supervisor: command limits and rate limits, counted per cause") {
  Rig first;
  first.Run({.v = 3.0, .w = -2.0});
  CHECK(first.v() == doctest::Approx(0.1));  // one rate step from 0 towards 1.5
  CHECK(first.w() == doctest::Approx(-0.25));
  CHECK((first.d.causes & (1u << static_cast<unsigned>(Cause::kCommandLimit))) != 0);
  CHECK((first.d.causes & (1u << static_cast<unsigned>(Cause::kRateLimit))) != 0);
  CHECK(first.d.mode == Mode::kNominal);
  Rig r;
  r.Run({.v = 3.0, .w = -2.0}, 30);
  CHECK(r.v() == 1.5);
  CHECK(r.w() == -0.5);
  CHECK((r.d.causes & (1u << static_cast<unsigned>(Cause::kRateLimit))) == 0);
  CHECK(r.s.counts[Cause::kCommandLimit] == 30);  // command limit every tick
  CHECK(r.s.counts[Cause::kRateLimit] == 14);     // rate limited until 1.5 is reached on the 15th tick
  CHECK(r.s.mode == Mode::kNominal);
}

TEST_CASE("auv supervisor: a rate step that reaches the limit lands on it exactly, never an ulp past it") {
  // Found by fuzz_run.auv_supervisor: -7.97 + (0.1 - -7.97) is 0.10000000000000053 in doubles.
  Rig r;
  r.m.commands[0] = {"v", -8.0, 0.1, -8.0, 0.05, 10.0, StopKind::kRamp, 10.0, 0, -1};
  REQUIRE(ValidateSupervisorModel(r.m).ok());
  r.s.previous[0] = -7.97;
  r.Run({.v = 5.0});
  CHECK(r.v() == 0.1);
  CHECK((r.d.causes & (1u << static_cast<unsigned>(Cause::kCommandLimit))) != 0);
  CHECK((r.d.causes & (1u << static_cast<unsigned>(Cause::kRateLimit))) == 0);  // within one step
  r.s.previous[0] = 0.1;
  r.Run({.v = -9.0});
  CHECK(r.v() == -8.0);
}

TEST_CASE("auv supervisor: a stale sample degrades, then stops - the reason names the age") {
  Rig r;
  r.Run({.v = 1.0, .w = 0.2}, 20);
  CHECK(r.v() == 1.0);
  r.Run({.v = 1.0, .w = 0.2, .age = 2});
  CHECK(r.d.mode == Mode::kDegraded);
  CHECK(r.d.transition);
  CHECK(r.Reason() == "degraded: stale sample: sensor: age 2 ticks > 1");
  CHECK(r.v() == doctest::Approx(0.9));  // towards the degraded 0.75 at the rate limit
  r.Run({.v = 1.0, .w = 0.2, .age = 4});
  CHECK(r.d.mode == Mode::kSafeStop);
  CHECK(r.Reason() == "safe-stop: stale sample: sensor: age 4 ticks > 3");
  CHECK(r.v() == doctest::Approx(0.6));  // stop ramp 0.3 per tick
  CHECK(r.w() == 0.0);                   // hold heading
  // A fresh sample does not bring the mode back down.
  r.Run({.v = 1.0, .w = 0.2}, 5);
  CHECK(r.d.mode == Mode::kSafeStop);
  CHECK(r.v() == 0.0);
  CHECK(r.s.entered[static_cast<std::size_t>(Mode::kSafeStop)].cause == Cause::kStaleSample);
}

TEST_CASE("auv supervisor: lost peer and e-stop request zero the command at once") {
  Rig r;
  r.Run({.v = 1.0, .w = 0.2}, 20);
  r.Run({.v = 1.0, .w = 0.2, .sample = false, .age = 21});
  CHECK(r.d.mode == Mode::kEStop);
  CHECK(r.v() == 0.0);
  CHECK(r.Reason() == "e-stop: lost peer: sensor: no sample for 21 ticks > 20");
  Rig r2;
  r2.Run({.v = 1.0, .peer_lost = true});
  CHECK(r2.Reason() == "e-stop: lost peer: transport 'dds' reports the peer gone");
  Rig r3;
  r3.Run({.v = 1.0, .estop = true});
  CHECK(r3.Reason() == "e-stop: e-stop request");
}

TEST_CASE("auv supervisor: non-finite command, invalid samples and deadline overruns") {
  Rig r;
  r.Run({.v = kNaN});
  CHECK(r.d.mode == Mode::kSafeStop);
  CHECK(r.Reason() == "safe-stop: non-finite command: v = nan");
  CHECK(std::isfinite(r.v()));

  Rig s;
  s.Run({.v = 1.0, .invalid = 0, .invalid_value = 9.0});  // surge_mps = 9
  CHECK(s.d.mode == Mode::kDegraded);
  CHECK(s.Reason() == "degraded: invalid sample: surge_mps = 9 (1 in a row)");
  s.Run({.v = 1.0, .invalid = 1, .invalid_value = HUGE_VAL}, 2);  // sonar_5_m = inf
  CHECK(s.d.mode == Mode::kSafeStop);
  CHECK(s.Reason() == "safe-stop: invalid sample: sonar_5_m = inf (3 in a row)");

  Rig o;
  o.Run({.v = 1.0, .misses = 2});
  CHECK(o.Reason() == "degraded: deadline overrun: 2 consecutive misses >= 2");
  o.Run({.v = 1.0, .misses = 5});
  CHECK(o.Reason() == "safe-stop: deadline overrun: 5 consecutive misses >= 5");
  CHECK(o.s.counts[Cause::kDeadlineOverrun] == 2);
}

TEST_CASE("auv supervisor: a failed inference holds the previous command and stops, naming the status") {
  Rig r;
  r.Run({.v = 1.0, .w = 0.2}, 20);
  const double cmd[2] = {1.0, 0.2};
  const StreamState stream{true, 0, -1, 0};
  const TransportHealth link;
  SupervisorInput x;
  x.command = cmd;
  x.streams = {&stream, 1};
  x.transports = {&link, 1};
  x.inference_failed = true;
  x.inference_status = "non-finite observation";
  r.d = Supervise(r.m, x, 20, r.s, r.out);
  CHECK(r.d.mode == Mode::kSafeStop);
  CHECK(r.Reason() == "safe-stop: inference failed: non-finite observation");
  CHECK(r.v() == doctest::Approx(0.7));  // the stop ramp from the held 1.0
}

TEST_CASE("auv supervisor: the mode comes back down only by a reset while disarmed") {
  Rig r;
  r.Run({.v = 1.0, .estop = true});
  CHECK(r.s.mode == Mode::kEStop);
  r.Run({.v = 1.0}, 10);
  CHECK(r.s.mode == Mode::kEStop);
  CHECK_FALSE(Reset(r.s, /*armed=*/true));
  CHECK(r.s.mode == Mode::kEStop);
  CHECK(Reset(r.s, /*armed=*/false));
  CHECK(r.s.mode == Mode::kNominal);
  r.Run({.v = 1.0});
  CHECK(r.v() == doctest::Approx(0.1));
}

TEST_CASE("auv supervisor: random hostile inputs keep the command finite and within limits - no allocation") {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-10, 10);
  const double specials[] = {kNaN, std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                             1e308, -1e308};
  auto value = [&] { return rng() % 10 == 0 ? specials[rng() % 5] : u(rng); };
  Rig r;
  const SupervisorModel& m = r.m;
  std::uint64_t rises = 0;
  pbppo::AllocationScope scope;
  for (int k = 0; k < 100000; ++k) {
    if (k % 5000 == 0) Reset(r.s, false);
    In in{.v = value(), .w = value()};
    if (rng() % 50 == 0) {
      in.invalid = 0;
      in.invalid_value = value();
    }
    in.sample = rng() % 20 != 0;
    in.age = static_cast<std::uint32_t>(rng() % 30 == 0 ? rng() % 40 : 0);
    in.misses = static_cast<std::uint32_t>(rng() % 100 == 0 ? rng() % 8 : 0);
    const double v_prev = r.s.previous[0], w_prev = r.s.previous[1];
    const Mode before = r.s.mode;
    r.Run(in);
    REQUIRE(std::isfinite(r.v()));
    REQUIRE(std::isfinite(r.w()));
    REQUIRE(r.v() >= m.commands[0].min);
    REQUIRE(r.v() <= m.commands[0].max);
    REQUIRE(std::abs(r.w()) <= m.commands[1].max);
    if (r.d.mode <= Mode::kDegraded) {
      REQUIRE(std::abs(r.v() - v_prev) <= m.commands[0].rate + 1e-12);
      REQUIRE(std::abs(r.w() - w_prev) <= m.commands[1].rate + 1e-12);
    }
    REQUIRE(r.d.mode >= before);
    rises += r.d.transition;
  }
  CHECK(scope.count() == 0);
  CHECK(rises > 20);
}
