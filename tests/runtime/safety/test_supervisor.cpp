// The safety supervisor as a pure function: each check, latching, the cause reported, counters,
// and a randomised property (limited commands always within limits, modes never fall).
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/safety/supervisor.hpp"

using namespace pbppo::safety;

namespace {

// Two joints (command q, tau; feedback q) on two buses.
SupervisorModel Model() {
  SupervisorModel m;
  m.channels = 2;
  m.command_fields = 2;
  m.feedback_fields = 1;
  m.transports = 2;
  m.command_min = {-1.0, -10.0, -2.0, -20.0};
  m.command_max = {1.0, 10.0, 2.0, 20.0};
  m.feedback_min = {-1.2, -2.2};
  m.feedback_max = {1.2, 2.2};
  m.channel_names = {"HIP", "KNEE"};
  m.command_field_names = {"q_rad", "tau_nm"};
  m.feedback_field_names = {"q_rad"};
  m.transport_names = {"vcan0", "vcan1"};
  return m;
}

struct Tick {
  std::vector<double> command{0.1, 1.0, 0.2, 2.0};
  std::vector<double> feedback{0.1, 0.2};
  std::vector<std::uint32_t> age{0, 0};
  std::vector<TransportHealth> transports{{}, {}};
  bool estop = false;
  SupervisorInput In() const { return {command, feedback, age, transports, estop}; }
};

}  // namespace

TEST_CASE("supervisor: model validation names the field") {
  auto m = Model();
  CHECK(ValidateSupervisorModel(m).ok());
  m.command_max[3] = -30;
  CHECK(ValidateSupervisorModel(m).error().message ==
        "supervisor model: channel 'KNEE' command field 'tau_nm': min -20.000000 is not below max -30.000000");
  m = Model();
  m.stale_safe_stop_ticks = 1;
  CHECK(ValidateSupervisorModel(m).error().message ==
        "supervisor model: stale thresholds 2 (degraded), 1 (safe-stop), 500 (e-stop) must satisfy 0 < degraded <= "
        "safe-stop < e-stop");
  m = Model();
  m.command_min.pop_back();
  CHECK_FALSE(ValidateSupervisorModel(m).ok());
}

TEST_CASE("supervisor: each check - the mode it asks for - the cause it names") {
  const auto m = Model();
  Tick t;
  Decision d = Supervise(m, t.In(), Mode::kNominal);
  CHECK(d.mode == Mode::kNominal);
  CHECK(d.fault == Fault::kNone);
  CHECK_FALSE(d.transition);

  t = Tick{};
  t.command[3] = 25.0;  // KNEE tau beyond 20
  d = Supervise(m, t.In(), Mode::kNominal);
  CHECK(d.mode == Mode::kDegraded);
  CHECK(d.fault == Fault::kCommandLimit);
  CHECK(d.channel == 1);
  CHECK(d.field == 1);
  CHECK(d.transition);
  CHECK(Describe(m, d) == "degraded: command outside limits, channel 'KNEE', command tau_nm");

  t = Tick{};
  t.age[1] = 2;
  d = Supervise(m, t.In(), Mode::kNominal);
  CHECK(d.mode == Mode::kDegraded);
  CHECK(d.fault == Fault::kStaleFeedback);
  CHECK(d.channel == 1);
  t.age[1] = 3;
  d = Supervise(m, t.In(), Mode::kNominal);
  CHECK(d.mode == Mode::kSafeStop);
  CHECK(Describe(m, d) == "safe-stop: stale feedback, channel 'KNEE'");
  t.age[1] = 500;
  CHECK(Supervise(m, t.In(), Mode::kSafeStop).mode == Mode::kEStop);

  t = Tick{};
  t.command[0] = std::numeric_limits<double>::quiet_NaN();
  d = Supervise(m, t.In(), Mode::kNominal);
  CHECK(d.mode == Mode::kSafeStop);
  CHECK(d.fault == Fault::kNonFiniteCommand);
  CHECK(d.channel == 0);
  CHECK(d.field == 0);

  t = Tick{};
  t.feedback[1] = std::numeric_limits<double>::infinity();
  d = Supervise(m, t.In(), Mode::kNominal);
  CHECK(d.fault == Fault::kNonFiniteFeedback);
  CHECK(d.mode == Mode::kSafeStop);
  t.feedback[1] = 2.3;
  d = Supervise(m, t.In(), Mode::kNominal);
  CHECK(d.fault == Fault::kFeedbackLimit);
  CHECK(d.mode == Mode::kSafeStop);

  t = Tick{};
  t.transports[1].fault = true;  // bus-off
  d = Supervise(m, t.In(), Mode::kNominal);
  CHECK(d.mode == Mode::kSafeStop);
  CHECK(Describe(m, d) == "safe-stop: transport fault, transport 'vcan1'");
  t = Tick{};
  t.transports[0].degraded = true;
  CHECK(Supervise(m, t.In(), Mode::kNominal).mode == Mode::kDegraded);

  t = Tick{};
  t.estop = true;
  d = Supervise(m, t.In(), Mode::kNominal);
  CHECK(d.mode == Mode::kEStop);
  CHECK(d.fault == Fault::kEStopRequest);

  // The most severe finding wins; among equals the first channel.
  t = Tick{};
  t.age = {3, 3};
  t.command[3] = 99;
  d = Supervise(m, t.In(), Mode::kNominal);
  CHECK(d.mode == Mode::kSafeStop);
  CHECK(d.fault == Fault::kStaleFeedback);
  CHECK(d.channel == 0);

  // Inputs of the wrong size never pass as nominal.
  t = Tick{};
  t.age.pop_back();
  CHECK(Supervise(m, t.In(), Mode::kNominal).mode == Mode::kSafeStop);
}

