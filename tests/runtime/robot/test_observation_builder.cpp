// The observation builder and action mapper: scale, offset, clip, history, the first-tick fill,
// unknown signals refused naming the element, non-finite actions flagged; no allocation per tick.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/robot/auv_signals.hpp"
#include "runtime/robot/observation_builder.hpp"

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

TEST_CASE("observation builder and AUV signals allocate nothing per tick") {
  auto l = ParseIoLayout(R"(
robot: auv
observations:
  - {name: s3, signal: sonar_3, scale: 0.1, history: 4}
  - {name: d, signal: depth_error}
  - {name: y, signal: yaw}
actions:
  - {name: v, command: surge_speed}
)",
                         "auv.yaml");
  REQUIRE(l.ok());
  auto b = ObservationBuilder::Create(*l, AuvSignalNames(8));
  REQUIRE_MESSAGE(b.ok(), b.error().message);
  AuvSensorSample s;
  s.sonar_beams = 8;
  s.depth_m = 5.5;
  s.yaw_rad = 3.5;  // wrapped by the yaw signal
  double g[kAuvSignalCapacity];
  float obs[6];
  pbppo::AllocationScope scope;
  for (int k = 0; k < 1000; ++k) {
    s.sonar_m[3] = static_cast<float>(k);
    AuvSignalsFromSample(s, 5.0, g);
    b->Build(g, k == 0, obs);
  }
  CHECK(scope.count() == 0);
  CHECK(obs[0] == doctest::Approx(99.9));
  CHECK(obs[3] == doctest::Approx(99.6));
  CHECK(obs[4] == 0.5f);
  CHECK(obs[5] == doctest::Approx(3.5 - 2 * 3.14159265358979323846));
}

TEST_CASE("AUV signals: nearest_echo is the shortest sonar range, +inf (the element's clip) without a sonar") {
  auto l = ParseIoLayout(R"(
robot: auv
observations:
  - {name: e, signal: nearest_echo, scale: 0.2, clip: 1.0}
actions:
  - {name: v, command: surge_speed}
)",
                         "auv.yaml");
  REQUIRE(l.ok());
  auto b = ObservationBuilder::Create(*l, AuvSignalNames(4));
  REQUIRE_MESSAGE(b.ok(), b.error().message);
  AuvSensorSample s;
  s.sonar_beams = 4;
  s.sonar_m[0] = 15.0f;
  s.sonar_m[1] = 3.5f;
  s.sonar_m[2] = 2.5f;
  s.sonar_m[3] = 9.0f;
  s.sonar_m[4] = 0.5f;  // beyond the sample's beam count: not a range
  double g[kAuvSignalCapacity];
  float obs[1];
  AuvSignalsFromSample(s, 5.0, g);
  CHECK(g[kAuvNearestEcho] == 2.5);
  b->Build(g, true, obs);
  CHECK(obs[0] == doctest::Approx(0.5));
  s.sonar_m[3] = 0.25f;
  AuvSignalsFromSample(s, 5.0, g);
  b->Build(g, false, obs);
  CHECK(obs[0] == doctest::Approx(0.05));
  s.sonar_beams = 0;
  AuvSignalsFromSample(s, 5.0, g);
  CHECK(std::isinf(g[kAuvNearestEcho]));
  b->Build(g, false, obs);
  CHECK(obs[0] == 1.0f);
}
