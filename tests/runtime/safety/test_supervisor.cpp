// The safety supervisor as a pure function, on a robot of two joints (commands q, tau; a position
// reply each) on two buses: each check, latching, the cause reported, counters by cause, and a
// randomised property (the command sent is always within its limits, modes never fall).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/safety/supervisor.hpp"

using namespace pbppo::safety;

namespace {

// Two joints (command q, tau; reply q) on two buses, like the quadruped's motors: a command
// outside its limits degrades, safe-stop holds the measured position with no torque, a reply is
// stale after 1 tick (degraded), 2 (safe-stop), lost after 499 (e-stop: its 500th silent tick).
SupervisorModel Model() {
  SupervisorModel m;
  m.commands = {
      {"q_HIP", -1.0, 1.0, -1.0, 1.0, HUGE_VAL, StopKind::kHoldInput, 0, 0, 0},
      {"tau_HIP", -10.0, 10.0, -10.0, 10.0, HUGE_VAL, StopKind::kValue, 0, 0, -1},
      {"q_KNEE", -2.0, 2.0, -2.0, 2.0, HUGE_VAL, StopKind::kHoldInput, 0, 0, 1},
      {"tau_KNEE", -20.0, 20.0, -20.0, 20.0, HUGE_VAL, StopKind::kValue, 0, 0, -1},
  };
  m.streams = {{"HIP", 1, 2, 499, 1}, {"KNEE", 1, 2, 499, 1}};
  m.input_names = {"q_HIP", "q_KNEE"};
  m.transport_names = {"can/front", "can/hind"};
  m.command_limit_degrades = true;
  return m;
}

struct Tick {
  std::vector<double> command{0.1, 1.0, 0.2, 2.0};
  std::vector<double> inputs{0.1, 0.2};
  std::vector<StreamState> streams{{true, 0, -1, 0}, {true, 0, -1, 0}};
  std::vector<TransportHealth> transports{{}, {}};
  bool estop = false;
  SupervisorInput In() const {
    SupervisorInput in;
    in.command = command;
    in.inputs = inputs;
    in.streams = streams;
    in.transports = transports;
    in.estop_request = estop;
    return in;
  }
  // The sample check's finding on an input outside [-1.2, 1.2] / [-2.2, 2.2] or non-finite (for
  // the streams there are: a test may remove one).
  void Check() {
    const double lim[] = {1.2, 2.2};
    for (std::size_t s = 0; s < std::min<std::size_t>(2, std::min(streams.size(), inputs.size())); ++s) {
      streams[s].invalid_input = -1;
      if (!(std::abs(inputs[s]) <= lim[s])) {
        streams[s].invalid_input = static_cast<std::int32_t>(s);
        streams[s].invalid_value = inputs[s];
      }
    }
  }
};

// One decision from `previous` (a fresh state at that mode).
Decision Once(const SupervisorModel& m, Tick t, Mode previous = Mode::kNominal) {
  t.Check();
  SupervisorState s = MakeSupervisorState(m);
  s.mode = previous;
  std::vector<double> out(m.commands.size());
  return Supervise(m, t.In(), 0, s, out);
}

}  // namespace

TEST_CASE("supervisor: model validation names the field") {
  auto m = Model();
  CHECK(ValidateSupervisorModel(m).ok());
  m.commands[3].max = -30;
  CHECK(ValidateSupervisorModel(m).error().message == "supervisor: command 'tau_KNEE': min -20 is not below max -30");
  m = Model();
  m.streams[1].stale_safe_stop_ticks = 1;
  CHECK(ValidateSupervisorModel(m).error().message ==
        "supervisor: stream 'KNEE': stale limits 1 (degraded), 1 (safe-stop), 499 (lost) must increase");
  m = Model();
  m.commands[0].hold_input = 7;
  CHECK(ValidateSupervisorModel(m).error().message == "supervisor: command 'q_HIP': hold_input 7 is not an input");
}

