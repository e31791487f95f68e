// Replay: the same Tick over a recorded log (runtime/loop/log.hpp) instead of the transports. The
// inputs of each tick are put back as they arrived (fields, fresh streams, links' health, deadline
// misses, requests) and the commands Tick writes are compared, bit for bit, with the recorded
// ones. The robot model, the source (policy blob or trajectory) and the tick period must be the
// recorded run's: a log of another robot, files that changed, or another policy are refused
// naming what differs. A later file of a rotated recording starts from its snapshot (the loop's
// state at the tick it begins with) and replays on its own.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/loop/log.hpp"
#include "runtime/loop/loop.hpp"

namespace pbppo::loop {

struct ReplayResult {
  std::uint64_t ticks = 0;          // ticks run
  std::uint64_t compared = 0;       // recorded outputs compared
  std::uint64_t mismatches = 0;     // of those, different
  std::string first_mismatch;       // "tick 12: command 'surge_speed' 0x1.99999999999ap-4 (recorded 0x1.9p-4)"
  std::vector<LogOutputs> outputs;  // what the replay wrote, in order
};

// Called after every replayed tick with what the tick saw and did (a trace: pbppo replay --trace).
using ReplayTick = std::function<void(const robot::RobotData&, const LoopData&)>;

// `robot` is the model as loaded (at its own tick period); `source` as the recorded run made it
// (nullptr: none), `source_hash` LogHash of its bytes. The loop's options are the log's.
Result<ReplayResult> Replay(const robot::RobotModel& robot, const Log& log, CommandSource* source,
                            std::uint64_t source_hash, const ReplayTick& each_tick = {});

// One line per output: tick, phase, mode, every command as a hexadecimal float (exact), the
// motors; the same text for the same bits.
std::string FormatOutputs(const robot::RobotModel& robot, const std::vector<LogOutputs>& outputs);

}  // namespace pbppo::loop
