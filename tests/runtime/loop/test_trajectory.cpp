// The stand-test trajectory file: loads (positions, and speeds for velocity-commanded joints), and
// refuses bad files naming the field.
#include <doctest/doctest.h>

#include <string>

#include "runtime/loop/trajectory_source.hpp"
#include "tests/support/refusal.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;

TEST_CASE("stand trajectory: the shipped file loads - errors name the field") {
  const robot::RobotModel& d = test::QuadrupedRobot();
  auto t = loop::RobotTrajectory(d);
  REQUIRE_MESSAGE(t.ok(), t.error().message);
  CHECK(t->joints.size() == 12);
  CHECK(t->duration_s == 2.0);
  auto err = [&](const std::string& y) { return pbppo::test::RefusalOf(loop::ParseTrajectory(y, "traj.yaml", d)); };
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

TEST_CASE("trajectory: speeds for velocity-commanded joints, never a position - errors name the joint and field") {
  const robot::RobotModel& d = test::DiffbotRobot();
  auto t = loop::RobotTrajectory(d);
  REQUIRE_MESSAGE(t.ok(), t.error().message);
  REQUIRE(t->joints.size() == 3);
  CHECK(t->joints[0].velocity);
  CHECK(t->joints[0].speed_rad_s == 12.0);
  CHECK(t->joints[0].amplitude_rad_s == 3.0);
  CHECK(t->joints[1].frequency_hz == 0.0);  // a constant speed needs no frequency
  CHECK_FALSE(t->joints[2].velocity);
  auto err = [&](const std::string& y) { return pbppo::test::RefusalOf(loop::ParseTrajectory(y, "traj.yaml", d)); };
  CHECK(err("duration_s: 1\njoints: [{joint: left_wheel, amplitude_rad: 0.5, frequency_hz: 1}]") ==
        "traj.yaml: joints[0] 'left_wheel'.amplitude_rad: joint 'left_wheel' is velocity-commanded (continuous): it "
        "takes no position target (give speed_rad_s, amplitude_rad_s)");
  CHECK(err("duration_s: 1\njoints: [{joint: head_pan, speed_rad_s: 1}]") ==
        "traj.yaml: joints[0] 'head_pan'.speed_rad_s: joint 'head_pan' is position-commanded: give amplitude_rad (a "
        "sinusoid around its default pose)");
  CHECK(err("duration_s: 1\njoints: [{joint: left_wheel, speed_rad_s: 18, amplitude_rad_s: 3, frequency_hz: 1}]") ==
        "traj.yaml: joints[0] 'left_wheel'.amplitude_rad_s: sweeps [15, 21] rad/s, outside the joint's velocity "
        "limits [-20, 20]");
  CHECK(err("duration_s: 1\njoints: [{joint: right_wheel, speed_rad_s: -25}]") ==
        "traj.yaml: joints[0] 'right_wheel'.speed_rad_s: sweeps [-25, -25] rad/s, outside the joint's velocity "
        "limits [-20, 20]");
  CHECK(err("duration_s: 1\njoints: [{joint: left_wheel, amplitude_rad_s: 3}]") ==
        "traj.yaml: joints[0] 'left_wheel': missing field 'frequency_hz'");
}
