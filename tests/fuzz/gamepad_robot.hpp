// The shipped gamepad robot (models/quadruped_gamepad), loaded once per fuzzing process from the
// source tree; shared by the fuzz targets that read it.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>

#include "runtime/robot/robot_model.hpp"

namespace pbppo::fuzz {

inline const robot::RobotModel& GamepadRobot() {
  static const robot::RobotModel* model = [] {
    auto m = robot::LoadRobotModel(std::string(PBPPO_SOURCE_DIR) + "/models/quadruped_gamepad/robot.yaml");
    if (!m) {
      std::fprintf(stderr, "%s\n", m.error().message.c_str());
      std::abort();
    }
    return new robot::RobotModel(std::move(*m));
  }();
  return *model;
}

}  // namespace pbppo::fuzz
