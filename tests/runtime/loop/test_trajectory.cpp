// The stand-test trajectory file: loads, and refuses bad files naming the field.
#include <doctest/doctest.h>

#include <string>

#include "runtime/loop/trajectory_source.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;

TEST_CASE("stand trajectory: the shipped file loads - errors name the field") {
  const robot::RobotModel& d = test::QuadrupedRobot();
  auto t = loop::RobotTrajectory(d);
  REQUIRE_MESSAGE(t.ok(), t.error().message);
  CHECK(t->joints.size() == 12);
  CHECK(t->duration_s == 2.0);
  auto err = [&](const std::string& y) {
    auto r = loop::ParseTrajectory(y, "traj.yaml", d);
    REQUIRE_FALSE(r.ok());
    return r.error().message;
  };
  CHECK(err("duration_s: 1\njoints: [{joint: LF_KNEE, amplitude_rad: 0.1, frequency_hz: 1}]") ==
        "traj.yaml: joints[0] 'LF_KNEE'.joint: is not an actuated joint of the robot");
  CHECK(err("duration_s: 1\njoints: [{joint: LF_KFE, amplitude_rad: 1.2, frequency_hz: 1}]") ==
        "traj.yaml: joints[0] 'LF_KFE'.amplitude_rad: sweeps [-2, 0.4] rad, outside the joint's limits [-2.6, 0.3]");
  CHECK(err("duration_s: 1\njoints: [{joint: LF_KFE, amplitude_rad: 0.1, frequency_hz: 0}]") ==
        "traj.yaml: joints[0] 'LF_KFE'.frequency_hz: is outside (0, 10] Hz");
  CHECK(err("duration_s: 1\njoints: [{joint: LF_KFE, amplitude_rad: 0.1, freq: 1}]") ==
        "traj.yaml: joints[0].freq: unknown field");
  CHECK(err("duration_s: -1\njoints: [{joint: LF_KFE, amplitude_rad: 0.1, frequency_hz: 1}]") ==
        "traj.yaml: duration_s: is not positive");
}
