// Ranges shared by the MIT codec fuzz targets: the quadruped's AK70-10 ranges and an asymmetric one.
#pragma once

#include <cstdint>
#include <cstdlib>

#include "runtime/transport/can/mit_codec.hpp"

namespace pbppo::fuzz {

inline can::MitRange FuzzRange(std::uint8_t selector) {
  can::MitRange r;
  if ((selector & 1u) == 0) {
    r.p_min = -12.5, r.p_max = 12.5, r.v_min = -50, r.v_max = 50, r.kp_min = 0, r.kp_max = 500;
    r.kd_min = 0, r.kd_max = 5, r.t_min = -25, r.t_max = 25;
  } else {
    r.p_min = -3.0, r.p_max = 9.7, r.v_min = -7, r.v_max = 41, r.kp_min = 2, r.kp_max = 333;
    r.kd_min = 0.1, r.kd_max = 4.2, r.t_min = -18, r.t_max = 30;
  }
  return r;
}

inline void Require(bool ok) {
  if (!ok) std::abort();
}

inline bool Within(double x, double lo, double hi) {
  const double slack = 1e-9 * (hi - lo);
  return x >= lo - slack && x <= hi + slack;
}

}  // namespace pbppo::fuzz
