#include "policies/trainer/ppo.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "policies/trainer/gae.hpp"
#include "policies/trainer/seed.hpp"

namespace pbppo::trainer {
namespace {

// In a fixed order (eight interleaved partial sums), independent of alignment and vector width.
double SquaredNorm(const float* x, Eigen::Index n) {
  double acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  const Eigen::Index n8 = n - n % 8;
  for (Eigen::Index i = 0; i < n8; i += 8)
    for (int k = 0; k < 8; ++k) acc[k] += static_cast<double>(x[i + k]) * static_cast<double>(x[i + k]);
  for (Eigen::Index i = n8; i < n; ++i) acc[0] += static_cast<double>(x[i]) * static_cast<double>(x[i]);
  return ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
}

double SquaredNorm(const Vec<float>& v) {
  return SquaredNorm(v.data(), v.size());
}

// The update's statistics are summed over minibatches, then averaged.
void AddPolicyStats(UpdateStats& sum, const PolicyLossStats& ps, bool with_entropy = true) {
  sum.policy_loss += ps.policy_loss;
  if (with_entropy) sum.entropy += ps.entropy;
  sum.approx_kl += ps.approx_kl;
  sum.clip_fraction += ps.clip_fraction;
}

UpdateStats MeanOver(UpdateStats sum, long minibatches) {
  const double m = static_cast<double>(minibatches);
  for (double* x :
       {&sum.policy_loss, &sum.entropy, &sum.approx_kl, &sum.clip_fraction, &sum.value_loss, &sum.grad_norm, &sum.kl})
    *x /= m;
  return sum;
}

std::vector<int> Widths(int in, const std::vector<int>& hidden, int out) {
  std::vector<int> w{in};
  w.insert(w.end(), hidden.begin(), hidden.end());
  w.push_back(out);
  return w;
}

}  // namespace

void PinEigenBlocking() {
  Eigen::setCpuCacheSizes(kEigenCacheSizes[0], kEigenCacheSizes[1], kEigenCacheSizes[2]);
}

Ppo::Ppo(const TrainOptions& o, int obs_size, int value_input_size, int action_size)
    : o_(o),
      actor_{Mlp<float>(
                 MlpShape{Widths(obs_size, o.policy_hidden, action_size), o.activation, policy::Activation::kIdentity}),
             action_size},
      critic_(MlpShape{Widths(value_input_size, o.critic_hidden(), 1), o.activation, policy::Activation::kIdentity}),
      lr_(o.learning_rate),
      rng_(Mix(o.seed, 0)) {
  PinEigenBlocking();
  actor_params_ = Vec<float>::Zero(static_cast<Eigen::Index>(actor_.size()));
  critic_params_ = Vec<float>::Zero(static_cast<Eigen::Index>(critic_.size()));
  actor_grad_ = Vec<float>::Zero(static_cast<Eigen::Index>(actor_.size()));
  critic_grad_ = Vec<float>::Zero(static_cast<Eigen::Index>(critic_.size()));
  Rng init(Mix(o.seed, 1));
  actor_.mean.InitOrthogonal(actor_params_.data(), init, std::sqrt(2.0), 0.01);
  critic_.InitOrthogonal(critic_params_.data(), init, std::sqrt(2.0), 1.0);
  for (int j = 0; j < action_size; ++j)
    actor_params_[static_cast<Eigen::Index>(actor_.log_std_offset()) + j] = static_cast<float>(o.log_std_init);
  actor_adam_ = Adam<float>(static_cast<std::size_t>(actor_params_.size()), 1e-5);
  critic_adam_ = Adam<float>(static_cast<std::size_t>(critic_params_.size()), 1e-5);
}

void Ppo::ComputeReturns(RolloutStorage& r, WorkerPool& pool) const {
  const long B = r.size();
  const long chunk = 256;
  const long chunks = (B + chunk - 1) / chunk;
  std::vector<long> trunc_idx;
  for (long i = 0; i < B; ++i)
    if (r.truncated[static_cast<std::size_t>(i)]) trunc_idx.push_back(i);
  const Mat<float>& in = r.value_inputs();
  pool.Run([&](int w) {
    typename Mlp<float>::Workspace ws;
    for (long k = w; k < chunks; k += pool.size()) {
      const long c0 = k * chunk, n = std::min(chunk, B - c0);
      const Mat<float>& v = critic_.Forward(critic_params_.data(), in.middleCols(c0, n), ws);
      std::copy(v.data(), v.data() + n, r.values.data() + c0);
    }
    if (w == 0) {
      const Mat<float>& v = critic_.Forward(critic_params_.data(), r.last_value_inputs, ws);
      std::copy(v.data(), v.data() + r.envs, r.last_values.data());
      for (std::size_t k = 0; k < trunc_idx.size(); ++k) {
        const Mat<float>& vt = critic_.Forward(critic_params_.data(), r.truncation_value_inputs.col(trunc_idx[k]), ws);
        r.truncation_values[static_cast<std::size_t>(trunc_idx[k])] = vt(0, 0);
      }
    }
  });
  GaeInput gae{r.steps,
               r.envs,
               r.rewards.data(),
               r.values.data(),
               r.terminated.data(),
               r.truncated.data(),
               r.truncation_values.data(),
               r.last_values.data()};
  ComputeGae(gae, o_.gamma, o_.gae_lambda, r.advantages.data(), r.returns.data());
}

double Ppo::ExplainedVariance(const RolloutStorage& r) {
  const std::vector<float>& ret = r.returns;
  const std::vector<float>& val = r.values;
  double mr = 0, mv = 0;
  const auto n = static_cast<double>(ret.size());
  for (std::size_t i = 0; i < ret.size(); ++i) {
    mr += ret[i];
    mv += ret[i] - val[i];
  }
  mr /= n;
  mv /= n;
  double vr = 0, vd = 0;
  for (std::size_t i = 0; i < ret.size(); ++i) {
    vr += (ret[i] - mr) * (ret[i] - mr);
    const double dd = ret[i] - val[i] - mv;
    vd += dd * dd;
  }
  return vr > 0 ? 1.0 - vd / vr : std::numeric_limits<double>::quiet_NaN();
}

UpdateStats Ppo::Update(const RolloutStorage& r, double eps, bool critic_only, WorkerPool& pool) {
  Minibatches m;
  const long B = r.size();
  m.size = std::min<long>(o_.minibatch, B);
  m.per_epoch = (B + m.size - 1) / m.size;
  m.total = m.per_epoch * o_.epochs;
  m.perms.resize(static_cast<std::size_t>(o_.epochs));
  for (auto& p : m.perms) {
    p.resize(static_cast<std::size_t>(B));
    for (long i = 0; i < B; ++i) p[static_cast<std::size_t>(i)] = i;
    for (long i = B - 1; i > 0; --i)
      std::swap(p[static_cast<std::size_t>(i)],
                p[static_cast<std::size_t>(rng_.Below(static_cast<std::uint64_t>(i + 1)))]);
  }
  UpdateStats st = m.size >= o_.chunked_minibatch ? UpdateChunked(r, m, eps, critic_only, pool)
                                                  : UpdateSplit(r, m, eps, critic_only, pool);
  double ls = 0;
  for (int j = 0; j < r.action_size; ++j) ls += actor_params_[static_cast<Eigen::Index>(actor_.log_std_offset()) + j];
  st.log_std_mean = ls / r.action_size;
  return st;
}

UpdateStats Ppo::UpdateSplit(const RolloutStorage& r, const Minibatches& mbs, double eps, bool critic_only,
                             WorkerPool& pool) {
  const long B = r.size(), mb = mbs.size, per_epoch = mbs.per_epoch, total = mbs.total;
  const auto& perms = mbs.perms;
  const int d = r.obs_size, a = r.action_size, vd = r.value_input_size();
  const Mat<float>& value_in = r.value_inputs();
  // Squared gradient norms per minibatch, [policy, value] in two slots alternating by parity.
  double sq[2][2] = {{0, 0}, {0, 0}};
  // Each minibatch's learning rate, in the same alternating slots: the policy thread adapts it
  // before the barrier and the value thread reads its minibatch's slot after it, so neither reads
  // a rate the other is writing.
  double step_lr[2] = {lr_, lr_};
  UpdateStats sum;
  // A held policy (--critic-warmup) has KL 0 from the rollout's: adapting to it would raise the rate
  // to its ceiling before the policy's first step, so the rate waits for the policy.
  const bool adaptive = o_.lr_schedule.kind == LrSchedule::Kind::kAdaptive && !critic_only;
  // With two threads or more the policy's and the value network's halves of each minibatch run side
  // by side, meeting before the shared gradient clip.
  const bool split = pool.size() >= 2;
  SpinBarrier sync(split ? 2 : 1);

  auto clip_scale = [&](long k) {
    const double n = std::sqrt(sq[k & 1][0] + sq[k & 1][1]);
    return std::pair<double, float>(
        n, o_.max_grad_norm > 0 && n > 0 ? static_cast<float>(std::min(1.0, o_.max_grad_norm / (n + 1e-6))) : 1.f);
  };
  // Minibatch k's value-network columns: its inputs, returns and the values the rollout had.
  auto gather_value = [&](long k, Mat<float>& v_in, std::vector<float>& rt, std::vector<float>& ov) {
    const auto& p = perms[static_cast<std::size_t>(k / per_epoch)];
    const long s0 = (k % per_epoch) * mb, n = std::min(mb, B - s0);
    v_in.resize(vd, n);
    for (long j = 0; j < n; ++j) {
      const long i = p[static_cast<std::size_t>(s0 + j)];
      v_in.col(j) = value_in.col(i);
      rt[static_cast<std::size_t>(j)] = r.returns[static_cast<std::size_t>(i)];
      ov[static_cast<std::size_t>(j)] = r.values[static_cast<std::size_t>(i)];
    }
  };
  auto value_step = [&](long k, Mat<float>& v_in, std::vector<float>& rt, std::vector<float>& ov,
                        ValueWorkspace<float>& wsv) {
    sum.value_loss += ValueLossAndGrad(critic_, critic_params_.data(), v_in, rt.data(), ov.data(), o_.clip_vf,
                                       o_.vf_coef, wsv, critic_grad_.data());
    sq[k & 1][1] = SquaredNorm(critic_grad_);
  };
  auto policy_loop = [&](bool sequential_value, PolicyWorkspace<float>& wsp, ValueWorkspace<float>& wsv) {
    Mat<float> o(d, mb), act(a, mb), old_mu(a, mb), v_in(vd, mb);
    std::vector<float> lp(static_cast<std::size_t>(mb)), ad(static_cast<std::size_t>(mb)),
        rt(static_cast<std::size_t>(mb)), ov(static_cast<std::size_t>(mb));
    for (long k = 0; k < total; ++k) {
      const auto& p = perms[static_cast<std::size_t>(k / per_epoch)];
      const long s0 = (k % per_epoch) * mb, n = std::min(mb, B - s0);
      o.resize(d, n);
      act.resize(a, n);
      old_mu.resize(a, n);
      for (long j = 0; j < n; ++j) {
        const long i = p[static_cast<std::size_t>(s0 + j)];
        o.col(j) = r.obs.col(i);
        act.col(j) = r.actions.col(i);
        old_mu.col(j) = r.action_mean.col(i);
        lp[static_cast<std::size_t>(j)] = r.log_prob[static_cast<std::size_t>(i)];
        ad[static_cast<std::size_t>(j)] = r.advantages[static_cast<std::size_t>(i)];
      }
      const PolicyLossStats ps = PolicyLossAndGrad(actor_, actor_params_.data(), o, act, lp.data(), ad.data(), eps,
                                                   o_.ent_coef, o_.normalize_advantages, wsp, actor_grad_.data());
      AddPolicyStats(sum, ps);
      // The KL divergence from the rollout's policy, before this minibatch's step; the adaptive
      // schedule sets the step's rate from it (the value thread reads it after the barrier).
      const double mb_kl =
          SumGaussianKl(wsp.net.y.back(), log_std(), old_mu, r.log_std.data()) / static_cast<double>(n);
      sum.kl += mb_kl;
      if (adaptive) lr_ = o_.lr_schedule.Adapt(lr_, mb_kl);
      step_lr[k & 1] = lr_;
      sq[k & 1][0] = critic_only ? 0.0 : SquaredNorm(actor_grad_);  // a held actor takes no part in the clip
      if (sequential_value) {
        gather_value(k, v_in, rt, ov);
        value_step(k, v_in, rt, ov, wsv);
      } else {
        sync.ArriveAndWait();
      }
      const auto [norm, scale] = clip_scale(k);
      sum.grad_norm += norm;
      if (!critic_only) actor_adam_.Step(actor_params_.data(), actor_grad_.data(), lr_, scale);
      if (sequential_value) critic_adam_.Step(critic_params_.data(), critic_grad_.data(), lr_, scale);
    }
  };
  auto value_loop = [&](ValueWorkspace<float>& wsv) {
    Mat<float> v_in(vd, mb);
    std::vector<float> rt(static_cast<std::size_t>(mb)), ov(static_cast<std::size_t>(mb));
    for (long k = 0; k < total; ++k) {
      gather_value(k, v_in, rt, ov);
      value_step(k, v_in, rt, ov, wsv);
      sync.ArriveAndWait();
      critic_adam_.Step(critic_params_.data(), critic_grad_.data(), step_lr[k & 1], clip_scale(k).second);
    }
  };
  PolicyWorkspace<float> wsp;
  ValueWorkspace<float> wsv;
  if (split) {
    pool.Run([&](int w) {
      if (w == 0) policy_loop(false, wsp, wsv);
      if (w == 1) value_loop(wsv);
    });
  } else {
    policy_loop(true, wsp, wsv);
  }
  return MeanOver(sum, total);
}

UpdateStats Ppo::UpdateChunked(const RolloutStorage& r, const Minibatches& mbs, double eps, bool critic_only,
                               WorkerPool& pool) {
  const long B = r.size();
  const int W = pool.size(), K = kChunks, S = kSegments;
  const int d = r.obs_size, a = r.action_size, vd = r.value_input_size();
  const Eigen::Index P = actor_params_.size(), V = critic_params_.size();
  const Mat<float>& value_in = r.value_inputs();
  // A held policy (--critic-warmup) has KL 0 from the rollout's: adapting to it would raise the rate
  // to its ceiling before the policy's first step, so the rate waits for the policy.
  const bool adaptive = o_.lr_schedule.kind == LrSchedule::Kind::kAdaptive && !critic_only;
  std::vector<Vec<float>> actor_grads(static_cast<std::size_t>(K), Vec<float>::Zero(P));
  std::vector<Vec<float>> critic_grads(static_cast<std::size_t>(K), Vec<float>::Zero(V));
  struct ChunkStats {
    PolicyLossStats policy;
    double value_loss = 0, gaussian_kl = 0;
  };
  std::vector<ChunkStats> chunk(static_cast<std::size_t>(K));
  std::vector<double> seg_sq(static_cast<std::size_t>(2 * S), 0.0);  // actor segments, then critic's
  UpdateStats sum;
  double lr_end = lr_;
  SpinBarrier sync(W);
  auto segment = [](Eigen::Index n, int s, int count) {
    return std::pair<Eigen::Index, Eigen::Index>(n * s / count, n * (s + 1) / count);
  };

  pool.Run([&](int w) {
    Mat<float> o(d, 0), act(a, 0), old_mu(a, 0), v_in(vd, 0);
    Vec<float> adv;
    std::vector<float> lp, rt, ov;
    PolicyWorkspace<float> wsp;
    ValueWorkspace<float> wsv;
    double lr = lr_;  // every thread follows the same rate
    for (long k = 0; k < mbs.total; ++k) {
      const auto& p = mbs.perms[static_cast<std::size_t>(k / mbs.per_epoch)];
      const long s0 = (k % mbs.per_epoch) * mbs.size, n = std::min(mbs.size, B - s0);
      // The minibatch's advantages, normalised over the whole minibatch (each thread the same).
      adv.resize(n);
      for (long j = 0; j < n; ++j) adv[j] = r.advantages[static_cast<std::size_t>(p[static_cast<std::size_t>(s0 + j)])];
      if (o_.normalize_advantages && n > 1) {
        const float m = adv.mean();
        const float var = (adv.array() - m).square().sum() / static_cast<float>(n - 1);
        adv = (adv.array() - m) / (std::sqrt(var) + 1e-8f);
      }
      // 1. Each chunk's gradient of the minibatch's mean loss.
      for (int c = w; c < K; c += W) {
        const long c0 = n * c / K, nc = n * (c + 1) / K - c0;
        o.resize(d, nc);
        act.resize(a, nc);
        old_mu.resize(a, nc);
        v_in.resize(vd, nc);
        lp.resize(static_cast<std::size_t>(nc));
        rt.resize(static_cast<std::size_t>(nc));
        ov.resize(static_cast<std::size_t>(nc));
        for (long j = 0; j < nc; ++j) {
          const long i = p[static_cast<std::size_t>(s0 + c0 + j)];
          const auto u = static_cast<std::size_t>(i), uj = static_cast<std::size_t>(j);
          o.col(j) = r.obs.col(i);
          act.col(j) = r.actions.col(i);
          old_mu.col(j) = r.action_mean.col(i);
          v_in.col(j) = value_in.col(i);
          lp[uj] = r.log_prob[u];
          rt[uj] = r.returns[u];
          ov[uj] = r.values[u];
        }
        ChunkStats& cs = chunk[static_cast<std::size_t>(c)];
        cs.policy = PolicyLossAndGrad(actor_, actor_params_.data(), o, act, lp.data(), adv.data() + c0, eps,
                                      c == 0 ? o_.ent_coef : 0.0, false, wsp,
                                      actor_grads[static_cast<std::size_t>(c)].data(), static_cast<int>(n));
        cs.gaussian_kl = SumGaussianKl(wsp.net.y.back(), log_std(), old_mu, r.log_std.data());
        cs.value_loss =
            ValueLossAndGrad(critic_, critic_params_.data(), v_in, rt.data(), ov.data(), o_.clip_vf, o_.vf_coef, wsv,
                             critic_grads[static_cast<std::size_t>(c)].data(), static_cast<int>(n));
      }
      sync.ArriveAndWait();
      // 2. The minibatch's gradient: the chunks' summed in chunk order, segment by segment, with each
      // segment's squared norm.
      for (int sg = w; sg < 2 * S; sg += W) {
        const bool actor = sg < S;
        const auto [b, e] = segment(actor ? P : V, actor ? sg : sg - S, S);
        auto& grads = actor ? actor_grads : critic_grads;
        auto total = (actor ? actor_grad_ : critic_grad_).segment(b, e - b);
        total = grads[0].segment(b, e - b);
        for (int c = 1; c < K; ++c) total += grads[static_cast<std::size_t>(c)].segment(b, e - b);
        seg_sq[static_cast<std::size_t>(sg)] = actor && critic_only ? 0.0 : SquaredNorm(total.data(), e - b);
      }
      if (w == 0) {
        if (!critic_only) actor_adam_.Advance();
        critic_adam_.Advance();
      }
      sync.ArriveAndWait();
      // 3. Every thread: the norm, the clip factor, the rate; then the Adam steps of its segments.
      double sq = 0, kl_sum = 0;
      for (double x : seg_sq) sq += x;
      for (const ChunkStats& cs : chunk) kl_sum += cs.gaussian_kl;
      const double mb_kl = kl_sum / static_cast<double>(n);
      if (adaptive) lr = o_.lr_schedule.Adapt(lr, mb_kl);
      const double norm = std::sqrt(sq);
      const float scale =
          o_.max_grad_norm > 0 && norm > 0 ? static_cast<float>(std::min(1.0, o_.max_grad_norm / (norm + 1e-6))) : 1.f;
      if (w == 0) {
        for (const ChunkStats& cs : chunk) {
          AddPolicyStats(sum, cs.policy, &cs == &chunk[0]);  // the entropy: the actor's, once
          sum.value_loss += cs.value_loss;
        }
        sum.grad_norm += norm;
        sum.kl += mb_kl;
        lr_end = lr;
      }
      for (int sg = w; sg < 2 * S; sg += W) {
        const bool actor = sg < S;
        if (actor && critic_only) continue;
        const auto [b, e] = segment(actor ? P : V, actor ? sg : sg - S, S);
        if (actor) {
          actor_adam_.Apply(actor_params_.data(), actor_grad_.data(), lr, scale, b, e);
        } else {
          critic_adam_.Apply(critic_params_.data(), critic_grad_.data(), lr, scale, b, e);
        }
      }
      sync.ArriveAndWait();  // the parameters are whole again before the next minibatch reads them
    }
  });
  lr_ = lr_end;
  return MeanOver(sum, mbs.total);
}

}  // namespace pbppo::trainer
