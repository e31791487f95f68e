#include <doctest/doctest.h>

#include "runtime/robot/io_layout.hpp"
#include "tests/support/refusal.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo::robot;

namespace {
const char* kGood = R"(
robot: testbot
observations:
  - {name: yaw, signal: yaw_rad, unit: rad, scale: 0.5, clip: 2}
  - {name: range, unit: m, history: 3, offset: 1.5}
actions:
  - {name: v, command: surge_mps, unit: m/s, scale: 0.5, offset: 0.5, low: 0, high: 1}
)";

std::string ErrorOf(const std::string& text) {
  return pbppo::test::RefusalOf(ParseIoLayout(text, "t.yaml"));
}
}  // namespace

TEST_CASE("a layout parses with defaults, history expanded") {
  auto l = ParseIoLayout(kGood, "t.yaml");
  REQUIRE_MESSAGE(l.ok(), l.error().message);
  CHECK(l->robot == "testbot");
  CHECK(l->observation_size() == 4);
  CHECK(l->action_size() == 1);
  CHECK(l->ObservationNames() == std::vector<std::string>{"yaw", "range", "range@-1", "range@-2"});
  CHECK(l->observations[1].signal == "range");
  CHECK(l->observations[1].offset == 1.5);
  CHECK(l->actions[0].high == 1.0);
}

TEST_CASE("the hash covers every field but not formatting") {
  auto a = ParseIoLayout(kGood, "a");
  std::string reformatted = std::string("# comment\n") + kGood;
  auto b = ParseIoLayout(reformatted, "b");
  REQUIRE(a.ok());
  REQUIRE(b.ok());
  CHECK(a->Hash() == b->Hash());
  IoLayout c = *a;
  c.observations[0].scale = 0.25;
  CHECK(c.Hash() != a->Hash());
  c = *a;
  c.actions[0].high = 2;
  CHECK(c.Hash() != a->Hash());
  c = *a;
  c.observations[1].history = 2;
  CHECK(c.Hash() != a->Hash());
}

TEST_CASE("bad layouts are refused naming the file, element and field") {
  CHECK(ErrorOf("robot: x\nobservations: []\nactions: [{name: a}]") ==
        "t.yaml: observations: expected a non-empty list");
  CHECK(ErrorOf("robot: x\nobservations: [{name: a, scale: fast}]\nactions: [{name: b}]") ==
        "t.yaml: observations[0].scale: 'fast' is not a number");
  CHECK(ErrorOf("robot: x\nobservations: [{name: a, clip: -1}]\nactions: [{name: b}]") ==
        "t.yaml: observations[0].clip: -1 is not positive");
  CHECK(ErrorOf("robot: x\nobservations: [{name: a, history: 1.5}]\nactions: [{name: b}]") ==
        "t.yaml: observations[0].history: 1.5 is not an integer in 1..64");
  CHECK(ErrorOf("robot: x\nobservations: [{name: a}, {name: a}]\nactions: [{name: b}]") ==
        "t.yaml: observations[1].name: 'a' appears twice");
  CHECK(ErrorOf("robot: x\nobservations: [{name: a, gain: 2}]\nactions: [{name: b}]") ==
        "t.yaml: observations[0].gain: unknown field");
  CHECK(ErrorOf("robot: x\nobservations: [{name: a}]\nactions: [{name: b, low: 1, high: 0}]") ==
        "t.yaml: actions[0]: low 1 is above high 0");
  CHECK(ErrorOf("robot: x\nobservations: [{name: a}]\nactions: [{name: b, high: .nan}]") ==
        "t.yaml: actions[0].high: '.nan' is not a number");
  CHECK(ErrorOf("robot: [x\n").rfind("t.yaml: YAML error at line", 0) == 0);
  // A key no reader could take as a name, refused where every document is read.
  CHECK(ErrorOf("robot: x\n? [a, b]\n: 1\nobservations: [{name: a}]\nactions: [{name: b}]") ==
        "t.yaml: YAML error at line 2: a mapping key that is not a name (a list, a mapping or empty)");
  CHECK(ErrorOf("robot: x\nobservations: [{name: a, {b: 1}: 2}]\nactions: [{name: b}]") ==
        "t.yaml: YAML error at line 2: a mapping key that is not a name (a list, a mapping or empty)");
  // A key given twice: a reader would see the first only.
  CHECK(ErrorOf("robot: x\nobservations: [{name: a}]\nactions: [{name: b}]\nrobot: y\n") ==
        "t.yaml: YAML error at line 4: key 'robot' given twice in one mapping (first at line 1)");
  CHECK(ErrorOf("robot: x\nobservations: [{name: a, clip: 1, clip: 2}]\nactions: [{name: b}]") ==
        "t.yaml: YAML error at line 2: key 'clip' given twice in one mapping (first at line 2)");
  CHECK(ErrorOf("robot: x\nobservations: " + std::string(300, '[') + std::string(300, ']') + "\n") ==
        "t.yaml: YAML error at line 2: nested more than 256 levels deep");
  CHECK(ErrorOf("- 1\n- 2\n") == "t.yaml: top level: expected a mapping with robot, observations, actions");
  auto missing = LoadIoLayout("/nonexistent/layout.yaml");
  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().message == "/nonexistent/layout.yaml: cannot open");
}

