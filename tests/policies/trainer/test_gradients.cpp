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

// A Gaussian policy (log-std -0.3, 0.2, 0.7, ...) and a value network, orthogonal weights from `rng`.
struct Nets {
  GaussianPolicy<double> pol;
  Mlp<double> value;
  std::vector<double> pp, pv;
};
Nets MakeNets(const std::vector<int>& policy_widths, const std::vector<int>& value_widths, Activation act, Rng& rng) {
  Nets n{{Mlp<double>(MlpShape{policy_widths, act, Activation::kIdentity}), policy_widths.back()},
         Mlp<double>(MlpShape{value_widths, act, Activation::kIdentity}),
         {},
         {}};
  n.pp.resize(n.pol.size());
  n.pv.resize(n.value.size());
  n.pol.mean.InitOrthogonal(n.pp.data(), rng, std::sqrt(2.0), 1.0);
  n.value.InitOrthogonal(n.pv.data(), rng, std::sqrt(2.0), 1.0);
  for (int j = 0; j < n.pol.action_size; ++j)
    n.pp[n.pol.log_std_offset() + static_cast<std::size_t>(j)] = -0.3 + 0.5 * j;
  return n;
}

TEST_CASE("full PPO loss gradient matches finite differences (policy, log-std, value, entropy)") {
  for (bool clip_values : {false, true}) {
    for (bool normalize : {false, true}) {
      CAPTURE(clip_values);
      CAPTURE(normalize);
      Rng rng(5);
      Nets nets = MakeNets({3, 8, 8, 2}, {3, 8, 8, 1}, Activation::kTanh, rng);
      const GaussianPolicy<double>& pol = nets.pol;
      const Mlp<double>& value = nets.value;
      std::vector<double>&pp = nets.pp, &pv = nets.pv;
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
      if (normalize) {  // as the update does before the loss
        Vec<double> a = Eigen::Map<const Vec<double>>(adv.data(), B);
        NormalizeAdvantages(a);
        adv.assign(a.data(), a.data() + B);
      }
      const double eps = 0.1, ent = 0.01, vf = 0.5, cvf = clip_values ? 0.2 : 0.0;
      PolicyWorkspace<double> wsp;
      ValueWorkspace<double> wsv;
      std::vector<double> gp(pol.size()), gv(value.size());
      auto total = [&] {
        std::vector<double> scratch_p(pol.size()), scratch_v(value.size());
        const PolicyLossStats st = PolicyLossAndGrad(pol, pp.data(), obs, actions, old_logp.data(), adv.data(), eps,
                                                     ent, wsp, scratch_p.data());
        const double lv =
            ValueLossAndGrad(value, pv.data(), obs, ret.data(), old_v.data(), cvf, vf, wsv, scratch_v.data());
        return st.policy_loss - ent * st.entropy + vf * lv;
      };
      const PolicyLossStats st =
          PolicyLossAndGrad(pol, pp.data(), obs, actions, old_logp.data(), adv.data(), eps, ent, wsp, gp.data());
      ValueLossAndGrad(value, pv.data(), obs, ret.data(), old_v.data(), cvf, vf, wsv, gv.data());
      // The data really exercises both branches of the clip.
      CHECK(st.clip_fraction > 0.1);
      CHECK(st.clip_fraction < 0.9);
      CHECK(CompareToFiniteDifferences(pp, gp, total) < 1e-6);
      CHECK(CompareToFiniteDifferences(pv, gv, total) < 1e-6);
    }
  }
}

