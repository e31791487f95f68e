// Linear ranges of the MIT (mini-cheetah) motor protocol as flashed into a driver: robot data
// (models/<robot>/can_map.yaml, runtime/robot/can_map.hpp) that the CAN codecs
// (runtime/transport/can/mit_codec.hpp) scale with. Plain data, no dependency.
#pragma once

namespace pbppo::robot {

struct MitRange {
  double p_min = 0, p_max = 0;    // position, rad
  double v_min = 0, v_max = 0;    // velocity, rad/s
  double kp_min = 0, kp_max = 0;  // stiffness, Nm/rad
  double kd_min = 0, kd_max = 0;  // damping, Nm*s/rad
  double t_min = 0, t_max = 0;    // torque (feed-forward and measured), Nm
};

}  // namespace pbppo::robot
