// Robots found by name: `--robot auv` as well as `--robot models/auv/robot.yaml`. Set-up time only.
//
// An argument with a '/' or ending in ".yaml" is a path: a robot file, or a folder holding a
// robot.yaml. Anything else is a robot's name (letters, digits, '_' and '-'), looked up as
// NAME/robot.yaml in these folders, first match wins:
//   1. each folder of $PBPPO_ROBOT_PATH (':'-separated), for robots of one's own;
//   2. ../share/pbppo-rt/robots beside the running program (the installed robots: a package,
//      `cmake --install`, or an unpacked tree, wherever its prefix is);
//   3. ./models (a source checkout, where the programs run from in development).
#pragma once

#include <string>
#include <vector>

#include "runtime/core/result.hpp"

namespace pbppo::robot {

// The folders a name is looked up in, in order (those that do not exist included).
std::vector<std::string> RobotSearchPath();

// The robot file `name_or_path` means; an unknown name's error lists where it was looked for and
// the robots found there.
Result<std::string> FindRobot(const std::string& name_or_path);

}  // namespace pbppo::robot
