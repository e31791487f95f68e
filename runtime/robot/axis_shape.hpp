// An input axis shaped into a field: a gamepad's stick through evdev (runtime/transport/evdev), a
// remote's stick inside a DDS message (robot.yaml `axes`). The robot file's data (AxisShape, in the
// transport specs) and the one function both transports shape with, with its inverse for a peer
// that writes the raw value.
#pragma once

#include <cmath>

namespace pbppo::robot {

// The raw range onto [-1, 1], a dead zone around 0 (rescaled, so the value leaves 0 without a step
// at the zone's edge), times the scale. A raw value outside the range (or not a number) gives NaN,
// which the sample check names.
struct AxisShape {
  double raw_min = -1, raw_max = 1, scale = 1, dead_zone = 0;
};

inline double ShapeAxis(const AxisShape& a, double raw) noexcept {
  if (!(raw >= a.raw_min && raw <= a.raw_max)) return std::nan("");
  const double n = (2 * raw - a.raw_min - a.raw_max) / (a.raw_max - a.raw_min);
  const double mag = std::abs(n);
  if (mag <= a.dead_zone) return 0.0;
  const double out = (mag - a.dead_zone) / (1 - a.dead_zone) * a.scale;
  return n < 0 ? -out : out;
}

// The raw value ShapeAxis takes to `value` (0: the middle of the range): what a peer writes.
inline double UnshapeAxis(const AxisShape& a, double value) noexcept {
  const double u = value / a.scale;
  const double n = u == 0 ? 0.0 : std::copysign(std::abs(u) * (1 - a.dead_zone) + a.dead_zone, u);
  return (n * (a.raw_max - a.raw_min) + a.raw_min + a.raw_max) / 2;
}

}  // namespace pbppo::robot
