// Adam exactly as torch.optim.Adam computes it (bias corrections, eps added after the square
// root of the corrected second moment), over one flat parameter vector.
#pragma once

#include <cmath>
#include <cstddef>

#include "policies/trainer/mlp.hpp"
#include "policies/trainer/state_io.hpp"

namespace pbppo::trainer {

template <typename S>
class Adam {
 public:
  Adam() = default;
  explicit Adam(std::size_t n, double eps = 1e-5, double beta1 = 0.9, double beta2 = 0.999)
      : m_(Vec<S>::Zero(static_cast<Eigen::Index>(n))),
        v_(Vec<S>::Zero(static_cast<Eigen::Index>(n))),
        eps_(eps),
        b1_(beta1),
        b2_(beta2) {}

  // One step in parts: Advance() once, then Apply() over ranges of the parameters that together
  // cover them all (element by element the same arithmetic in any split). p -= lr * the
  // bias-corrected update for gradient `g` multiplied by `grad_scale` (the clip factor).
  void Advance() noexcept { ++t_; }
  void Apply(S* p, const S* g, double lr, S grad_scale, Eigen::Index begin, Eigen::Index end) {
    const Eigen::Index n = end - begin;
    auto m = m_.segment(begin, n);
    auto v = v_.segment(begin, n);
    Eigen::Map<Vec<S>> pv(p + begin, n);
    Eigen::Map<const Vec<S>> gv(g + begin, n);
    const S b1 = static_cast<S>(b1_), b2 = static_cast<S>(b2_);
    m = b1 * m + (S(1) - b1) * (gv * grad_scale);
    v = b2 * v + ((S(1) - b2) * grad_scale * grad_scale) * gv.cwiseAbs2();
    const double bc1 = 1.0 - std::pow(b1_, static_cast<double>(t_));
    const double bc2 = 1.0 - std::pow(b2_, static_cast<double>(t_));
    const S step = static_cast<S>(lr / bc1);
    const S inv_sqrt_bc2 = static_cast<S>(1.0 / std::sqrt(bc2));
    const S eps = static_cast<S>(eps_);
    pv.array() -= step * m.array() / (v.array().sqrt() * inv_sqrt_bc2 + eps);
  }

  // Its moments and step count (a resumed run's).
  void Save(ByteWriter& w) const {
    w.PutMatrix(m_);
    w.PutMatrix(v_);
    w.Put(t_);
  }
  void Load(ByteReader& r) {
    r.GetMatrix(m_, "Adam's first moments");
    r.GetMatrix(v_, "Adam's second moments");
    t_ = r.Get<long>("Adam's step count");
  }

 private:
  Vec<S> m_, v_;
  double eps_ = 1e-5, b1_ = 0.9, b2_ = 0.999;
  long t_ = 0;
};

}  // namespace pbppo::trainer
