// The loop over a clock (runtime/rt/tick_clock.hpp: absolute deadlines, lock-step, or paced by a
// lock-step transport): wait for the tick, Tick, until the robot is done. SIGINT and SIGTERM
// request the stop: a robot with motors goes through damping and motor-off on its own ticks; a
// robot without them stops the clock and sends its stop command (loop::Shutdown). Runs on the
// calling thread, set up with rt::SetUpRealTime; allocation-free per tick.
#pragma once

#include <cstdint>
#include <span>

#include "runtime/loop/loop.hpp"
#include "runtime/rt/tick_clock.hpp"

namespace pbppo::loop {

struct RunOptions {
  std::uint64_t max_ticks = 0;  // 0: until done or stopped; then the stop as by a signal
  bool arm = true;              // arm on the first tick
};

struct RunResult {
  std::uint64_t ticks = 0;
  bool stopped = false;  // by RequestStop (a signal)
  TickStatus status = TickStatus::kRunning;
};

// SIGINT and SIGTERM call RequestStop.
void InstallStopSignals();
// Async-signal-safe: the running loop stops (see above).
void RequestStop() noexcept;
bool StopRequested() noexcept;
void ClearStop() noexcept;

RunResult Run(const robot::RobotModel& model, robot::RobotData& data, LoopData& loop,
              std::span<robot::Transport* const> transports, rt::TickClock& clock, const RunOptions& options) noexcept;

}  // namespace pbppo::loop
