// `pbppo replay LOG... --robot models/<robot>/robot.yaml [--policy BLOB | --trajectory FILE]`: runs
// the robot's loop tick over a log recorded by pbppo-controller --record (runtime/loop/replay.hpp)
// and compares every command with the recorded one, bit for bit. The files of a rotated recording
// (--record-max-mb) each replay on their own from the snapshot they begin with; given several,
// each is replayed and they must follow one another (one recording, consecutive files, the ticks
// continuing). --trace FILE writes what every tick saw and did: tick, phase, mode and the robot's
// fields as the tick held them (--trace-fields NAME,...: those only), one CSV row per tick.
// --policy-io PREFIX writes each policy run's observation and action (float32 rows). Exit 0:
// identical; 1: a difference (the first one named), files that do not follow
// one another, or a log, robot or source refused (naming the offset and field, or what differs
// from the recording); 2: usage.
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace pbppo::cli {

struct ReplayOptions {
  std::vector<std::string> logs;
  std::string robot, policy, trajectory, out, trace;
  std::string policy_io;  // PREFIX: each policy run's observation and action, PREFIX.obs.f32 / .act.f32
  std::vector<std::string> trace_fields;
  std::vector<std::string> switch_policies;  // the recording's --switch-policy blobs, in order
  std::string kernel = "auto";               // the recording's forward kernel
};

// Adds the subcommand to `app`; Replay runs it.
CLI::App* AddReplay(CLI::App& app, ReplayOptions& o);
int Replay(const ReplayOptions& o);

}  // namespace pbppo::cli
