// The AUV control loop over any transport and any tick clock: wait for the tick, take the newest
// sample, Tick the controller, send the command; SIGINT/SIGTERM (or RequestLoopStop) ends it
// after sending the safe command (zero speed, e-stop mode). The transport is an abstract link
// (DDS, an in-process test link, ...): its calls must not allocate, lock or block.
#pragma once

#include <cstdint>

#include "firmware/auv/auv_controller.hpp"
#include "runtime/robot/auv_messages.hpp"
#include "runtime/rt/tick_clock.hpp"

namespace pbppo::firmware {

enum class PeerState : std::uint8_t { kUnknown, kAlive, kLost };

class AuvLink {
 public:
  virtual ~AuvLink() = default;
  // Copies the newest sample received so far (false: none yet). Non-blocking.
  virtual bool Latest(robot::AuvSensorSample& out) noexcept = 0;
  // Queues a command (false: dropped). Non-blocking.
  virtual bool Send(const robot::AuvCommand& cmd) noexcept = 0;
  // What the transport knows about the vehicle (liveliness, heartbeats).
  virtual PeerState Peer() noexcept = 0;
};

struct LoopOptions {
  std::uint64_t max_ticks = 0;  // 0: until stopped
  bool arm_at_start = true;
};

struct LoopResult {
  std::uint64_t ticks = 0;
  std::uint64_t send_failures = 0;
  bool stopped = false;  // by a signal or RequestLoopStop (not by max_ticks or the clock)
  safety::AuvMode final_mode = safety::AuvMode::kNominal;
};

// SIGINT and SIGTERM request the stop (and stop the clock of the running loop).
void InstallLoopSignalHandlers();
// Async-signal-safe.
void RequestLoopStop() noexcept;
bool LoopStopRequested() noexcept;
void ClearLoopStop() noexcept;

// Runs on the calling thread (set it up with rt::SetUpRealTime first). Allocation-free per tick.
LoopResult RunAuvControlLoop(AuvController& controller, AuvLink& link, rt::TickClock& clock,
                             const LoopOptions& options) noexcept;

}  // namespace pbppo::firmware
