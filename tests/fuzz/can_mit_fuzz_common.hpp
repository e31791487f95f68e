// Ranges shared by the MIT codec fuzz targets: the quadruped's AK70-10 ranges and an asymmetric one.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>

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

// One fuzz input: a selector byte (which range), then a CAN payload of up to 64 bytes.
struct MitInput {
  can::MitRange range;
  std::uint8_t payload[can::kFdMaxLen] = {};
  std::uint8_t len = 0;
};

// Splits data into range and payload; false for an empty input or a payload longer than a frame's.
inline bool SplitMitInput(const std::uint8_t* data, std::size_t size, MitInput* in) {
  if (size < 1 || size > 1 + can::kFdMaxLen) return false;
  in->range = FuzzRange(data[0]);
  in->len = static_cast<std::uint8_t>(size - 1);
  std::memcpy(in->payload, data + 1, in->len);
  return true;
}

inline void Require(bool ok) {
  if (!ok) std::abort();
}

inline bool Within(double x, double lo, double hi) {
  const double slack = 1e-9 * (hi - lo);
  return x >= lo - slack && x <= hi + slack;
}

// Every value of a decoded command or reply lies inside the range it was decoded with.
inline bool InsideRange(const can::MitRange& r, const can::MitCommand& c) {
  return Within(c.q_rad, r.p_min, r.p_max) && Within(c.dq_rad_s, r.v_min, r.v_max) &&
         Within(c.kp_nm_rad, r.kp_min, r.kp_max) && Within(c.kd_nm_s_rad, r.kd_min, r.kd_max) &&
         Within(c.tau_ff_nm, r.t_min, r.t_max);
}
inline bool InsideRange(const can::MitRange& r, const can::MitReply& c) {
  return Within(c.q_rad, r.p_min, r.p_max) && Within(c.dq_rad_s, r.v_min, r.v_max) &&
         Within(c.tau_nm, r.t_min, r.t_max);
}

}  // namespace pbppo::fuzz
