// Finite-difference checks, in double, of every hand-written gradient: each layer activation,
// the input gradient, and the full PPO loss (clipped surrogate + entropy + clipped value loss).
#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "policies/trainer/mlp.hpp"
#include "policies/trainer/ppo_loss.hpp"

namespace pbppo::trainer {
namespace {

using Md = Mat<double>;

Md RandomMatrix(int r, int c, Rng& rng, double scale = 1.0) {
  Md m(r, c);
  for (int j = 0; j < c; ++j)
    for (int i = 0; i < r; ++i) m(i, j) = scale * rng.Normal();
  return m;
}

// max |analytic - numeric| / max(1, |numeric|) over all coordinates.
template <typename F>
double CompareToFiniteDifferences(std::vector<double>& x, const std::vector<double>& analytic, F loss) {
  const double h = 1e-6;
  double worst = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double keep = x[i];
    x[i] = keep + h;
    const double up = loss();
    x[i] = keep - h;
    const double down = loss();
    x[i] = keep;
    const double numeric = (up - down) / (2 * h);
    worst = std::max(worst, std::fabs(analytic[i] - numeric) / std::max(1.0, std::fabs(numeric)));
  }
  return worst;
}

TEST_CASE("mlp gradients match finite differences for every activation") {
  for (Activation act : {Activation::kIdentity, Activation::kTanh, Activation::kElu, Activation::kRelu}) {
    for (Activation out_act : {Activation::kIdentity, Activation::kTanh}) {
      CAPTURE(policy::ToString(act));
      CAPTURE(policy::ToString(out_act));
      Mlp<double> net(MlpShape{{4, 6, 5, 3}, act, out_act});
      Rng rng(11);
      std::vector<double> p(net.size());
      for (double& v : p) v = 0.7 * rng.Normal();
      const Md x = RandomMatrix(4, 7, rng);
      const Md c = RandomMatrix(3, 7, rng);
      typename Mlp<double>::Workspace ws;
      auto loss = [&] { return (net.Forward(p.data(), x, ws).array() * c.array()).sum(); };
      loss();
      std::vector<double> g(net.size());
      Md dx;
      net.Backward(p.data(), x, ws, c, g.data(), &dx);
      CHECK(CompareToFiniteDifferences(p, g, loss) < 1e-7);

      // The input gradient.
      Md xv = x;
      std::vector<double> xs(xv.data(), xv.data() + xv.size());
      std::vector<double> dxs(dx.data(), dx.data() + dx.size());
      auto loss_x = [&] {
        const Eigen::Map<const Md> xm(xs.data(), 4, 7);
        return (net.Forward(p.data(), xm, ws).array() * c.array()).sum();
      };
      CHECK(CompareToFiniteDifferences(xs, dxs, loss_x) < 1e-7);
    }
  }
}

TEST_CASE("full PPO loss gradient matches finite differences (policy, log-std, value, entropy)") {
  for (bool clip_values : {false, true}) {
    for (bool normalize : {false, true}) {
      CAPTURE(clip_values);
      CAPTURE(normalize);
      GaussianPolicy<double> pol{Mlp<double>(MlpShape{{3, 8, 8, 2}, Activation::kTanh, Activation::kIdentity}), 2};
      Mlp<double> value(MlpShape{{3, 8, 8, 1}, Activation::kTanh, Activation::kIdentity});
      Rng rng(5);
      std::vector<double> pp(pol.size()), pv(value.size());
      pol.mean.InitOrthogonal(pp.data(), rng, std::sqrt(2.0), 1.0);
      value.InitOrthogonal(pv.data(), rng, std::sqrt(2.0), 1.0);
      pp[pol.log_std_offset()] = -0.3;
      pp[pol.log_std_offset() + 1] = 0.2;
      const int B = 24;
      const Md obs = RandomMatrix(3, B, rng);
      const Md actions = RandomMatrix(2, B, rng);
      std::vector<double> old_logp(B), adv(B), ret(B), old_v(B);
      // Old log-probabilities from perturbed parameters: ratios spread on both sides of the clip.
      {
        std::vector<double> q = pp;
        for (double& v : q) v += 0.15 * rng.Normal();
        typename Mlp<double>::Workspace ws;
        const Md& mu = pol.mean.Forward(q.data(), obs, ws);
        for (int i = 0; i < B; ++i) old_logp[i] = GaussianLogProb(actions, mu, q.data() + pol.log_std_offset(), i);
        typename Mlp<double>::Workspace wv;
        const Md& v = value.Forward(pv.data(), obs, wv);
        for (int i = 0; i < B; ++i) old_v[i] = v(0, i) + 0.4 * rng.Normal();
      }
      for (int i = 0; i < B; ++i) {
        adv[i] = rng.Normal();
        ret[i] = rng.Normal();
      }
      const double eps = 0.1, ent = 0.01, vf = 0.5, cvf = clip_values ? 0.2 : 0.0;
      PolicyWorkspace<double> wsp;
      ValueWorkspace<double> wsv;
      std::vector<double> gp(pol.size()), gv(value.size());
      auto total = [&] {
        std::vector<double> scratch_p(pol.size()), scratch_v(value.size());
        const PolicyLossStats st = PolicyLossAndGrad(pol, pp.data(), obs, actions, old_logp.data(), adv.data(), eps,
                                                     ent, normalize, wsp, scratch_p.data());
        const double lv =
            ValueLossAndGrad(value, pv.data(), obs, ret.data(), old_v.data(), cvf, vf, wsv, scratch_v.data());
        return st.policy_loss - ent * st.entropy + vf * lv;
      };
      const PolicyLossStats st = PolicyLossAndGrad(pol, pp.data(), obs, actions, old_logp.data(), adv.data(), eps, ent,
                                                   normalize, wsp, gp.data());
      ValueLossAndGrad(value, pv.data(), obs, ret.data(), old_v.data(), cvf, vf, wsv, gv.data());
      // The data really exercises both branches of the clip.
      CHECK(st.clip_fraction > 0.1);
      CHECK(st.clip_fraction < 0.9);
      CHECK(CompareToFiniteDifferences(pp, gp, total) < 1e-6);
      CHECK(CompareToFiniteDifferences(pv, gv, total) < 1e-6);
    }
  }
}

TEST_CASE("orthogonal init gives orthonormal rows or columns times the gain") {
  Rng rng(3);
  for (auto [r, c] : {std::pair{64, 3}, std::pair{3, 64}, std::pair{64, 64}, std::pair{1, 64}}) {
    Eigen::MatrixXd w(r, c);
    FillOrthogonal(w.data(), r, c, 2.0, rng);
    const Eigen::MatrixXd g = r >= c ? Eigen::MatrixXd(w.transpose() * w) : Eigen::MatrixXd(w * w.transpose());
    CHECK((g - 4.0 * Eigen::MatrixXd::Identity(g.rows(), g.cols())).cwiseAbs().maxCoeff() < 1e-12);
  }
}

TEST_CASE("Gaussian log-probability and entropy match the closed forms") {
  Md a(1, 1), mu(1, 1);
  a(0, 0) = 1.5;
  mu(0, 0) = 0.5;
  const double log_std = std::log(2.0);
  const double want = -0.5 * 0.25 - std::log(2.0) - 0.5 * std::log(2 * M_PI);
  CHECK(GaussianLogProb(a, mu, &log_std, 0) == doctest::Approx(want).epsilon(1e-14));
  CHECK(GaussianEntropy(&log_std, 1) == doctest::Approx(0.5 * std::log(2 * M_PI * M_E * 4.0)).epsilon(1e-14));
}

}  // namespace
}  // namespace pbppo::trainer