TEST_CASE("a policy must match the layout it runs on") {
  auto l = ParseIoLayout(kGood, "t.yaml");
  REQUIRE(l.ok());
  pbppo::policy::PolicySpec spec = pbppo::policy::MakeRandomSpec({4, 8, 1}, pbppo::policy::Activation::kTanh, 1);
  ApplyLayoutToSpec(*l, spec);
  CHECK(spec.action_offset[0] == 0.5f);
  CHECK(CheckPolicyMatchesLayout(spec, *l).ok());

  IoLayout other = *l;
  other.observations[0].name = "heading";
  auto st = CheckPolicyMatchesLayout(spec, other);
  REQUIRE_FALSE(st.ok());
  CHECK(st.error().message ==
        "policy does not fit robot layout 'testbot': observation 0 is 'yaw' in the policy, 'heading' in the layout");
  other = *l;
  other.observations[0].scale = 2;
  st = CheckPolicyMatchesLayout(spec, other);
  REQUIRE_FALSE(st.ok());
  CHECK(st.error().message.find("same names, but scales") != std::string::npos);
  other = *l;
  other.actions.push_back(other.actions[0]);
  other.actions[1].name = "w";
  st = CheckPolicyMatchesLayout(spec, other);
  REQUIRE_FALSE(st.ok());
  CHECK(st.error().message ==
        "policy does not fit robot layout 'testbot': the policy gives 1 actions, the layout takes 2");
}

TEST_CASE("the shipped pendulum layout loads") {
  auto l = LoadIoLayout(pbppo::test::SourcePath("models/pendulum/io_layout.yaml"));
  REQUIRE_MESSAGE(l.ok(), l.error().message);
  CHECK(l->observation_size() == 3);
  CHECK(l->action_size() == 1);
}

TEST_CASE(
    "a policy's action limits are held in float inside the layout's - at its limit it sends no command beyond it") {
  // The Go2's calf stops at -0.83776 rad, which rounds to the float -0.8377599716, above it.
  CHECK(static_cast<double>(static_cast<float>(-0.83776)) > -0.83776);
  for (const char* robot : {"go2", "quadruped"}) {
    CAPTURE(robot);
    auto l = LoadIoLayout(pbppo::test::SourcePath(std::string("models/") + robot + "/io_layout.yaml"));
    REQUIRE_MESSAGE(l.ok(), l.error().message);
    pbppo::policy::PolicySpec spec = pbppo::policy::MakeRandomSpec(
        {static_cast<std::uint32_t>(l->observation_size()), 8, static_cast<std::uint32_t>(l->action_size())},
        pbppo::policy::Activation::kTanh, 1);
    ApplyLayoutToSpec(*l, spec);
    for (std::size_t j = 0; j < l->actions.size(); ++j) {
      const double low = l->actions[j].low, high = l->actions[j].high;
      const double lo = spec.action_low[j], hi = spec.action_high[j];
      CHECK(lo >= low);
      CHECK(hi <= high);
      // ... and the nearest such float: the next one out is beyond the limit.
      CHECK(static_cast<double>(std::nextafter(spec.action_low[j], -HUGE_VALF)) < low);
      CHECK(static_cast<double>(std::nextafter(spec.action_high[j], HUGE_VALF)) > high);
    }
  }
  CHECK(pbppo::policy::FloatNotAbove(-0.83776) < static_cast<float>(-0.83776));
  CHECK(pbppo::policy::FloatNotAbove(0.5) == 0.5f);
  CHECK(pbppo::policy::FloatNotBelow(0.3) > static_cast<float>(0.3) - 1e-6f);
  CHECK(static_cast<double>(pbppo::policy::FloatNotBelow(0.3)) >= 0.3);
}