TEST_CASE("chunks of a minibatch: their gradients and statistics add up to the whole minibatch's") {
  // The update's chunks: each chunk's loss averaged over the whole minibatch (mean_over),
  // advantages normalised over the minibatch beforehand, the entropy term in one chunk only.
  Rng rng(17);
  const Nets nets = MakeNets({5, 16, 8, 3}, {7, 16, 8, 1}, Activation::kElu, rng);
  const GaussianPolicy<double>& pol = nets.pol;
  const Mlp<double>& value = nets.value;
  const std::vector<double>&pp = nets.pp, &pv = nets.pv;
  const int n = 37;  // not a multiple of the 4 chunks
  const Md obs = RandomMatrix(5, n, rng), critic_obs = RandomMatrix(7, n, rng), actions = RandomMatrix(3, n, rng);
  std::vector<double> old_logp(n), adv(n), ret(n), old_v(n);
  for (int i = 0; i < n; ++i) {
    old_logp[i] = -3.0 + 0.5 * rng.Normal();
    adv[i] = 2.0 + rng.Normal();
    ret[i] = rng.Normal();
    old_v[i] = ret[i] + 0.3 * rng.Normal();
  }
  const double eps = 0.2, ent = 0.01, vf = 0.5, cvf = 0.2;
  PolicyWorkspace<double> wsp;
  ValueWorkspace<double> wsv;
  std::vector<double> gp(pol.size()), gv(value.size());
  Vec<double> whole_adv = Eigen::Map<const Vec<double>>(adv.data(), n);
  NormalizeAdvantages(whole_adv);
  const PolicyLossStats whole =
      PolicyLossAndGrad(pol, pp.data(), obs, actions, old_logp.data(), whole_adv.data(), eps, ent, wsp, gp.data());
  const double whole_v =
      ValueLossAndGrad(value, pv.data(), critic_obs, ret.data(), old_v.data(), cvf, vf, wsv, gv.data());

  Eigen::Map<Vec<double>> a(adv.data(), n);
  const double m = a.mean();
  const double sd = std::sqrt((a.array() - m).square().sum() / (n - 1));
  std::vector<double> norm(n);
  for (int i = 0; i < n; ++i) norm[i] = (adv[i] - m) / (sd + 1e-8);
  std::vector<double> sum_p(pol.size(), 0.0), sum_v(value.size(), 0.0), cp(pol.size()), cv(value.size());
  double loss = 0, kl = 0, clip = 0, vloss = 0;
  for (int c = 0; c < 4; ++c) {
    const int c0 = n * c / 4, nc = n * (c + 1) / 4 - c0;
    const PolicyLossStats st =
        PolicyLossAndGrad(pol, pp.data(), obs.middleCols(c0, nc), actions.middleCols(c0, nc), old_logp.data() + c0,
                          norm.data() + c0, eps, c == 0 ? ent : 0.0, wsp, cp.data(), n);
    vloss += ValueLossAndGrad(value, pv.data(), critic_obs.middleCols(c0, nc), ret.data() + c0, old_v.data() + c0, cvf,
                              vf, wsv, cv.data(), n);
    loss += st.policy_loss;
    kl += st.approx_kl;
    clip += st.clip_fraction;
    for (std::size_t k = 0; k < cp.size(); ++k) sum_p[k] += cp[k];
    for (std::size_t k = 0; k < cv.size(); ++k) sum_v[k] += cv[k];
  }
  CHECK(loss == doctest::Approx(whole.policy_loss).epsilon(1e-12));
  CHECK(kl == doctest::Approx(whole.approx_kl).epsilon(1e-12));
  CHECK(clip == doctest::Approx(whole.clip_fraction).epsilon(1e-12));
  CHECK(vloss == doctest::Approx(whole_v).epsilon(1e-12));
  double worst = 0;
  for (std::size_t k = 0; k < gp.size(); ++k) worst = std::max(worst, std::fabs(sum_p[k] - gp[k]));
  for (std::size_t k = 0; k < gv.size(); ++k) worst = std::max(worst, std::fabs(sum_v[k] - gv[k]));
  CHECK(worst < 1e-12);
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

TEST_CASE("the trainer's MLP refuses leaky_relu (a blob and runtime activation only)") {
  CHECK_THROWS_AS(Mlp<double>(MlpShape{{3, 4, 2}, Activation::kLeakyRelu, Activation::kIdentity}),
                  std::invalid_argument);
  CHECK_THROWS_AS(Mlp<float>(MlpShape{{3, 4, 2}, Activation::kTanh, Activation::kLeakyRelu}), std::invalid_argument);
}

}  // namespace
}  // namespace pbppo::trainer
