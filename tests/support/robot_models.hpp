// The shipped robots, each loaded once per test process (as a program loads its robot once).
#pragma once

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "runtime/robot/robot_model.hpp"
#include "tests/support/test_paths.hpp"

namespace pbppo::test {

// A fresh copy of a shipped robot's folder (or of `folder`, relative to the source tree) to edit:
// <scratch dir `scratch`>/<name>, with the robots' shared files beside it (models/dds_profile.xml,
// the quadruped's operator messages, the ROS 2 messages of models/ros2).
// Returns the copy's folder.
inline std::string CopyRobotFolder(const std::string& name, const std::string& scratch, std::string folder = "") {
  if (folder.empty()) folder = "models/" + name;
  const std::string root = ScratchDir(scratch), dir = root + "/" + name;
  std::filesystem::copy(SourcePath(folder), dir, std::filesystem::copy_options::recursive);
  std::filesystem::copy_file(SourcePath("models/dds_profile.xml"), root + "/dds_profile.xml");
  std::filesystem::copy(SourcePath("models/ros2"), root + "/ros2", std::filesystem::copy_options::recursive);
  // The operator's message files another robot names from beside it (../quadruped/idl).
  if (name != "quadruped") {
    std::filesystem::create_directories(root + "/quadruped/idl");
    for (const auto& e : std::filesystem::directory_iterator(SourcePath("models/quadruped/idl")))
      std::filesystem::copy_file(e.path(), root + "/quadruped/idl/" + e.path().filename().string(),
                                 std::filesystem::copy_options::overwrite_existing);
  }
  // The robot whose files another one names (../go2/go2.yaml ...).
  if (name == "go2_remote")
    std::filesystem::copy(SourcePath("models/go2"), root + "/go2", std::filesystem::copy_options::recursive);
  return dir;
}

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

inline const robot::RobotModel& Go2Robot() {
  static const robot::RobotModel& m = LoadShipped("go2");
  return m;
}

inline const robot::RobotModel& QuadrupedRobot() {
  static const robot::RobotModel& m = LoadShipped("quadruped");
  return m;
}

// The quadruped driven from a gamepad (models/quadruped_gamepad).
inline const robot::RobotModel& GamepadRobot() {
  static const robot::RobotModel& m = LoadShipped("quadruped_gamepad");
  return m;
}

inline const robot::RobotModel& Go2RemoteRobot() {
  static const robot::RobotModel& m = LoadShipped("go2_remote");
  return m;
}

// The two-wheeled robot on CAN that exists only as test data (tests/data/diffbot): continuous,
// velocity-commanded wheels and a position-commanded head.
inline const robot::RobotModel& DiffbotRobot() {
  static const robot::RobotModel& m = LoadShipped("../tests/data/diffbot");
  return m;
}

}  // namespace pbppo::test
