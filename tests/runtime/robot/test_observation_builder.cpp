// The observation builder and action mapper: scale, offset, clip, history, the first-tick fill,
// unknown signals refused naming the element, non-finite actions flagged; no allocation per tick.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/robot/observation_builder.hpp"
#include "runtime/robot/signals.hpp"
#include "tests/support/robot_models.hpp"

using namespace pbppo::robot;

namespace {
const char* kLayout = R"(
robot: testbot
observations:
  - {name: a, signal: alpha, scale: 0.5, offset: 1.0, clip: 2}
  - {name: b, signal: beta, history: 3}
  - {name: a2, signal: alpha, scale: -1.0, clip: 0.25}
actions:
  - {name: v, command: v, scale: 0.75, offset: 0.75, low: 0, high: 1.5}
  - {name: w, command: w, scale: 0.5, low: -0.5, high: 0.5}
)";

IoLayout Layout() {
  auto l = ParseIoLayout(kLayout, "t.yaml");
  REQUIRE_MESSAGE(l.ok(), l.error().message);
  return *l;
}
}  // namespace

TEST_CASE("observation builder: scale, offset, clip and history through the layout") {
  auto b = ObservationBuilder::Create(Layout(), {"beta", "gamma", "alpha"});
  REQUIRE_MESSAGE(b.ok(), b.error().message);
  CHECK(b->observation_size() == 5);
  CHECK(b->signal_of_element() == std::vector<std::uint32_t>{2, 0, 2});
  float obs[5];
  double g[3] = {7.0, 0.0, 3.0};  // beta, gamma, alpha
  b->Build(g, true, obs);
  CHECK(obs[0] == 1.0f);  // (3 - 1) * 0.5
  CHECK(obs[1] == 7.0f);
  CHECK(obs[2] == 7.0f);  // history filled with the first value
  CHECK(obs[3] == 7.0f);
  CHECK(obs[4] == -0.25f);  // -3 clipped
  g[0] = 8.0;
  g[2] = 100.0;
  b->Build(g, false, obs);
  CHECK(obs[0] == 2.0f);  // clipped at 2
  CHECK(obs[1] == 8.0f);
  CHECK(obs[2] == 7.0f);
  CHECK(obs[3] == 7.0f);
  g[0] = 9.0;
  b->Build(g, false, obs);
  CHECK(obs[1] == 9.0f);
  CHECK(obs[2] == 8.0f);
  CHECK(obs[3] == 7.0f);
  // `first` again (re-arming) refills the history.
  b->Build(g, true, obs);
  CHECK(obs[2] == 9.0f);
  CHECK(obs[3] == 9.0f);
}

TEST_CASE("observation builder: an unknown signal is refused naming the element and the signal") {
  auto b = ObservationBuilder::Create(Layout(), {"alpha", "gamma"});
  REQUIRE_FALSE(b.ok());
  CHECK(b.error().message.find("observations[1] 'b': signal 'beta' is not provided (known: alpha, gamma)") !=
        std::string::npos);
}

TEST_CASE("action mapper: scale, offset, limits - non-finite elements flagged and taken as 0") {
  const ActionMapper m = ActionMapper::Create(Layout());
  double cmd[2];
  float a[2] = {0.5f, -3.0f};
  CHECK(m.Map(a, cmd) == 0u);
  CHECK(cmd[0] == 1.125);
  CHECK(cmd[1] == -0.5);
  a[0] = std::numeric_limits<float>::quiet_NaN();
  a[1] = std::numeric_limits<float>::infinity();
  CHECK(m.Map(a, cmd) == 3u);
  CHECK(cmd[0] == 0.75);
  CHECK(cmd[1] == 0.0);
}

namespace {
// The AUV's signals for a layout and its fields, set by name.
struct AuvSignals {
  const RobotModel& m = pbppo::test::AuvRobot();
  SignalProgram program;
  std::vector<double> fields = std::vector<double>(m.fields.size(), 0.0), g;

  std::optional<ObservationBuilder> builder;

  // The signals and the observation builder of an AUV layout with these observation lines and
  // one action.
  explicit AuvSignals(const std::string& observations) {
    auto l = ParseIoLayout(
        "robot: auv\nobservations:\n" + observations + "actions:\n  - {name: v, command: surge_speed}\n", "auv.yaml");
    REQUIRE_MESSAGE(l.ok(), l.error().message);
    auto p = SignalProgram::ForLayout(m, *l);
    REQUIRE_MESSAGE(p.ok(), p.error().message);
    program = std::move(*p);
    g.assign(program.size(), 0.0);
    auto b = ObservationBuilder::Create(*l, program.names());
    REQUIRE_MESSAGE(b.ok(), b.error().message);
    builder.emplace(std::move(*b));
  }
  void Set(const std::string& field, double v) { fields[static_cast<std::size_t>(m.FieldIndex(field))] = v; }
  const double* Compute() {
    program.Compute(fields, {}, g.data());
    return g.data();
  }
};
}  // namespace

TEST_CASE("observation builder and the AUV's signals allocate nothing per tick") {
  AuvSignals sig(R"(  - {name: s3, signal: sonar_3, scale: 0.1, history: 4}
  - {name: d, signal: depth_error}
  - {name: y, signal: yaw}
)");
  ObservationBuilder& b = *sig.builder;
  sig.Set("depth_m", 5.5);  // the mission depth (robot.yaml's parameters.depth_m) is 5
  sig.Set("yaw_rad", 3.5);  // wrapped by the yaw signal
  const std::size_t sonar3 = static_cast<std::size_t>(sig.m.FieldIndex("sonar_3_m"));
  float obs[6];
  pbppo::AllocationScope scope;
  for (int k = 0; k < 1000; ++k) {
    sig.fields[sonar3] = static_cast<double>(k);
    b.Build(sig.Compute(), k == 0, obs);
  }
  CHECK(scope.count() == 0);
  CHECK(obs[0] == doctest::Approx(99.9));
  CHECK(obs[3] == doctest::Approx(99.6));
  CHECK(obs[4] == 0.5f);
  CHECK(obs[5] == doctest::Approx(3.5 - 2 * 3.14159265358979323846));
}

TEST_CASE("AUV signals: nearest_echo is the shortest sonar range, +inf (the element's clip) without an echo") {
  AuvSignals sig("  - {name: e, signal: nearest_echo, scale: 0.2, clip: 1.0}\n");
  ObservationBuilder& b = *sig.builder;
  for (std::uint32_t i = 0; i < 16; ++i) sig.Set(ExpandIndex("sonar_{i}_m", i), 15.0);
  sig.Set("sonar_1_m", 3.5);
  sig.Set("sonar_2_m", 2.5);
  sig.Set("sonar_9_m", 9.0);
  float obs[1];
  CHECK(sig.Compute()[0] == 2.5);
  b.Build(sig.g.data(), true, obs);
  CHECK(obs[0] == doctest::Approx(0.5));
  sig.Set("sonar_15_m", 0.25);
  b.Build(sig.Compute(), false, obs);
  CHECK(obs[0] == doctest::Approx(0.05));
  for (std::uint32_t i = 0; i < 16; ++i) sig.Set(ExpandIndex("sonar_{i}_m", i), HUGE_VAL);
  CHECK(std::isinf(sig.Compute()[0]));
  b.Build(sig.g.data(), false, obs);
  CHECK(obs[0] == 1.0f);
}
