// An emulated MIT (mini-cheetah protocol) motor driver with the behaviour of the real firmware,
// speaking the same codecs as the controller (runtime/transport/can/mit_codec.hpp). Pure: frames
// in, frames and torque out; the HIL program moves the frames over SocketCAN.
//
//   - every frame addressed to the motor is answered with one reply (position, velocity, torque),
//     in or out of motor mode, commands and special frames alike;
//   - FF..FC enters motor mode, FF..FD exits it (zero torque), FF..FE sets the current position
//     as zero (later positions, in both directions, are relative to it);
//   - in motor mode the torque is kp (p - q) + kd (v - dq) + t_ff from the latest command,
//     evaluated every simulation tick and limited to +-tau_limit (the actuator config: the URDF
//     effort limit and the MIT torque range, whichever is smaller);
//   - no command for timeout_ticks: zero torque until the next command (the driver's watchdog);
//   - commands outside motor mode are answered but not obeyed;
//   - wrap_position (a continuous joint's driver): the reported position wraps into the MIT range
//     [p_min, p_max) (period p_max - p_min) instead of saturating at its ends; the torque law uses
//     the joint's own (multi-turn) position.
//
// Test hooks (the emulator's own faults): drop a fraction of received frames (no effect, no
// reply) with a seeded generator and a bound on consecutive drops, or go silent from a tick on
// (a driver off the bus: hears nothing, answers nothing, its watchdog cuts the torque).
#pragma once

#include <cstdint>

#include "runtime/transport/can/can_frame.hpp"
#include "runtime/transport/can/mit_codec.hpp"

namespace pbppo::sim {

struct MitMotorConfig {
  std::uint32_t motor_id = 0;  // command identifier and first reply byte
  std::uint32_t reply_id = 0;
  can::MitRange range;
  double tau_limit_nm = 0;
  std::uint32_t timeout_ticks = 50;
  bool wrap_position = false;  // report the position modulo the MIT range (a continuous joint)
  // Faults for tests.
  double drop_probability = 0;       // of each received frame
  std::uint32_t max_drop_burst = 0;  // most consecutive drops (0: unbounded)
  std::uint64_t silent_from_tick = UINT64_MAX;
  std::uint64_t seed = 1;
};

struct MitMotorState {
  bool motor_mode = false;
  double zero_offset_rad = 0;
  can::MitCommand command;
  bool have_command = false;
  std::uint64_t last_command_tick = 0;
  std::uint64_t rng = 0;
  std::uint32_t drop_burst = 0;
  double tau_nm = 0;  // the torque of the current tick
  // Counters.
  std::uint64_t frames = 0;  // commands and special frames handled
  std::uint64_t commands = 0, specials = 0, replies = 0, dropped = 0, ignored_silent = 0, ignored_length = 0;
  std::uint64_t timeouts = 0;  // ticks at zero torque for lack of commands while in motor mode
};

MitMotorState MakeMitMotorState(const MitMotorConfig& config) noexcept;

// One received frame for this motor (the caller has matched the identifier). Returns true and
// fills *reply when the driver answers. q/dq: the joint's state now (rad, rad/s).
bool MitMotorReceive(const MitMotorConfig& config, MitMotorState& s, const can::CanFrame& frame, std::uint64_t tick,
                     double q_rad, double dq_rad_s, can::CanFrame* reply) noexcept;

// The torque for this tick (Nm), from the latest command and the joint's state.
double MitMotorTorque(const MitMotorConfig& config, MitMotorState& s, std::uint64_t tick, double q_rad,
                      double dq_rad_s) noexcept;

}  // namespace pbppo::sim
