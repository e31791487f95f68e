#include <doctest/doctest.h>

#include <string>

#include "runtime/robot/can_map.hpp"
#include "tests/support/refusal.hpp"
#include "tests/support/test_paths.hpp"
#include "tests/support/text_edit.hpp"

using pbppo::test::ReplaceOnce;

using namespace pbppo::robot;

namespace {
const char* kGood = R"(
robot: testbot
buses:
  - {name: a, interface: vcan0, fd: true}
  - {name: b, interface: vcan1}
actuators:
  - {name: m, p_min: -12.5, p_max: 12.5, v_min: -50, v_max: 50, kp_min: 0, kp_max: 500, kd_min: 0, kd_max: 5, t_min: -25, t_max: 25}
motors:
  - {joint: J1, bus: a, id: 1, reply_id: 0x101, actuator: m}
  - {joint: J2, bus: b, id: 1, reply_id: 0x101, actuator: m}
imus:
  - {name: imu, bus: a, format: fd, id: 0x80}
)";

std::string ErrorOf(const std::string& text) {
  return pbppo::test::RefusalOf(ParseCanMap(text, "t.yaml"));
}
}  // namespace

TEST_CASE("the quadruped's CAN map loads: 12 motors on two buses - one IMU") {
  auto m = LoadCanMap(pbppo::test::SourcePath("models/quadruped/can_map.yaml"));
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  CHECK(m->robot == "quadruped");
  REQUIRE(m->buses.size() == 2);
  REQUIRE(m->motors.size() == 12);
  REQUIRE(m->imus.size() == 1);
  int per_bus[2] = {0, 0};
  for (const auto& mo : m->motors) ++per_bus[mo.bus];
  CHECK(per_bus[0] == 6);
  CHECK(per_bus[1] == 6);
  CHECK(m->motors[0].joint == "LF_HAA");
  CHECK(m->motors[0].reply_id == 0x101);
  CHECK(m->range_of(m->motors[0]).kp_max == 500.0);
  CHECK(m->range_of(m->motors[2]).t_max == 37.5);
  CHECK(m->imus[0].format == ImuFormat::kClassic);
}

TEST_CASE("a small map parses - ids may repeat on different buses") {
  auto m = ParseCanMap(kGood, "t.yaml");
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  CHECK(m->motors[1].bus == 1);
  CHECK(m->imus[0].format == ImuFormat::kFd);
  CHECK_FALSE(m->buses[1].fd);
}

TEST_CASE("errors name the file - the element and the field") {
  const std::string g = kGood;
  CHECK(ErrorOf("robot: [").find("t.yaml: YAML error") == 0);
  CHECK(ErrorOf(ReplaceOnce(g, "bus: b, id: 1", "bus: c, id: 1")) == "t.yaml: motors[1] 'J2'.bus: unknown bus 'c'");
  CHECK(ErrorOf(ReplaceOnce(g, "bus: b, id: 1, reply_id: 0x101", "bus: a, id: 1, reply_id: 0x102")) ==
        "t.yaml: motors[1] 'J2'.id: identifier 0x001 on bus 'a' is already used by motor 'J1' (id)");
  CHECK(ErrorOf(ReplaceOnce(g, "id: 0x80", "id: 0x101")) ==
        "t.yaml: imus[0] 'imu'.id: identifier 0x101 on bus 'a' is already used by motor 'J1' (reply_id)");
  CHECK(ErrorOf(ReplaceOnce(g, "joint: J2", "joint: J1")) == "t.yaml: motors[1] 'J1'.joint: duplicate joint 'J1'");
  CHECK(ErrorOf(ReplaceOnce(g, "p_min: -12.5", "p_min: 12.5")) ==
        "t.yaml: actuators[0] 'm'.p_min: p_min 12.5 is not below p_max 12.5");
  CHECK(ErrorOf(ReplaceOnce(g, "kd_max: 5", "kd_max: -1")) ==
        "t.yaml: actuators[0] 'm'.kd_min: kd_min 0 is not below kd_max -1");
  CHECK(ErrorOf(ReplaceOnce(g, "t_max: 25", "t_max: abc")) == "t.yaml: actuators[0] 'm'.t_max: 'abc' is not a number");
  CHECK(ErrorOf(ReplaceOnce(g, "v_min: -50, ", "")) == "t.yaml: actuators[0] 'm': missing field 'v_min'");
  CHECK(ErrorOf(ReplaceOnce(g, "actuator: m}\n  - {joint: J2", "actuator: n}\n  - {joint: J2")) ==
        "t.yaml: motors[0] 'J1'.actuator: unknown actuator 'n'");
  CHECK(ErrorOf(ReplaceOnce(g, "reply_id: 0x101, actuator: m}\n  - {joint: J2",
                            "reply_id: 0x800, actuator: m}\n  - {joint: J2")) ==
        "t.yaml: motors[0] 'J1'.reply_id: '0x800' is outside [0x000, 0x7FF]");
  CHECK(ErrorOf(ReplaceOnce(g, "bus: a, id: 1,", "bus: a, id: 256,")) ==
        "t.yaml: motors[0] 'J1'.id: '256' is outside [0x001, 0x0FF]");
  CHECK(ErrorOf(ReplaceOnce(g, "bus: a, format: fd", "bus: b, format: fd")) ==
        "t.yaml: imus[0] 'imu'.format: 'fd' on bus 'b', which is not an fd bus");
  CHECK(ErrorOf(ReplaceOnce(g, "format: fd", "format: can2")) ==
        "t.yaml: imus[0] 'imu'.format: 'can2' is not classic or fd");
  CHECK(ErrorOf(ReplaceOnce(g, "interface: vcan1", "interface: vcan0")) ==
        "t.yaml: buses[1].interface: 'vcan0' is already used by bus 'a'");
  CHECK(ErrorOf(ReplaceOnce(g, "{name: b,", "{name: a,")) == "t.yaml: buses[1].name: duplicate bus 'a'");
  CHECK(ErrorOf(ReplaceOnce(g, "fd: true", "fd: yes please")) ==
        "t.yaml: buses[0].fd: 'yes please' is not true or false");
  CHECK(ErrorOf(ReplaceOnce(g, "robot: testbot", "robot: testbot\nextra: 1")) == "t.yaml: extra: unknown field");
  CHECK(ErrorOf(ReplaceOnce(g, "id: 0x80", "id: 0x80, gain: 2")) == "t.yaml: imus[0].gain: unknown field");
  CHECK(LoadCanMap("/nonexistent/can_map.yaml").error().message == "/nonexistent/can_map.yaml: cannot open");
}

TEST_CASE("a classic IMU claims three consecutive ids") {
  std::string g = ReplaceOnce(kGood, "format: fd, id: 0x80", "format: classic, id: 0xFF");
  g = ReplaceOnce(
      g, "reply_id: 0x101, actuator: m}\n  - {joint: J2",
      "reply_id: 0x101, actuator: m}\n  - {joint: J3, bus: a, id: 2, reply_id: 0x100, actuator: m}\n  - {joint: J2");
  CHECK(ErrorOf(g) == "t.yaml: imus[0] 'imu'.id: identifier 0x100 on bus 'a' is already used by motor 'J3' (reply_id)");
}