TEST_CASE("supervisor: each check - the mode it asks for - the cause it names") {
  const auto m = Model();
  Tick t;
  Decision d = Once(m, t);
  CHECK(d.mode == Mode::kNominal);
  CHECK_FALSE(d.any);
  CHECK_FALSE(d.transition);

  t = Tick{};
  t.command[3] = 25.0;  // KNEE tau beyond 20
  d = Once(m, t);
  CHECK(d.mode == Mode::kDegraded);
  CHECK(d.cause == Cause::kCommandLimit);
  CHECK(d.subject == 3);
  CHECK(d.transition);
  CHECK(Describe(m, d) == "degraded: command limit: tau_KNEE = 25 (limit 20)");

  t = Tick{};
  t.streams[1].age_ticks = 2;
  d = Once(m, t);
  CHECK(d.mode == Mode::kDegraded);
  CHECK(d.cause == Cause::kStaleSample);
  CHECK(d.subject == 1);
  t.streams[1].age_ticks = 3;
  d = Once(m, t);
  CHECK(d.mode == Mode::kSafeStop);
  CHECK(Describe(m, d) == "safe-stop: stale sample: KNEE: age 3 ticks > 2");
  t.streams[1].age_ticks = 500;
  CHECK(Once(m, t, Mode::kSafeStop).mode == Mode::kEStop);

  t = Tick{};
  t.command[0] = std::numeric_limits<double>::quiet_NaN();
  d = Once(m, t);
  CHECK(d.mode == Mode::kSafeStop);
  CHECK(d.cause == Cause::kNonFiniteCommand);
  CHECK(d.subject == 0);

  t = Tick{};
  t.inputs[1] = std::numeric_limits<double>::infinity();
  d = Once(m, t);
  CHECK(d.cause == Cause::kInvalidSample);
  CHECK(d.input == 1);
  CHECK(d.mode == Mode::kSafeStop);
  t.inputs[1] = 2.3;
  d = Once(m, t);
  CHECK(d.cause == Cause::kInvalidSample);
  CHECK(d.mode == Mode::kSafeStop);
  CHECK(Describe(m, d) == "safe-stop: invalid sample: q_KNEE = 2.3 (1 in a row)");

  t = Tick{};
  t.transports[1].fault = true;  // bus-off
  d = Once(m, t);
  CHECK(d.mode == Mode::kSafeStop);
  CHECK(Describe(m, d) == "safe-stop: transport fault: 'can/hind'");
  t = Tick{};
  t.transports[0].degraded = true;
  CHECK(Once(m, t).mode == Mode::kDegraded);

  t = Tick{};
  t.estop = true;
  d = Once(m, t);
  CHECK(d.mode == Mode::kEStop);
  CHECK(d.cause == Cause::kEStopRequest);

  // The most severe finding wins; among equals the first stream.
  t = Tick{};
  t.streams[0].age_ticks = t.streams[1].age_ticks = 3;
  t.command[3] = 99;
  d = Once(m, t);
  CHECK(d.mode == Mode::kSafeStop);
  CHECK(d.cause == Cause::kStaleSample);
  CHECK(d.subject == 0);

  // Inputs of the wrong size never pass as nominal.
  t = Tick{};
  t.streams.pop_back();
  CHECK(Once(m, t).mode == Mode::kSafeStop);
}

TEST_CASE("supervisor: safe-stop holds the measured position with the stop values - e-stop zero, or damping") {
  const auto m = Model();
  SupervisorState s = MakeSupervisorState(m);
  std::vector<double> out(4);
  Tick t;
  t.inputs = {0.7, -3.0};  // the knee's measurement is beyond its command limits: held at the limit
  t.streams[0].age_ticks = 3;
  Supervise(m, t.In(), 0, s, out);
  REQUIRE(s.mode == Mode::kSafeStop);
  CHECK(out == std::vector<double>{0.7, 0.0, -2.0, 0.0});
  t.estop = true;
  Supervise(m, t.In(), 1, s, out);
  CHECK(out == std::vector<double>{0.0, 0.0, 0.0, 0.0});
  // An e-stop that damps (robot.yaml supervisor.estop: damping) sends safe-stop's commands, latched.
  auto damping = Model();
  damping.estop_damps = true;
  SupervisorState e = MakeSupervisorState(damping);
  Tick u;
  u.inputs = {0.7, -3.0};
  u.estop = true;
  Supervise(damping, u.In(), 0, e, out);
  REQUIRE(e.mode == Mode::kEStop);
  CHECK(out == std::vector<double>{0.7, 0.0, -2.0, 0.0});
  u.estop = false;
  u.inputs = {0.2, 0.1};
  Supervise(damping, u.In(), 1, e, out);
  CHECK(e.mode == Mode::kEStop);
  CHECK(out == std::vector<double>{0.2, 0.0, 0.1, 0.0});
}

