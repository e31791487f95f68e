// The portable forward pass: Eigen maps over the model's parameters and the data's arena.
#include <Eigen/Core>
#include <cmath>

#include "runtime/policy/kernel_view.hpp"

namespace pbppo::policy::detail {
namespace {

using VecMap = Eigen::Map<Eigen::ArrayXf, Eigen::Aligned64>;
using ConstVecMap = Eigen::Map<const Eigen::ArrayXf, Eigen::Aligned64>;
using MatMap =
    Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>, Eigen::Aligned64>;

inline Eigen::Index Ix(std::uint32_t n) noexcept {
  return static_cast<Eigen::Index>(n);
}

// Vectorised forms only: a select() with exp() evaluates exp per scalar.
// leaky_relu as max(x, alpha * x): for 0 <= alpha <= 1 (validated) this is x > 0 ? x : alpha * x
// bit for bit, because the rounded product of a float x and alpha lies between 0 and x (so it is
// <= x for x > 0 and >= x for x <= 0), and a NaN stays NaN; Eigen 3.4 would not vectorise a select().
void Activate(std::uint32_t activation, float alpha, VecMap y) noexcept {
  switch (activation) {
    case 1: y = y.tanh(); break;
    case 2: y = y.max(0.0f) + y.min(0.0f).exp() - 1.0f; break;
    case 3: y = y.max(0.0f); break;
    case 4: y = y.max(y * alpha); break;
    default: break;
  }
}

// y = act(W x + b) over row-major W; x and y of the layer's widths (no padding needed).
void Dense(const KernelLayer& l, const float* x, float* y) {
  VecMap out(y, Ix(l.out));
  out.matrix().noalias() = MatMap(l.weight, Ix(l.out), Ix(l.in)) * ConstVecMap(x, Ix(l.in)).matrix();
  out += ConstVecMap(l.bias, Ix(l.out));
  Activate(l.activation, l.alpha, out);
}

}  // namespace

std::uint32_t ForwardPortable(const ModelView& m, const DataView& d) noexcept {
  const Eigen::Index n_in = Ix(m.input_size), n_out = Ix(m.output_size);
  VecMap obs(d.observation, n_in);
  if (!obs.isFinite().all()) {
    VecMap(d.action, n_out).setConstant(std::nanf(""));
    return kBadObservation;
  }
  VecMap x(d.x, n_in);
  x = ((obs - ConstVecMap(m.obs_mean, n_in)) * ConstVecMap(m.obs_inv_std, n_in)).max(-m.obs_clip).min(m.obs_clip);

  const float* src = d.x;
  float* dst = d.ping;
  for (std::uint32_t li = 0; li < m.layer_count; ++li) {
    const KernelLayer& l = m.layers[li];
    if (l.kind == 0) {
      Dense(l, src, dst);
    } else {
      RecurrentStep(l, src, dst, d, &Dense);
    }
    src = dst;
    dst = (dst == d.ping) ? d.pong : d.ping;
  }

  VecMap a(d.action, n_out);
  a = ConstVecMap(src, n_out);
  if (m.action_head == 1) a = a.tanh();
  a = a * ConstVecMap(m.action_scale, n_out) + ConstVecMap(m.action_offset, n_out);
  std::uint32_t bad = 0;
  for (Eigen::Index i = 0; i < n_out; ++i) {
    if (!std::isfinite(a[i])) {
      a[i] = std::nanf("");
      bad = kBadAction;
    } else {
      a[i] = std::fmin(std::fmax(a[i], m.action_low[i]), m.action_high[i]);
    }
  }
  return bad;
}

}  // namespace pbppo::policy::detail