TEST_CASE("supervisor: modes latch - counters - the decision that entered each mode - no allocation") {
  const auto m = Model();
  SupervisorData data;
  Tick t;
  pbppo::AllocationScope scope;
  for (std::uint64_t k = 0; k < 10; ++k) Step(m, t.In(), k, data);
  t.age[0] = 2;
  Step(m, t.In(), 10, data);
  t.age[0] = 0;  // the motor answers again: still degraded (latched)
  for (std::uint64_t k = 11; k < 20; ++k) CHECK(Step(m, t.In(), k, data).mode == Mode::kDegraded);
  t.transports[0].fault = true;
  Step(m, t.In(), 20, data);
  t.transports[0].fault = false;
  Step(m, t.In(), 21, data);
  CHECK(scope.count() == 0);
  CHECK(data.mode == Mode::kSafeStop);
  CHECK(data.decisions == 22);
  CHECK(data.transitions == 2);
  CHECK(data.ticks_in_mode[0] == 10);
  CHECK(data.ticks_in_mode[1] == 10);
  CHECK(data.ticks_in_mode[2] == 2);
  CHECK(data.entered_tick[1] == 10);
  CHECK(data.entered[1].fault == Fault::kStaleFeedback);
  CHECK(data.entered[1].channel == 0);
  CHECK(data.entered_tick[2] == 20);
  CHECK(data.entered[2].transport == 0);
  CHECK(data.findings[static_cast<int>(Fault::kNone)] == 20);
}

TEST_CASE("supervisor property: limited commands are within limits - modes never fall (random inputs)") {
  const auto m = Model();
  std::mt19937_64 rng(1234);
  std::uniform_real_distribution<double> u(-50, 50);
  std::uniform_int_distribution<int> pick(0, 19);
  const double specials[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(), 1e308, -0.0};
  Mode mode = Mode::kNominal;
  for (int i = 0; i < 20000; ++i) {
    Tick t;
    for (double& v : t.command) v = pick(rng) == 0 ? specials[static_cast<std::size_t>(pick(rng)) % 5] : u(rng) / 10;
    for (double& v : t.feedback) v = pick(rng) == 0 ? specials[static_cast<std::size_t>(pick(rng)) % 5] : u(rng) / 30;
    for (auto& a : t.age) a = static_cast<std::uint32_t>(pick(rng) < 18 ? 0 : pick(rng));
    const Decision d = Supervise(m, t.In(), i % 100 == 0 ? Mode::kNominal : mode);
    if (i % 100 != 0) CHECK(d.mode >= mode);
    mode = i % 100 == 0 ? Mode::kNominal : d.mode;
    LimitCommand(m, t.command);
    for (std::size_t k = 0; k < t.command.size(); ++k) {
      REQUIRE(std::isfinite(t.command[k]));
      REQUIRE(t.command[k] >= m.command_min[k]);
      REQUIRE(t.command[k] <= m.command_max[k]);
    }
    // A limited, finite command never raises a command finding.
    t.feedback = {0, 0};
    t.age = {0, 0};
    CHECK(Supervise(m, t.In(), Mode::kNominal).fault == Fault::kNone);
  }
}
