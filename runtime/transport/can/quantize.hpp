// Linear quantisation of the MIT (mini-cheetah) protocol: a value x in [min, max] travels as an
// n-bit unsigned integer u = round((x - min) * (2^n - 1) / (max - min)), x clamped into
// [min, max] first; the receiver computes x' = u * (max - min) / (2^n - 1) + min. Rounding to
// nearest keeps |x' - x| <= step / 2 with step = (max - min) / (2^n - 1), and Decode then
// Encode gives back u exactly. Zero is a code only when -min / step is an integer (docs/can.md).
#pragma once

#include <cmath>
#include <cstdint>

namespace pbppo::can {

struct QuantizeResult {
  std::uint32_t code;
  bool clamped;     // x was outside [min, max]
  bool non_finite;  // x was NaN or infinite: encoded as the code nearest to zero
};

constexpr std::uint32_t MaxCode(unsigned bits) noexcept {
  return (1u << bits) - 1u;
}

inline double CodeToValue(std::uint32_t code, double min, double max, unsigned bits) noexcept {
  return static_cast<double>(code) * (max - min) / static_cast<double>(MaxCode(bits)) + min;
}

inline QuantizeResult ValueToCode(double x, double min, double max, unsigned bits) noexcept {
  QuantizeResult r{0, false, false};
  if (!std::isfinite(x)) {
    r.non_finite = true;
    x = 0.0;
  }
  if (x < min) {
    x = min;
    r.clamped = !r.non_finite;
  } else if (x > max) {
    x = max;
    r.clamped = !r.non_finite;
  }
  const double scaled = (x - min) * static_cast<double>(MaxCode(bits)) / (max - min);
  double rounded = std::floor(scaled + 0.5);
  if (rounded > static_cast<double>(MaxCode(bits))) rounded = static_cast<double>(MaxCode(bits));
  if (rounded < 0.0) rounded = 0.0;
  r.code = static_cast<std::uint32_t>(rounded);
  return r;
}

inline double QuantizationStep(double min, double max, unsigned bits) noexcept {
  return (max - min) / static_cast<double>(MaxCode(bits));
}

}  // namespace pbppo::can
