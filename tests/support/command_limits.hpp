// Every command a CAN transport encoded (CanTransportOptions::command_record_capacity), judged
// against the robot model's command limits: the walking tests' "nothing unsafe on the bus".
#pragma once

#include <cstdint>
#include <vector>

#include "runtime/robot/robot_model.hpp"
#include "runtime/transport/can/can_transport.hpp"

namespace pbppo::test {

// How many values (q, dq, kp, kd, tau of each record) are not finite or outside their limits.
inline std::uint64_t CommandsOutsideLimits(const robot::RobotModel& m, const std::vector<can::CommandRecord>& records) {
  std::uint64_t bad = 0;
  for (const can::CommandRecord& c : records) {
    const robot::MotorSpec& mo = m.motors[c.motor];
    const double v[5] = {c.q_rad, c.dq_rad_s, c.kp, c.kd, c.tau_nm};
    const std::uint32_t k[5] = {mo.q, mo.dq, mo.kp, mo.kd, mo.tau};
    for (int i = 0; i < 5; ++i)
      if (!(v[i] >= m.commands[k[i]].min - 1e-9 && v[i] <= m.commands[k[i]].max + 1e-9)) ++bad;
  }
  return bad;
}

}  // namespace pbppo::test
