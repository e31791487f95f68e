// The shipped robots, each loaded once per test process (as a program loads its robot once).
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>

#include "runtime/robot/robot_model.hpp"
#include "tests/support/test_paths.hpp"

namespace pbppo::test {

inline const robot::RobotModel& LoadShipped(const std::string& name) {
  auto m = robot::LoadRobotModel(SourcePath("models/" + name + "/robot.yaml"));
  if (!m) {
    std::fprintf(stderr, "%s\n", m.error().message.c_str());
    std::abort();
  }
  return *new robot::RobotModel(std::move(*m));  // lives as long as the process
}

inline const robot::RobotModel& AuvRobot() {
  static const robot::RobotModel& m = LoadShipped("auv");
  return m;
}

inline const robot::RobotModel& QuadrupedRobot() {
  static const robot::RobotModel& m = LoadShipped("quadruped");
  return m;
}

}  // namespace pbppo::test
