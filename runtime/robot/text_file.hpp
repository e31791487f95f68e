// Reading the robot's data files (set-up time only). Every read is counted per path, so a test
// can prove that a process reads each robot file once (runtime/robot/robot_model.hpp).
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "runtime/core/result.hpp"

namespace pbppo::robot {

// The whole file; "PATH: cannot open" when it cannot be read.
Result<std::string> ReadTextFile(const std::string& path);

// How often each path was read by ReadTextFile in this process (a copy, under a lock).
std::map<std::string, std::uint64_t> FileReads();

}  // namespace pbppo::robot
