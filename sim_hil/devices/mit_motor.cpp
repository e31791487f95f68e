#include "sim_hil/devices/mit_motor.hpp"

#include <cmath>

namespace pbppo::sim {
namespace {

// splitmix64: a small, seeded, reproducible generator.
std::uint64_t Next(std::uint64_t& state) noexcept {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace

MitMotorState MakeMitMotorState(const MitMotorConfig& config) noexcept {
  MitMotorState s;
  s.rng = config.seed * 0x2545F4914F6CDD1Dull + config.motor_id;
  return s;
}

bool MitMotorReceive(const MitMotorConfig& c, MitMotorState& s, const can::CanFrame& frame, std::uint64_t tick,
                     double q_rad, double dq_rad_s, can::CanFrame* reply) noexcept {
  if (tick >= c.silent_from_tick) {
    ++s.ignored_silent;
    return false;
  }
  if (c.drop_probability > 0) {
    const double u = static_cast<double>(Next(s.rng) >> 11) * 0x1.0p-53;
    if (u < c.drop_probability && (c.max_drop_burst == 0 || s.drop_burst < c.max_drop_burst)) {
      ++s.drop_burst;
      ++s.dropped;
      return false;
    }
    s.drop_burst = 0;
  }
  can::MitSpecial special;
  can::MitCommand cmd;
  if (can::DecodeMitSpecial(frame.data, frame.len, &special)) {
    ++s.frames;
    ++s.specials;
    switch (special) {
      case can::MitSpecial::kEnterMotorMode:
        s.motor_mode = true;
        s.have_command = false;  // a fresh start: no torque until the first command
        break;
      case can::MitSpecial::kExitMotorMode:
        s.motor_mode = false;
        s.have_command = false;
        break;
      case can::MitSpecial::kSetZero: s.zero_offset_rad = q_rad; break;
    }
  } else if (can::DecodeMitCommand(c.range, frame.data, frame.len, &cmd)) {
    ++s.frames;
    ++s.commands;
    if (s.motor_mode) {
      s.command = cmd;
      s.have_command = true;
      s.last_command_tick = tick;
    }
  } else {
    ++s.ignored_length;
    return false;  // wrong length: the firmware ignores it
  }
  can::MitReply r;
  r.motor_id = static_cast<std::uint8_t>(c.motor_id);
  r.q_rad = q_rad - s.zero_offset_rad;
  if (c.wrap_position) {
    const double span = c.range.p_max - c.range.p_min;
    r.q_rad = c.range.p_min + (r.q_rad - c.range.p_min - span * std::floor((r.q_rad - c.range.p_min) / span));
  }
  r.dq_rad_s = dq_rad_s;
  r.tau_nm = s.tau_nm;
  *reply = can::MakeMitReplyFrame(c.reply_id, c.range, r);
  ++s.replies;
  return true;
}

double MitMotorTorque(const MitMotorConfig& c, MitMotorState& s, std::uint64_t tick, double q_rad,
                      double dq_rad_s) noexcept {
  double tau = 0;
  if (s.motor_mode && s.have_command) {
    if (tick - s.last_command_tick > c.timeout_ticks) {
      ++s.timeouts;
    } else {
      const can::MitCommand& m = s.command;
      tau =
          m.kp_nm_rad * (m.q_rad - (q_rad - s.zero_offset_rad)) + m.kd_nm_s_rad * (m.dq_rad_s - dq_rad_s) + m.tau_ff_nm;
    }
  }
  if (!std::isfinite(tau)) tau = 0;
  tau = tau > c.tau_limit_nm ? c.tau_limit_nm : (tau < -c.tau_limit_nm ? -c.tau_limit_nm : tau);
  s.tau_nm = tau;
  return tau;
}

}  // namespace pbppo::sim
