// A command source from its files, as a controller program and a replay load it: a policy blob
// (checked against the robot's IO layout, its golden vectors run through the engine first: the
// self-test at arming), a joint trajectory file (the robot's own stand_trajectory, read with the
// robot, or another), or none (the loop holds the default pose). `hash` (LogHash of the file's
// bytes) identifies the source in a recorded log. Set-up time only.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "runtime/core/result.hpp"
#include "runtime/loop/log.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/loop/trajectory_source.hpp"
#include "runtime/policy/policy_model.hpp"

namespace pbppo::loop {

struct SourceFiles {
  std::string policy;      // a blob ("": none)
  std::string trajectory;  // a trajectory file ("": none)
  bool self_test = true;   // run the blob's golden vectors (refuse to arm on a mismatch)
};

struct LoadedSource {
  std::unique_ptr<policy::PolicyModel> policy;
  std::unique_ptr<CommandSource> source;   // null: none
  TrajectorySource* trajectory = nullptr;  // source, when it is a trajectory
  SourceKind kind = SourceKind::kNone;
  std::uint64_t hash = 0;
};

// Errors name the file and what is wrong ("refusing to arm: golden vectors: row 3 ...").
Result<LoadedSource> LoadSource(const robot::RobotModel& robot, const SourceFiles& files);

}  // namespace pbppo::loop
