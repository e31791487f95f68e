// The PPO losses on one minibatch and their exact gradients (hand-written backprop), templated
// on the scalar so the same code is checked against finite differences in double.
//
// Policy: diagonal Gaussian, mean = MLP(obs), state-independent log-std. Its flat parameter
// vector is [mean MLP parameters..., log_std (action size)].
// Loss (stable-baselines3 PPO): L = L_clip + ent_coef * (-mean entropy) + vf_coef * L_value with
//   L_clip  = -mean_i min(r_i A_i, clamp(r_i, 1 - eps, 1 + eps) A_i),  r_i = exp(logp_i - old_i)
//   L_value = mean_i (R_i - v'_i)^2,  v'_i = v_i, or old_v_i + clamp(v_i - old_v_i, -c, c) with
//             value clipping c > 0 (the SB3 form).
// A is normalised per minibatch (NormalizeAdvantages), (A - mean) / (std + 1e-8) with the unbiased
// std, unless --no-adv-norm.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include "policies/trainer/mlp.hpp"

namespace pbppo::trainer {

struct PolicyLossStats {
  double policy_loss = 0;  // L_clip
  double entropy = 0;      // mean entropy of the Gaussian (nats)
  double approx_kl = 0;    // mean((r - 1) - log r)
  double clip_fraction = 0;
};

template <typename S>
struct GaussianPolicy {
  Mlp<S> mean;
  int action_size = 0;
  std::size_t size() const noexcept { return mean.size() + static_cast<std::size_t>(action_size); }
  std::size_t log_std_offset() const noexcept { return mean.size(); }
};

template <typename S>
struct PolicyWorkspace {
  typename Mlp<S>::Workspace net;
  Mat<S> dmean;
};

// A minibatch's advantages, in place: (A - mean) / (std + 1e-8) with the unbiased std (unchanged
// below two samples).
template <typename S>
void NormalizeAdvantages(Vec<S>& adv) {
  const Eigen::Index n = adv.size();
  if (n < 2) return;
  const S m = adv.mean();
  const S var = (adv.array() - m).square().sum() / static_cast<S>(n - 1);
  adv = (adv.array() - m) / (std::sqrt(var) + static_cast<S>(1e-8));
}

// log N(a; mu, diag(exp(log_std))^2) per column.
template <typename S, typename DA, typename DM>
S GaussianLogProb(const Eigen::MatrixBase<DA>& a, const Eigen::MatrixBase<DM>& mu, const S* log_std, int col) {
  const S half_log_2pi = static_cast<S>(0.5 * std::log(2.0 * std::numbers::pi));
  S lp = 0;
  for (int j = 0; j < a.rows(); ++j) {
    const S z = (a(j, col) - mu(j, col)) * std::exp(-log_std[j]);
    lp += S(-0.5) * z * z - log_std[j] - half_log_2pi;
  }
  return lp;
}

template <typename S>
S GaussianEntropy(const S* log_std, int n) {
  const S c = static_cast<S>(0.5 + 0.5 * std::log(2.0 * std::numbers::pi));
  S h = 0;
  for (int j = 0; j < n; ++j) h += log_std[j] + c;
  return h;
}

// Policy part of the loss, L_clip + ent_coef * (-entropy), and its gradient into `grad`
// (policy.size() elements, overwritten), for the advantages as given (normalised beforehand over the
// whole minibatch, if at all). mean_over: the number of samples the means are taken over, 0 for
// these columns; a chunk of a larger minibatch passes the minibatch's size, so that the chunks'
// gradients and statistics add up to the minibatch's, and only one chunk passes the entropy
// coefficient.
template <typename S, typename DO, typename DA>
PolicyLossStats PolicyLossAndGrad(const GaussianPolicy<S>& pol, const S* p, const Eigen::MatrixBase<DO>& obs,
                                  const Eigen::MatrixBase<DA>& actions, const S* old_logp, const S* advantages,
                                  double clip_eps, double ent_coef, PolicyWorkspace<S>& ws, S* grad,
                                  int mean_over = 0) {
  const int B = static_cast<int>(obs.cols());
  const int M = mean_over > 0 ? mean_over : B;
  const int A = pol.action_size;
  const S* log_std = p + pol.log_std_offset();
  const Mat<S>& mu = pol.mean.Forward(p, obs, ws.net);

  const S eps = static_cast<S>(clip_eps);
  const S inv_b = S(1) / static_cast<S>(M);
  S* g_log_std = grad + pol.log_std_offset();
  for (int j = 0; j < A; ++j) g_log_std[j] = 0;
  ws.dmean.resize(A, B);
  double loss = 0, kl = 0, clipped = 0;
  for (int i = 0; i < B; ++i) {
    S lp = 0;
    for (int j = 0; j < A; ++j) {
      const S z = (actions(j, i) - mu(j, i)) * std::exp(-log_std[j]);
      lp += S(-0.5) * z * z - log_std[j];
    }
    lp -= static_cast<S>(A) * static_cast<S>(0.5 * std::log(2.0 * std::numbers::pi));
    const S log_ratio = lp - old_logp[i];
    const S r = std::exp(log_ratio);
    const S adv = advantages[i];
    const S u1 = r * adv;
    const S u2 = std::clamp(r, S(1) - eps, S(1) + eps) * adv;
    loss -= static_cast<double>(std::min(u1, u2));
    kl += static_cast<double>((r - S(1)) - log_ratio);
    if (std::fabs(r - S(1)) > eps) clipped += 1;
    // d L_clip / d logp_i: the unclipped branch carries -r A / B, the clipped one nothing.
    const S g = u1 <= u2 ? -u1 * inv_b : S(0);
    for (int j = 0; j < A; ++j) {
      const S inv_std = std::exp(-log_std[j]);
      const S z = (actions(j, i) - mu(j, i)) * inv_std;
      ws.dmean(j, i) = g * z * inv_std;
      g_log_std[j] += g * (z * z - S(1));
    }
  }
  for (int j = 0; j < A; ++j) g_log_std[j] -= static_cast<S>(ent_coef);
  pol.mean.Backward(p, obs, ws.net, ws.dmean, grad);

  PolicyLossStats st;
  st.policy_loss = loss / M;
  st.entropy = static_cast<double>(GaussianEntropy(log_std, A));
  st.approx_kl = kl / M;
  st.clip_fraction = clipped / M;
  return st;
}

// The KL divergence of the current policy (means `mu`, log-std `log_std`) from the one that
// collected the rollout (`old_mu`, `old_log_std`), as rsl_rl computes it for its adaptive learning
// rate: per column, sum over the actions of log(std / old_std + 1e-5) + (old_std^2 + (old_mu -
// mu)^2) / (2 std^2) - 1/2; returned summed over the columns (in double, in column order).
template <typename S, typename DM, typename DO>
double SumGaussianKl(const Eigen::MatrixBase<DM>& mu, const S* log_std, const Eigen::MatrixBase<DO>& old_mu,
                     const S* old_log_std) {
  double sum = 0;
  for (Eigen::Index i = 0; i < mu.cols(); ++i) {
    S kl = 0;
    for (Eigen::Index j = 0; j < mu.rows(); ++j) {
      const S std = std::exp(log_std[j]), old_std = std::exp(old_log_std[j]);
      const S d = old_mu(j, i) - mu(j, i);
      kl += std::log(std / old_std + static_cast<S>(1e-5)) + (old_std * old_std + d * d) / (S(2) * std * std) -
            static_cast<S>(0.5);
    }
    sum += static_cast<double>(kl);
  }
  return sum;
}

template <typename S>
struct ValueWorkspace {
  typename Mlp<S>::Workspace net;
  Mat<S> dv;
};

// vf_coef * L_value and its gradient into `grad` (value.size() elements, overwritten). Returns
// L_value (without the coefficient). mean_over: as PolicyLossAndGrad's.
template <typename S, typename DO>
double ValueLossAndGrad(const Mlp<S>& value, const S* p, const Eigen::MatrixBase<DO>& obs, const S* returns,
                        const S* old_values, double clip_vf, double vf_coef, ValueWorkspace<S>& ws, S* grad,
                        int mean_over = 0) {
  const int B = static_cast<int>(obs.cols());
  const int M = mean_over > 0 ? mean_over : B;
  const Mat<S>& v = value.Forward(p, obs, ws.net);
  ws.dv.resize(1, B);
  const S c = static_cast<S>(clip_vf);
  const S k = static_cast<S>(2.0 * vf_coef / M);
  double loss = 0;
  for (int i = 0; i < B; ++i) {
    S pred = v(0, i);
    S pass = 1;
    if (clip_vf > 0) {
      const S diff = v(0, i) - old_values[i];
      if (diff > c || diff < -c) pass = 0;
      pred = old_values[i] + std::clamp(diff, -c, c);
    }
    const S e = pred - returns[i];
    loss += static_cast<double>(e * e);
    ws.dv(0, i) = k * e * pass;
  }
  value.Backward(p, obs, ws.net, ws.dv, grad);
  return loss / M;
}

}  // namespace pbppo::trainer
