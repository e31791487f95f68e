// The loop over a clock (runtime/rt/tick_clock.hpp: absolute deadlines, lock-step, or paced by a
// lock-step transport): wait for the tick, Tick, until the robot is done. SIGINT and SIGTERM
// request the stop: a robot with motors goes through damping and motor-off on its own ticks; a
// robot without them stops the clock and sends its stop command (loop::Shutdown). Runs on the
// calling thread, set up with rt::SetUpRealTime; allocation-free per tick.
#pragma once

#include <atomic>
#include <functional>
#include <thread>

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
  bool ended = false;    // by the robot's end field (LoopOptions::stop_at_end_field)
  TickStatus status = TickStatus::kRunning;
};

// SIGINT and SIGTERM call RequestStop.
void InstallStopSignals();
// SIGUSR1 asks the running loop to re-arm (LoopData::RequestRearm: the robot file's recovery rule).
void InstallRearmSignal();
// Async-signal-safe: the running loop stops (see above).
void RequestStop() noexcept;
bool StopRequested() noexcept;
void ClearStop() noexcept;

RunResult Run(const robot::RobotModel& model, robot::RobotData& data, LoopData& loop,
              std::span<robot::Transport* const> transports, rt::TickClock& clock, const RunOptions& options) noexcept;

// The controller's status as another thread sees it (status messages, progress lines).
robot::ControllerStatus StatusOf(const LoopData& loop) noexcept;

// Publishes StatusOf(loop) through `transports` (their status messages) every `period_ns`, from
// a thread of its own; `poll`, when given, is called from that thread every 10 ms with the loop's
// status and whether it was just published (progress lines). The destructor stops the thread;
// the transports' Finish publishes the final state. `transports` and `loop` must outlive it.
class StatusPublisher {
 public:
  using Poll = std::function<void(const LoopStatus& status, bool published)>;
  StatusPublisher(std::span<robot::Transport* const> transports, const LoopData& loop, std::int64_t period_ns,
                  Poll poll = {});
  ~StatusPublisher();
  StatusPublisher(const StatusPublisher&) = delete;
  StatusPublisher& operator=(const StatusPublisher&) = delete;

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Lock-step over a stream (robot.yaml timing.lockstep): a thread that advances `clock` once per
// new sample of `stream` from `transport`, or once per `timeout_ns` without one (a vanished peer
// is then seen as stale samples), each time after the loop took the previous tick, until `done`.
std::thread PaceBySamples(robot::Transport& transport, std::uint32_t stream, rt::LockStepClock& clock,
                          const std::atomic<bool>& done, std::int64_t timeout_ns);

}  // namespace pbppo::loop
