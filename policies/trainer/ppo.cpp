#include "policies/trainer/ppo.hpp"

#include <algorithm>
#include <chrono>
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

void Ppo::Save(ByteWriter& w) const {
  w.PutMatrix(actor_params_);
  w.PutMatrix(critic_params_);
  actor_adam_.Save(w);
  critic_adam_.Save(w);
  w.Put(lr_);
  w.Put(rng_);
}

void Ppo::Load(ByteReader& r) {
  r.GetMatrix(actor_params_, "actor parameters");
  r.GetMatrix(critic_params_, "critic parameters");
  actor_adam_.Load(r);
  critic_adam_.Load(r);
  lr_ = r.Get<double>("learning rate");
  rng_ = r.Get<Rng>("minibatch generator");
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

UpdateStats Ppo::Update(const RolloutStorage& r, double eps, bool critic_only, WorkerPool& pool,
                        const Collective* group) {
  const long B = r.size();
  const long mb = std::min<long>(o_.minibatch, B), per_epoch = (B + mb - 1) / mb, total = per_epoch * o_.epochs;
  std::vector<std::vector<long>> perms(static_cast<std::size_t>(o_.epochs));  // per epoch, columns in minibatch order
  for (auto& p : perms) {
    p.resize(static_cast<std::size_t>(B));
    for (long i = 0; i < B; ++i) p[static_cast<std::size_t>(i)] = i;
    for (long i = B - 1; i > 0; --i)
      std::swap(p[static_cast<std::size_t>(i)],
                p[static_cast<std::size_t>(rng_.Below(static_cast<std::uint64_t>(i + 1)))]);
  }
  const int K = Chunks(mb), S = Segments(K);
  // The threads that take part: no more than there are tasks in a phase.
  const int W = std::min(pool.size(), 2 * std::max(K, S));
  const int d = r.obs_size, a = r.action_size, vd = r.value_input_size();
  const Eigen::Index P = actor_params_.size(), V = critic_params_.size();
  const Mat<float>& value_in = r.value_inputs();
  // A held policy (--critic-warmup) has KL 0 from the rollout's: adapting to it would raise the rate
  // to its ceiling before the policy's first step, so the rate waits for the policy.
  const bool adaptive = o_.lr_schedule.kind == LrSchedule::Kind::kAdaptive && !critic_only;
  // Chunk c of network n (0: the actor, 1: the critic) runs on rank (c + n) % R, on its thread
  // ((c + n) / R) % W; the actor's segments 0..S-1 and the critic's S..2S-1 on thread (index % W) of
  // every rank: each thread takes its share of both networks. With ranks, each chunk's gradient and
  // statistics go from its rank to the others (by thread 0, between two barriers), and every rank
  // then makes the same step. With one rank, and one thread or one chunk (two threads at most: one
  // per network), every network stays on one thread, which then reads only what it wrote itself
  // but for the other network's part of the gradient norm (and, for the critic, the actor's KL
  // divergence): one barrier per minibatch instead of three.
  const int R = group != nullptr ? group->size() : 1, rank = group != nullptr ? group->rank() : 0;
  const bool network_per_thread = R == 1 && (W == 1 || K == 1);
  // A minibatch of one chunk computes its gradients in place; more sum theirs into them.
  const std::size_t buffers = K > 1 ? static_cast<std::size_t>(K) : 0;
  std::vector<Vec<float>> actor_chunks(buffers, Vec<float>::Zero(P)), critic_chunks(buffers, Vec<float>::Zero(V));
  struct ChunkStats {
    PolicyLossStats policy;
    double value_loss = 0, gaussian_kl = 0;
  };
  // What threads exchange within a minibatch, in two sets by its parity: with one barrier per
  // minibatch a thread may fill the next minibatch's while another still reads this one's.
  struct Shared {
    std::vector<ChunkStats> chunk;
    std::vector<double> seg_sq;  // the actor's segments, then the critic's
  };
  Shared shared[2];
  for (Shared& sh : shared) {
    sh.chunk.resize(static_cast<std::size_t>(K));
    sh.seg_sq.assign(static_cast<std::size_t>(2 * S), 0.0);
  }
  UpdateStats sum;
  double lr_end = lr_, exchange_seconds = 0;
  SpinBarrier sync(W);
  auto segment = [S](Eigen::Index n, int s) {
    return std::pair<Eigen::Index, Eigen::Index>(n * s / S, n * (s + 1) / S);
  };

  pool.Run([&](int w) {
    if (w >= W) return;
    Mat<float> o(d, 0), act(a, 0), old_mu(a, 0), v_in(vd, 0);
    Vec<float> adv;
    std::vector<float> lp, rt, ov;
    PolicyWorkspace<float> wsp;
    ValueWorkspace<float> wsv;
    double lr = lr_;  // every thread follows the same rate
    for (long k = 0; k < total; ++k) {
      const auto& p = perms[static_cast<std::size_t>(k / per_epoch)];
      const long s0 = (k % per_epoch) * mb, n = std::min(mb, B - s0);
      auto column = [&](long j) { return p[static_cast<std::size_t>(s0 + j)]; };
      Shared& sh = shared[k & 1];
      // 1. Each chunk's gradient of the minibatch's mean loss, per network.
      bool have_advantages = false;
      for (int t = 0; t < 2 * K; ++t) {
        const int c = t / 2;
        const bool actor = t % 2 == 0;
        const int owner = c + (actor ? 0 : 1);
        if (owner % R != rank || (owner / R) % W != w) continue;
        const long c0 = n * c / K, nc = n * (c + 1) / K - c0;
        ChunkStats& cs = sh.chunk[static_cast<std::size_t>(c)];
        if (actor) {
          if (!have_advantages) {  // the minibatch's, normalised over the whole minibatch
            adv.resize(n);
            for (long j = 0; j < n; ++j) adv[j] = r.advantages[static_cast<std::size_t>(column(j))];
            if (o_.normalize_advantages) NormalizeAdvantages(adv);
            have_advantages = true;
          }
          o.resize(d, nc);
          act.resize(a, nc);
          old_mu.resize(a, nc);
          lp.resize(static_cast<std::size_t>(nc));
          for (long j = 0; j < nc; ++j) {
            const long i = column(c0 + j);
            o.col(j) = r.obs.col(i);
            act.col(j) = r.actions.col(i);
            old_mu.col(j) = r.action_mean.col(i);
            lp[static_cast<std::size_t>(j)] = r.log_prob[static_cast<std::size_t>(i)];
          }
          float* grad = K > 1 ? actor_chunks[static_cast<std::size_t>(c)].data() : actor_grad_.data();
          cs.policy = PolicyLossAndGrad(actor_, actor_params_.data(), o, act, lp.data(), adv.data() + c0, eps,
                                        c == 0 ? o_.ent_coef : 0.0, wsp, grad, static_cast<int>(n));
          cs.gaussian_kl = SumGaussianKl(wsp.net.y.back(), log_std(), old_mu, r.log_std.data());
        } else {
          v_in.resize(vd, nc);
          rt.resize(static_cast<std::size_t>(nc));
          ov.resize(static_cast<std::size_t>(nc));
          for (long j = 0; j < nc; ++j) {
            const long i = column(c0 + j);
            v_in.col(j) = value_in.col(i);
            rt[static_cast<std::size_t>(j)] = r.returns[static_cast<std::size_t>(i)];
            ov[static_cast<std::size_t>(j)] = r.values[static_cast<std::size_t>(i)];
          }
          float* grad = K > 1 ? critic_chunks[static_cast<std::size_t>(c)].data() : critic_grad_.data();
          cs.value_loss = ValueLossAndGrad(critic_, critic_params_.data(), v_in, rt.data(), ov.data(), o_.clip_vf,
                                           o_.vf_coef, wsv, grad, static_cast<int>(n));
        }
      }
      if (!network_per_thread) sync.ArriveAndWait();
      if (R > 1) {
        if (w == 0) {  // every chunk's gradient and statistics from its rank, in chunk order
          const auto e0 = std::chrono::steady_clock::now();
          for (int c = 0; c < K; ++c) {
            ChunkStats& cs = sh.chunk[static_cast<std::size_t>(c)];
            float* ag = K > 1 ? actor_chunks[static_cast<std::size_t>(c)].data() : actor_grad_.data();
            float* cg = K > 1 ? critic_chunks[static_cast<std::size_t>(c)].data() : critic_grad_.data();
            group->Broadcast(ag, static_cast<std::size_t>(P) * sizeof(float), c % R);
            group->Broadcast(&cs.policy, sizeof cs.policy, c % R);
            group->Broadcast(&cs.gaussian_kl, sizeof cs.gaussian_kl, c % R);
            group->Broadcast(cg, static_cast<std::size_t>(V) * sizeof(float), (c + 1) % R);
            group->Broadcast(&cs.value_loss, sizeof cs.value_loss, (c + 1) % R);
          }
          exchange_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - e0).count();
        }
        sync.ArriveAndWait();
      }
      // 2. The minibatch's gradient, segment by segment: the chunks' summed in chunk order; each
      // segment's squared norm.
      for (int i = w; i < 2 * S; i += W) {
        const bool actor = i < S;
        const int sg = actor ? i : i - S;
        const auto [b, e] = segment(actor ? P : V, sg);
        if (K > 1) {
          const auto& chunks = actor ? actor_chunks : critic_chunks;
          auto whole = (actor ? actor_grad_ : critic_grad_).segment(b, e - b);
          whole = chunks[0].segment(b, e - b);
          for (int c = 1; c < K; ++c) whole += chunks[static_cast<std::size_t>(c)].segment(b, e - b);
        }
        const float* g = (actor ? actor_grad_ : critic_grad_).data() + b;
        // A held actor takes no part in the clip.
        sh.seg_sq[static_cast<std::size_t>(i)] = actor && critic_only ? 0.0 : SquaredNorm(g, e - b);
        if (sg == 0 && !(actor && critic_only)) (actor ? actor_adam_ : critic_adam_).Advance();
      }
      sync.ArriveAndWait();
      // 3. Every thread: the norm, the clip factor, the rate; then the Adam steps of its segments.
      double sq = 0, kl_sum = 0;
      for (double x : sh.seg_sq) sq += x;
      for (const ChunkStats& cs : sh.chunk) kl_sum += cs.gaussian_kl;
      const double mb_kl = kl_sum / static_cast<double>(n);
      if (adaptive) lr = o_.lr_schedule.Adapt(lr, mb_kl);
      const double norm = std::sqrt(sq);
      const float scale =
          o_.max_grad_norm > 0 && norm > 0 ? static_cast<float>(std::min(1.0, o_.max_grad_norm / (norm + 1e-6))) : 1.f;
      if (w == 0) {
        for (const ChunkStats& cs : sh.chunk) {
          AddPolicyStats(sum, cs.policy, &cs == &sh.chunk[0]);  // the entropy: the actor's, once
          sum.value_loss += cs.value_loss;
        }
        sum.grad_norm += norm;
        sum.kl += mb_kl;
        lr_end = lr;
      }
      for (int i = w; i < 2 * S; i += W) {
        const bool actor = i < S;
        if (actor && critic_only) continue;
        const auto [b, e] = segment(actor ? P : V, actor ? i : i - S);
        if (actor) {
          actor_adam_.Apply(actor_params_.data(), actor_grad_.data(), lr, scale, b, e);
        } else {
          critic_adam_.Apply(critic_params_.data(), critic_grad_.data(), lr, scale, b, e);
        }
      }
      // The parameters are whole again before the next minibatch reads them (with a network per
      // thread, its own thread wrote them).
      if (!network_per_thread) sync.ArriveAndWait();
    }
  });
  lr_ = lr_end;
  UpdateStats st = MeanOver(sum, total);
  st.exchange_seconds = exchange_seconds;
  double ls = 0;
  for (int j = 0; j < r.action_size; ++j) ls += actor_params_[static_cast<Eigen::Index>(actor_.log_std_offset()) + j];
  st.log_std_mean = ls / r.action_size;
  return st;
}

}  // namespace pbppo::trainer