TEST_CASE("supervisor: modes latch - counters by cause - the decision that entered each mode - no allocation") {
  const auto m = Model();
  SupervisorState s = MakeSupervisorState(m);
  std::vector<double> out(4);
  Tick t;
  pbppo::AllocationScope scope;
  for (std::uint64_t k = 0; k < 10; ++k) Supervise(m, t.In(), k, s, out);
  t.streams[0].age_ticks = 2;
  Supervise(m, t.In(), 10, s, out);
  t.streams[0].age_ticks = 0;  // the motor answers again: still degraded (latched)
  for (std::uint64_t k = 11; k < 20; ++k) CHECK(Supervise(m, t.In(), k, s, out).mode == Mode::kDegraded);
  t.transports[0].fault = true;
  Supervise(m, t.In(), 20, s, out);
  t.transports[0].fault = false;
  Supervise(m, t.In(), 21, s, out);
  CHECK(scope.count() == 0);
  CHECK(s.mode == Mode::kSafeStop);
  CHECK(s.ticks == 22);
  CHECK(s.transitions == 2);
  CHECK(s.ticks_in_mode[0] == 10);
  CHECK(s.ticks_in_mode[1] == 10);
  CHECK(s.ticks_in_mode[2] == 2);
  CHECK(s.entered_tick[1] == 10);
  CHECK(s.entered[1].cause == Cause::kStaleSample);
  CHECK(s.entered[1].subject == 0);
  CHECK(s.entered_tick[2] == 20);
  CHECK(s.entered[2].cause == Cause::kTransportFault);
  CHECK(s.entered[2].subject == 0);
  CHECK(s.counts[Cause::kStaleSample] == 1);
  CHECK(s.counts[Cause::kTransportFault] == 1);
}

TEST_CASE("supervisor property: the command sent is within limits - modes never fall (random inputs)") {
  const auto m = Model();
  std::mt19937_64 rng(1234);
  std::uniform_real_distribution<double> u(-50, 50);
  std::uniform_int_distribution<int> pick(0, 19);
  const double specials[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(), 1e308, -0.0};
  SupervisorState s = MakeSupervisorState(m);
  std::vector<double> out(4);
  for (int i = 0; i < 20000; ++i) {
    if (i % 100 == 0) Reset(s, false);
    const Mode before = s.mode;
    Tick t;
    for (double& v : t.command) v = pick(rng) == 0 ? specials[static_cast<std::size_t>(pick(rng)) % 5] : u(rng) / 10;
    for (double& v : t.inputs) v = pick(rng) == 0 ? specials[static_cast<std::size_t>(pick(rng)) % 5] : u(rng) / 30;
    for (auto& st : t.streams) st.age_ticks = static_cast<std::uint32_t>(pick(rng) < 18 ? 0 : pick(rng));
    t.Check();
    const Decision d = Supervise(m, t.In(), static_cast<std::uint64_t>(i), s, out);
    CHECK(d.mode >= before);
    for (std::size_t k = 0; k < out.size(); ++k) {
      REQUIRE(std::isfinite(out[k]));
      REQUIRE(out[k] >= m.commands[k].min);
      REQUIRE(out[k] <= m.commands[k].max);
    }
    // A command within its limits, with fresh valid inputs, never raises a finding.
    Tick ok;
    ok.command = out;
    CHECK_FALSE(Once(m, ok).any);
  }
}
