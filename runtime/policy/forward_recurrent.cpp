// The element-wise half of an LSTM or GRU step, shared by every kernel: the gate products run
// through the calling kernel's dense layer (packed AVX-512 or NEON tiles, or Eigen), the gates and
// the state update here as Eigen arrays (vectorised with the build's instruction set). Sigmoid is
// 0.5 * tanh(0.5 x) + 0.5, so its error is that of the kernels' tanh (reference.cpp's bound).
#include <Eigen/Core>

#include "runtime/policy/kernel_view.hpp"

namespace pbppo::policy::detail {
namespace {

using Vec = Eigen::Map<Eigen::ArrayXf>;
using ConstVec = Eigen::Map<const Eigen::ArrayXf>;

inline Eigen::Index Ix(std::uint32_t n) noexcept {
  return static_cast<Eigen::Index>(n);
}

// Writes the new h to the layer's output and zeroes the output's padding.
void Emit(const float* h, std::uint32_t n, std::uint32_t n_pad, float* y) noexcept {
  Vec(y, Ix(n)) = ConstVec(h, Ix(n));
  for (std::uint32_t i = n; i < n_pad; ++i) y[i] = 0.0f;
}

void LstmStep(const KernelLayer& l, const float* x, float* y, const DataView& d, DenseFn dense) noexcept {
  const std::uint32_t n = l.out;
  float* h = d.state + l.state;
  float* c = h + l.out_pad;
  dense(l.parts[0], x, d.gx);  // W x + Wb, gates i, o, f, c
  dense(l.parts[1], h, d.gh);  // R h + Rb
  Vec g(d.gx, Ix(4 * n));
  g += ConstVec(d.gh, Ix(4 * n));
  const auto gate = [&](std::uint32_t k) { return Vec(d.gx + static_cast<std::size_t>(k) * n, Ix(n)); };
  Vec gi = gate(0), go = gate(1), gf = gate(2), gc = gate(3);
  gi = (gi * 0.5f).tanh() * 0.5f + 0.5f;
  go = (go * 0.5f).tanh() * 0.5f + 0.5f;
  gf = (gf * 0.5f).tanh() * 0.5f + 0.5f;
  gc = gc.tanh();
  Vec cv(c, Ix(n)), hv(h, Ix(n));
  cv = gf * cv + gi * gc;
  hv = go * cv.tanh();
  Emit(h, n, l.out_pad, y);
}

void GruStep(const KernelLayer& l, const float* x, float* y, const DataView& d, DenseFn dense) noexcept {
  const std::uint32_t n = l.out;
  float* h = d.state + l.state;
  dense(l.parts[0], x, d.gx);  // W x + Wb, gates z, r, h
  dense(l.parts[1], h, d.gh);  // R_zr h + Rb_zr
  Vec z(d.gx, Ix(n)), r(d.gx + n, Ix(n)), gn(d.gx + 2 * static_cast<std::size_t>(n), Ix(n));
  z = ((z + ConstVec(d.gh, Ix(n))) * 0.5f).tanh() * 0.5f + 0.5f;
  r = ((r + ConstVec(d.gh + n, Ix(n))) * 0.5f).tanh() * 0.5f + 0.5f;
  Vec hv(h, Ix(n)), t(d.gt, Ix(n));
  if (l.linear_before_reset != 0) {
    dense(l.parts[2], h, d.gt);  // R_h h + Rb_h
    gn = (gn + r * t).tanh();
  } else {
    Vec(d.rh, Ix(n)) = r * hv;  // d.rh's padding stays zero
    dense(l.parts[2], d.rh, d.gt);
    gn = (gn + t).tanh();
  }
  hv = (1.0f - z) * gn + z * hv;
  Emit(h, n, l.out_pad, y);
}

}  // namespace

void RecurrentStep(const KernelLayer& l, const float* x, float* y, const DataView& d, DenseFn dense) noexcept {
  if (l.kind == 1) {
    LstmStep(l, x, y, d, dense);
  } else {
    GruStep(l, x, y, d, dense);
  }
}

}  // namespace pbppo::policy::detail
