// The quadruped operator's messages as plain fixed-size C++ structs: the velocity command an
// operator sends and the walking controller's status. The DDS types (models/quadruped/idl/) carry
// the same fields; the transport converts between the two on its own threads, so the control tick
// only ever sees these structs.
#pragma once

#include <cstdint>

namespace pbppo::robot {

struct VelocityCommand {
  std::uint64_t seq = 0;                              // the operator's sequence number (1, 2, ...)
  std::int64_t stamp_ns = 0;                          // operator clock
  double vx_mps = 0, vy_mps = 0, yaw_rate_radps = 0;  // base frame: forward, left, counter-clockwise
};

struct QuadrupedStatus {
  std::uint64_t tick = 0;
  std::uint8_t phase = 0;   // loop::Phase
  std::uint8_t mode = 0;    // safety::Mode
  std::uint32_t cause = 0;  // 1 << the latest latched safety::Cause (0: none)
  std::uint64_t commands_received = 0;
  double command_vx_mps = 0, command_vy_mps = 0, command_yaw_rate_radps = 0;  // the command in force
  std::uint64_t deadline_misses = 0, stale_samples = 0;
  double tick_median_us = 0, tick_max_us = 0;
};

}  // namespace pbppo::robot
