#include "policies/trainer/trainer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <tuple>

#include "policies/envs/auv_nav.hpp"
#include "policies/envs/env.hpp"
#include "policies/trainer/adam.hpp"
#include "policies/trainer/gae.hpp"
#include "policies/trainer/mlp.hpp"
#include "policies/trainer/ppo_loss.hpp"
#include "policies/trainer/running_stats.hpp"
#include "policies/trainer/worker_pool.hpp"
#include "report/plots.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/reference.hpp"
#include "runtime/robot/io_layout.hpp"

namespace pbppo::trainer {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Error Invalid(const std::string& field, const std::string& what) {
  return MakeError(ErrorCode::kInvalidValue, field + ": " + what);
}

std::uint64_t Mix(std::uint64_t a, std::uint64_t b) {
  std::uint64_t z = a + 0x9E3779B97F4A7C15ull * (b + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// In a fixed order (eight interleaved partial sums), independent of alignment and vector width.
double SquaredNorm(const Vec<float>& v) {
  double acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  const Eigen::Index n = v.size(), n8 = n - n % 8;
  const float* x = v.data();
  for (Eigen::Index i = 0; i < n8; i += 8)
    for (int k = 0; k < 8; ++k) acc[k] += static_cast<double>(x[i + k]) * static_cast<double>(x[i + k]);
  for (Eigen::Index i = n8; i < n; ++i) acc[0] += static_cast<double>(x[i]) * static_cast<double>(x[i]);
  return ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
}

std::string GitRevision() {
  std::string rev;
  FILE* p = ::popen("git -C '" PBPPO_SOURCE_DIR_FOR_GIT "' rev-parse --short=12 HEAD 2>/dev/null", "r");
  if (p == nullptr) return "unknown";
  char buf[64];
  if (std::fgets(buf, sizeof buf, p) != nullptr) rev = buf;
  ::pclose(p);
  while (!rev.empty() && (rev.back() == '\n' || rev.back() == '\r')) rev.pop_back();
  return rev.empty() ? "unknown" : rev;
}

Status WriteText(const std::string& path, const std::string& text) {
  return policy::WriteFileAtomic(path, std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

class Trainer {
 public:
  Trainer(const TrainConfig& c, std::unique_ptr<envs::Env> proto) : c_(c), proto_(std::move(proto)), pool_(c.threads) {}

  Result<TrainResult> Run(const std::function<void(const Progress&)>& progress);

 private:
  struct Worker {
    int e0 = 0, e1 = 0;
    Mat<float> x;
    typename Mlp<float>::Workspace ws;
    std::vector<std::tuple<long, double, int>> episodes;  // (index t*N+e, return, success: 1, 0, -1 n/a)
  };

  void Setup();
  Status LoadInit();
  void NormalizeInto(const float* raw, float* out) const;
  void FreezeNormalizer();
  void CollectRollout();
  void RolloutWorker(Worker& w);
  void ComputeValuesAndAdvantages();
  void Update(double eps, IterationStats& st);
  double Evaluate(int iteration, std::uint64_t* steps);
  policy::PolicySpec Freeze(double final_return) const;
  double FreezeCheck(const policy::PolicySpec& spec);
  Status WriteCheckpoint(double final_return, std::uint64_t env_steps, const std::string& name = "policy.blob");
  double best_return_ = -std::numeric_limits<double>::infinity();
  double best_success_ = -1.0;  // -1: no task success known
  std::string CsvHeader() const;
  std::string CsvRow(const IterationStats& s) const;
  std::string Plots(const std::vector<IterationStats>& its);

  const TrainConfig& c_;
  std::unique_ptr<envs::Env> proto_;
  WorkerPool pool_;
  int d_ = 0, a_ = 0, N_ = 0, T_ = 0;
  GaussianPolicy<float> pol_;
  Mlp<float> value_;
  // Eigen-aligned storage: vectorised code then sees the same alignment on every run.
  Vec<float> pp_, pv_, gp_, gv_;
  Adam<float> adam_p_, adam_v_;
  double lr_now_ = 0;  // this iteration's learning rate (annealed or constant)
  Rng rng_;
  std::vector<std::unique_ptr<envs::Env>> envs_;
  std::vector<Rng> env_rng_;
  std::vector<float> raw_obs_cur_;  // [N][d]
  std::vector<double> ep_return_;
  RunningMeanStd obs_rms_, ret_rms_;
  std::vector<float> obs_mean_, obs_inv_std_;
  float obs_clip_ = std::numeric_limits<float>::max();
  std::vector<double> disc_ret_;
  std::vector<Worker> workers_;
  // Rollout buffer, time-major columns t*N+e.
  Mat<float> obs_, act_, trunc_obs_, last_obs_;
  std::vector<float> raw_obs_;  // [T*N][d] for the normaliser
  std::vector<float> logp_, rew_, values_, trunc_values_, last_values_, adv_, ret_;
  std::vector<std::uint8_t> term_, trunc_;
  std::vector<double> rollout_returns_;
  std::deque<double> last100_;
  std::deque<int> success100_;  // task success of the last 100 training episodes (where known)
  double clip_fraction_ = 0;
};

}  // namespace

Status TrainConfig::Validate() const {
  if (total_steps < 1) return Invalid("--steps", "must be at least 1");
  if (num_envs < 1 || num_envs > 4096) return Invalid("--envs", std::to_string(num_envs) + " is not in [1, 4096]");
  if (rollout_steps < 1) return Invalid("--rollout", std::to_string(rollout_steps) + " is not positive");
  if (threads < 1 || threads > 256) return Invalid("--threads", std::to_string(threads) + " is not in [1, 256]");
  if (minibatch < 2) return Invalid("--minibatch", std::to_string(minibatch) + " is below 2");
  if (epochs < 1) return Invalid("--epochs", std::to_string(epochs) + " is not positive");
  if (!(exploring_starts >= 0 && exploring_starts <= 1))
    return Invalid("--exploring-starts", std::to_string(exploring_starts) + " is not in [0, 1]");
  if (exploring_starts > 0 && env != "auv-nav")
    return Invalid("--exploring-starts", "only auv-nav has exploring starts, not '" + env + "'");
  if (auto p = envs::AuvNav::ProgressFor(progress, ""); !p) return Invalid("--progress", p.error().message);
  if (!progress.empty() && env != "auv-nav")
    return Invalid("--progress", "only auv-nav has a progress term to choose, not '" + env + "'");
  if (auto m = envs::AuvNav::ParseGeodesicMargin(geodesic_margin); !m)
    return Invalid("--geodesic-margin", m.error().message);
  if (!geodesic_margin.empty() && env != "auv-nav")
    return Invalid("--geodesic-margin", "only auv-nav has one, not '" + env + "'");
  if (auto m = envs::AuvNav::ParseClearancePenalty(clearance_penalty); !m)
    return Invalid("--clearance-penalty", m.error().message);
  if (!clearance_penalty.empty() && env != "auv-nav")
    return Invalid("--clearance-penalty", "only auv-nav has one, not '" + env + "'");
  if (extra_obstacles < 0 || extra_obstacles > 16)
    return Invalid("--extra-obstacles", std::to_string(extra_obstacles) + " is not in [0, 16]");
  if (extra_obstacles > 0 && env != "auv-nav")
    return Invalid("--extra-obstacles", "only auv-nav has obstacles, not '" + env + "'");
  if (critic_warmup < 0) return Invalid("--critic-warmup", std::to_string(critic_warmup) + " is negative");
  if (critic_warmup > 0 && init_blob.empty())
    return Invalid("--critic-warmup", "needs --init (it holds a trained policy while the fresh value network learns)");
  if (snapshots < 0 || snapshots > 1000)
    return Invalid("--snapshots", std::to_string(snapshots) + " is not in [0, 1000]");
  if (!(learning_rate > 0)) return Invalid("--lr", std::to_string(learning_rate) + " is not positive");
  if (!(gamma > 0 && gamma <= 1)) return Invalid("--gamma", std::to_string(gamma) + " is not in (0, 1]");
  if (!(gae_lambda >= 0 && gae_lambda <= 1))
    return Invalid("--gae-lambda", std::to_string(gae_lambda) + " is not in [0, 1]");
  if (policy_hidden.empty() || value_hidden.empty()) return Invalid("--hidden", "needs at least one hidden layer");
  for (int h : policy_hidden)
    if (h < 1 || h > 2048) return Invalid("--hidden", std::to_string(h) + " is not in [1, 2048]");
  for (int h : value_hidden)
    if (h < 1 || h > 2048) return Invalid("--value-hidden", std::to_string(h) + " is not in [1, 2048]");
  if (schedule.arms.empty()) return Invalid("--arms", "no clip bound");
  for (double a : schedule.arms)
    if (!(a >= 0 && a <= 1)) return Invalid("--arms", "clip bound " + std::to_string(a) + " is outside [0, 1]");
  if (!init_blob.empty() && normalize_observations)
    return Invalid("--init", "'" + init_blob +
                                 "' brings its frozen observation normaliser; --normalize-obs would re-learn it "
                                 "under the blob's weights (leave it off)");
  if (schedule.eval_episodes < 1)
    return Invalid("--eval-episodes", std::to_string(schedule.eval_episodes) + " is below 1");
  return {};
}

namespace {

void Trainer::Setup() {
  d_ = static_cast<int>(proto_->observation_size());
  a_ = static_cast<int>(proto_->action_size());
  N_ = c_.num_envs;
  T_ = c_.rollout_steps;
  rng_.Seed(Mix(c_.seed, 0));

  std::vector<int> pw{d_};
  pw.insert(pw.end(), c_.policy_hidden.begin(), c_.policy_hidden.end());
  pw.push_back(a_);
  std::vector<int> vw{d_};
  vw.insert(vw.end(), c_.value_hidden.begin(), c_.value_hidden.end());
  vw.push_back(1);
  pol_ = GaussianPolicy<float>{Mlp<float>(MlpShape{pw, c_.activation, policy::Activation::kIdentity}), a_};
  value_ = Mlp<float>(MlpShape{vw, c_.activation, policy::Activation::kIdentity});
  pp_ = Vec<float>::Zero(static_cast<Eigen::Index>(pol_.size()));
  pv_ = Vec<float>::Zero(static_cast<Eigen::Index>(value_.size()));
  gp_ = Vec<float>::Zero(static_cast<Eigen::Index>(pol_.size()));
  gv_ = Vec<float>::Zero(static_cast<Eigen::Index>(value_.size()));
  Rng init(Mix(c_.seed, 1));
  pol_.mean.InitOrthogonal(pp_.data(), init, std::sqrt(2.0), 0.01);
  value_.InitOrthogonal(pv_.data(), init, std::sqrt(2.0), 1.0);
  for (int j = 0; j < a_; ++j)
    pp_[static_cast<Eigen::Index>(pol_.log_std_offset()) + j] = static_cast<float>(c_.log_std_init);
  adam_p_ = Adam<float>(static_cast<std::size_t>(pp_.size()), 1e-5);
  adam_v_ = Adam<float>(static_cast<std::size_t>(pv_.size()), 1e-5);

  obs_rms_ = RunningMeanStd(d_);
  ret_rms_ = RunningMeanStd(1);
  obs_mean_.assign(static_cast<std::size_t>(d_), 0.f);
  obs_inv_std_.assign(static_cast<std::size_t>(d_), 1.f);
  if (c_.normalize_observations) obs_clip_ = 10.f;

  envs_.clear();
  env_rng_.clear();
  raw_obs_cur_.assign(static_cast<std::size_t>(N_ * d_), 0.f);
  ep_return_.assign(static_cast<std::size_t>(N_), 0.0);
  disc_ret_.assign(static_cast<std::size_t>(N_), 0.0);
  for (int e = 0; e < N_; ++e) {
    envs_.push_back(proto_->Clone());
    env_rng_.emplace_back(Mix(c_.seed, 1000 + static_cast<std::uint64_t>(e)));
    envs_.back()->Reset(env_rng_.back(), {raw_obs_cur_.data() + e * d_, static_cast<std::size_t>(d_)});
  }
  const int W = std::min(pool_.size(), N_);
  workers_.assign(static_cast<std::size_t>(W), Worker{});
  for (int w = 0; w < W; ++w) {
    workers_[static_cast<std::size_t>(w)].e0 = N_ * w / W;
    workers_[static_cast<std::size_t>(w)].e1 = N_ * (w + 1) / W;
  }
  const long B = static_cast<long>(T_) * N_;
  obs_.resize(d_, B);
  act_.resize(a_, B);
  trunc_obs_.resize(d_, B);
  last_obs_.resize(d_, N_);
  raw_obs_.assign(static_cast<std::size_t>(B * d_), 0.f);
  for (auto* v : {&logp_, &rew_, &values_, &trunc_values_, &adv_, &ret_}) v->assign(static_cast<std::size_t>(B), 0.f);
  last_values_.assign(static_cast<std::size_t>(N_), 0.f);
  term_.assign(static_cast<std::size_t>(B), 0);
  trunc_.assign(static_cast<std::size_t>(B), 0);
}

Status Trainer::LoadInit() {
  auto blob = policy::ReadBlobFile(c_.init_blob);
  if (!blob) return MakeError(blob.error().code, "--init: " + blob.error().message);
  const policy::PolicySpec& s = *blob;
  if (auto st = robot::CheckPolicyMatchesLayout(s, proto_->layout()); !st)
    return Invalid("--init", "'" + c_.init_blob + "': " + st.error().message);
  if (s.layers.size() != pol_.mean.layers())
    return Invalid("--init", "'" + c_.init_blob + "' has " + std::to_string(s.layers.size()) +
                                 " layers, --hidden gives " + std::to_string(pol_.mean.layers()));
  for (std::size_t l = 0; l < s.layers.size(); ++l) {
    const policy::DenseLayer& L = s.layers[l];
    const std::string where = "'" + c_.init_blob + "' layer " + std::to_string(l) + " ";
    if (static_cast<int>(L.in) != pol_.mean.in(l) || static_cast<int>(L.out) != pol_.mean.out(l))
      return Invalid("--init", where + "is " + std::to_string(L.in) + "x" + std::to_string(L.out) +
                                   ", --hidden gives " + std::to_string(pol_.mean.in(l)) + "x" +
                                   std::to_string(pol_.mean.out(l)));
    if (L.activation != pol_.mean.activation(l))
      return Invalid("--init", where + "has activation " + policy::ToString(L.activation) + ", the trainer " +
                                   policy::ToString(pol_.mean.activation(l)) + " (--activation)");
  }
  for (std::size_t l = 0; l < s.layers.size(); ++l) {
    const policy::DenseLayer& L = s.layers[l];
    auto W = pol_.mean.W(pp_.data(), l);
    for (std::uint32_t o = 0; o < L.out; ++o)
      for (std::uint32_t i = 0; i < L.in; ++i) W(o, i) = L.weight[o * L.in + i];
    auto b = pol_.mean.b(pp_.data(), l);
    for (std::uint32_t o = 0; o < L.out; ++o) b[o] = L.bias[o];
  }
  obs_mean_ = s.obs_mean;
  obs_inv_std_ = s.obs_inv_std;
  obs_clip_ = s.obs_clip;
  return {};
}

void Trainer::NormalizeInto(const float* raw, float* out) const {
  for (int j = 0; j < d_; ++j) {
    const auto k = static_cast<std::size_t>(j);
    out[j] = std::clamp((raw[j] - obs_mean_[k]) * obs_inv_std_[k], -obs_clip_, obs_clip_);
  }
}

void Trainer::FreezeNormalizer() {
  if (!c_.normalize_observations) return;
  for (int j = 0; j < d_; ++j) {
    const auto k = static_cast<std::size_t>(j);
    obs_mean_[k] = static_cast<float>(obs_rms_.mean()[k]);
    obs_inv_std_[k] = static_cast<float>(1.0 / std::sqrt(obs_rms_.var()[k] + 1e-8));
  }
}

void Trainer::RolloutWorker(Worker& w) {
  const int n = w.e1 - w.e0;
  w.x.resize(d_, n);
  w.episodes.clear();
  const float* log_std = pp_.data() + pol_.log_std_offset();
  std::vector<float> stdv(static_cast<std::size_t>(a_)), act(static_cast<std::size_t>(a_));
  const double half_log_2pi = 0.5 * std::log(2.0 * M_PI);
  for (int j = 0; j < a_; ++j) stdv[static_cast<std::size_t>(j)] = std::exp(log_std[j]);
  for (int t = 0; t < T_; ++t) {
    for (int e = w.e0; e < w.e1; ++e) {
      const long i = static_cast<long>(t) * N_ + e;
      const float* raw = raw_obs_cur_.data() + e * d_;
      std::copy(raw, raw + d_, raw_obs_.data() + i * d_);
      NormalizeInto(raw, w.x.col(e - w.e0).data());
      obs_.col(i) = w.x.col(e - w.e0);
    }
    const Mat<float>& mu = pol_.mean.Forward(pp_.data(), w.x, w.ws);
    for (int e = w.e0; e < w.e1; ++e) {
      const long i = static_cast<long>(t) * N_ + e;
      const int c = e - w.e0;
      Rng& rng = env_rng_[static_cast<std::size_t>(e)];
      envs::Env& env = *envs_[static_cast<std::size_t>(e)];
      float lp = 0;
      for (int j = 0; j < a_; ++j) {
        const auto k = static_cast<std::size_t>(j);
        const float sample = mu(j, c) + stdv[k] * static_cast<float>(rng.Normal());
        act_(j, i) = sample;
        const float z = (sample - mu(j, c)) * std::exp(-log_std[j]);
        lp += -0.5f * z * z - log_std[j];
        act[k] = std::clamp(sample, env.action_low()[k], env.action_high()[k]);
      }
      logp_[static_cast<std::size_t>(i)] = lp - static_cast<float>(a_ * half_log_2pi);
      float* raw = raw_obs_cur_.data() + e * d_;
      const envs::StepResult r = env.Step(act, {raw, static_cast<std::size_t>(d_)});
      rew_[static_cast<std::size_t>(i)] = static_cast<float>(r.reward);
      term_[static_cast<std::size_t>(i)] = r.terminated;
      trunc_[static_cast<std::size_t>(i)] = r.truncated && !r.terminated;
      ep_return_[static_cast<std::size_t>(e)] += r.reward;
      if (r.terminated || r.truncated) {
        if (!r.terminated) NormalizeInto(raw, trunc_obs_.col(i).data());
        const envs::EpisodeInfo info = env.episode_info();
        w.episodes.emplace_back(i, ep_return_[static_cast<std::size_t>(e)],
                                info.available ? (info.success ? 1 : 0) : -1);
        ep_return_[static_cast<std::size_t>(e)] = 0;
        env.Reset(rng, {raw, static_cast<std::size_t>(d_)});
      }
    }
  }
  for (int e = w.e0; e < w.e1; ++e) NormalizeInto(raw_obs_cur_.data() + e * d_, last_obs_.col(e).data());
}

void Trainer::CollectRollout() {
  FreezeNormalizer();
  pool_.Run([&](int w) {
    if (w < static_cast<int>(workers_.size())) RolloutWorker(workers_[static_cast<std::size_t>(w)]);
  });
  std::vector<std::tuple<long, double, int>> eps;
  for (auto& w : workers_) eps.insert(eps.end(), w.episodes.begin(), w.episodes.end());
  std::sort(eps.begin(), eps.end());
  rollout_returns_.clear();
  for (const auto& [i, r, ok] : eps) {
    rollout_returns_.push_back(r);
    last100_.push_back(r);
    if (last100_.size() > 100) last100_.pop_front();
    if (ok >= 0) {
      success100_.push_back(ok);
      if (success100_.size() > 100) success100_.pop_front();
    }
  }
  if (c_.normalize_observations) obs_rms_.Update(raw_obs_.data(), static_cast<long>(T_) * N_);
  if (c_.scale_rewards) {
    // Running discounted return per environment (reset at episode ends), its variance, and
    // rewards divided by its standard deviation and clipped to +-10.
    std::vector<float> rets(rew_.size());
    for (long i = 0; i < static_cast<long>(rew_.size()); ++i) {
      const auto e = static_cast<std::size_t>(i % N_);
      disc_ret_[e] = disc_ret_[e] * c_.gamma + rew_[static_cast<std::size_t>(i)];
      rets[static_cast<std::size_t>(i)] = static_cast<float>(disc_ret_[e]);
      if (term_[static_cast<std::size_t>(i)] || trunc_[static_cast<std::size_t>(i)]) disc_ret_[e] = 0;
    }
    ret_rms_.Update(rets.data(), static_cast<long>(rets.size()));
    const double s = std::sqrt(ret_rms_.var()[0] + 1e-8);
    for (float& r : rew_) r = static_cast<float>(std::clamp(r / s, -10.0, 10.0));
  }
}

void Trainer::ComputeValuesAndAdvantages() {
  // Values in fixed 256-column chunks: the same arithmetic for any thread count.
  const long B = static_cast<long>(T_) * N_;
  const long chunk = 256;
  const long chunks = (B + chunk - 1) / chunk;
  std::vector<long> trunc_idx;
  for (long i = 0; i < B; ++i)
    if (trunc_[static_cast<std::size_t>(i)]) trunc_idx.push_back(i);
  pool_.Run([&](int w) {
    typename Mlp<float>::Workspace ws;
    for (long k = w; k < chunks; k += pool_.size()) {
      const long c0 = k * chunk, n = std::min(chunk, B - c0);
      const Mat<float>& v = value_.Forward(pv_.data(), obs_.middleCols(c0, n), ws);
      std::copy(v.data(), v.data() + n, values_.data() + c0);
    }
    if (w == 0) {
      const Mat<float>& v = value_.Forward(pv_.data(), last_obs_, ws);
      std::copy(v.data(), v.data() + N_, last_values_.data());
      for (std::size_t k = 0; k < trunc_idx.size(); ++k) {
        const Mat<float>& vt = value_.Forward(pv_.data(), trunc_obs_.col(trunc_idx[k]), ws);
        trunc_values_[static_cast<std::size_t>(trunc_idx[k])] = vt(0, 0);
      }
    }
  });
  GaeInput in{
      T_, N_, rew_.data(), values_.data(), term_.data(), trunc_.data(), trunc_values_.data(), last_values_.data()};
  ComputeGae(in, c_.gamma, c_.gae_lambda, adv_.data(), ret_.data());
}

void Trainer::Update(double eps, IterationStats& st) {
  const long B = static_cast<long>(T_) * N_;
  const long mb = std::min<long>(c_.minibatch, B);
  const long per_epoch = (B + mb - 1) / mb;
  std::vector<std::vector<long>> perms(static_cast<std::size_t>(c_.epochs));
  for (auto& p : perms) {
    p.resize(static_cast<std::size_t>(B));
    for (long i = 0; i < B; ++i) p[static_cast<std::size_t>(i)] = i;
    for (long i = B - 1; i > 0; --i)
      std::swap(p[static_cast<std::size_t>(i)],
                p[static_cast<std::size_t>(rng_.Below(static_cast<std::uint64_t>(i + 1)))]);
  }
  const long total = per_epoch * c_.epochs;
  // Squared gradient norms per minibatch, [policy, value] in two slots alternating by parity.
  double sq[2][2] = {{0, 0}, {0, 0}};
  double pol_loss = 0, ent = 0, kl = 0, clipfrac = 0, vloss = 0, gnorm = 0;
  const bool split = pool_.size() >= 2;
  SpinBarrier sync(split ? 2 : 1);
  // --critic-warmup: the value network learns, the policy stays as it is (its loss is still
  // computed for the log).
  const bool critic_only = st.iteration < c_.critic_warmup;

  auto clip_scale = [&](long k) {
    const double n = std::sqrt(sq[k & 1][0] + sq[k & 1][1]);
    return std::pair<double, float>(
        n, c_.max_grad_norm > 0 && n > 0 ? static_cast<float>(std::min(1.0, c_.max_grad_norm / (n + 1e-6))) : 1.f);
  };
  auto policy_loop = [&](bool sequential_value, PolicyWorkspace<float>& wsp, ValueWorkspace<float>& wsv) {
    Mat<float> o(d_, mb), a(a_, mb);
    std::vector<float> lp(static_cast<std::size_t>(mb)), ad(static_cast<std::size_t>(mb)),
        rt(static_cast<std::size_t>(mb)), ov(static_cast<std::size_t>(mb));
    for (long k = 0; k < total; ++k) {
      const auto& p = perms[static_cast<std::size_t>(k / per_epoch)];
      const long s0 = (k % per_epoch) * mb, n = std::min(mb, B - s0);
      o.resize(d_, n);
      a.resize(a_, n);
      for (long j = 0; j < n; ++j) {
        const long i = p[static_cast<std::size_t>(s0 + j)];
        o.col(j) = obs_.col(i);
        a.col(j) = act_.col(i);
        lp[static_cast<std::size_t>(j)] = logp_[static_cast<std::size_t>(i)];
        ad[static_cast<std::size_t>(j)] = adv_[static_cast<std::size_t>(i)];
        rt[static_cast<std::size_t>(j)] = ret_[static_cast<std::size_t>(i)];
        ov[static_cast<std::size_t>(j)] = values_[static_cast<std::size_t>(i)];
      }
      const PolicyLossStats ps = PolicyLossAndGrad(pol_, pp_.data(), o, a, lp.data(), ad.data(), eps, c_.ent_coef,
                                                   c_.normalize_advantages, wsp, gp_.data());
      pol_loss += ps.policy_loss;
      ent += ps.entropy;
      kl += ps.approx_kl;
      clipfrac += ps.clip_fraction;
      sq[k & 1][0] = critic_only ? 0.0 : SquaredNorm(gp_);  // a held policy takes no part in the clip
      if (sequential_value) {
        vloss += ValueLossAndGrad(value_, pv_.data(), o, rt.data(), ov.data(), c_.clip_vf, c_.vf_coef, wsv, gv_.data());
        sq[k & 1][1] = SquaredNorm(gv_);
      } else {
        sync.ArriveAndWait();
      }
      const auto [norm, scale] = clip_scale(k);
      gnorm += norm;
      if (!critic_only) adam_p_.Step(pp_.data(), gp_.data(), lr_now_, scale);
      if (sequential_value) adam_v_.Step(pv_.data(), gv_.data(), lr_now_, scale);
    }
  };
  auto value_loop = [&](ValueWorkspace<float>& wsv) {
    Mat<float> o(d_, mb);
    std::vector<float> rt(static_cast<std::size_t>(mb)), ov(static_cast<std::size_t>(mb));
    for (long k = 0; k < total; ++k) {
      const auto& p = perms[static_cast<std::size_t>(k / per_epoch)];
      const long s0 = (k % per_epoch) * mb, n = std::min(mb, B - s0);
      o.resize(d_, n);
      for (long j = 0; j < n; ++j) {
        const long i = p[static_cast<std::size_t>(s0 + j)];
        o.col(j) = obs_.col(i);
        rt[static_cast<std::size_t>(j)] = ret_[static_cast<std::size_t>(i)];
        ov[static_cast<std::size_t>(j)] = values_[static_cast<std::size_t>(i)];
      }
      vloss += ValueLossAndGrad(value_, pv_.data(), o, rt.data(), ov.data(), c_.clip_vf, c_.vf_coef, wsv, gv_.data());
      sq[k & 1][1] = SquaredNorm(gv_);
      sync.ArriveAndWait();
      const auto [norm, scale] = clip_scale(k);
      (void)norm;
      adam_v_.Step(pv_.data(), gv_.data(), lr_now_, scale);
    }
  };
  PolicyWorkspace<float> wsp;
  ValueWorkspace<float> wsv;
  if (split) {
    pool_.Run([&](int w) {
      if (w == 0) policy_loop(false, wsp, wsv);
      if (w == 1) value_loop(wsv);
    });
  } else {
    policy_loop(true, wsp, wsv);
  }
  const double m = static_cast<double>(total);
  st.policy_loss = pol_loss / m;
  st.entropy = ent / m;
  st.approx_kl = kl / m;
  st.clip_fraction = clipfrac / m;
  st.value_loss = vloss / m;
  st.grad_norm = gnorm / m;
  double ls = 0;
  for (int j = 0; j < a_; ++j) ls += pp_[static_cast<Eigen::Index>(pol_.log_std_offset()) + j];
  st.log_std_mean = ls / a_;
}

double Trainer::Evaluate(int iteration, std::uint64_t* steps) {
  const int k = c_.schedule.eval_episodes;
  std::vector<double> returns(static_cast<std::size_t>(k), 0.0);
  std::vector<std::uint64_t> counts(static_cast<std::size_t>(k), 0);
  pool_.Run([&](int w) {
    typename Mlp<float>::Workspace ws;
    Mat<float> x(d_, 1);
    std::vector<float> raw(static_cast<std::size_t>(d_)), act(static_cast<std::size_t>(a_));
    for (int ep = w; ep < k; ep += pool_.size()) {
      auto env = proto_->Clone();
      Rng rng(Mix(Mix(c_.seed, 7), static_cast<std::uint64_t>(iteration) * 4096 + static_cast<std::uint64_t>(ep)));
      env->Reset(rng, raw);
      double ret = 0;
      std::uint64_t n = 0;
      for (;;) {
        NormalizeInto(raw.data(), x.data());
        const Mat<float>& mu = pol_.mean.Forward(pp_.data(), x, ws);
        for (int j = 0; j < a_; ++j) {
          const auto q = static_cast<std::size_t>(j);
          act[q] = std::clamp(mu(j, 0), env->action_low()[q], env->action_high()[q]);
        }
        const envs::StepResult r = env->Step(act, raw);
        ret += r.reward;
        ++n;
        if (r.terminated || r.truncated) break;
      }
      returns[static_cast<std::size_t>(ep)] = ret;
      counts[static_cast<std::size_t>(ep)] = n;
    }
  });
  double sum = 0;
  for (int ep = 0; ep < k; ++ep) {
    sum += returns[static_cast<std::size_t>(ep)];
    *steps += counts[static_cast<std::size_t>(ep)];
  }
  return sum / k;
}

policy::PolicySpec Trainer::Freeze(double final_return) const {
  policy::PolicySpec s;
  s.input_size = static_cast<std::uint32_t>(d_);
  s.output_size = static_cast<std::uint32_t>(a_);
  s.obs_mean = obs_mean_;
  s.obs_inv_std = obs_inv_std_;
  s.obs_clip = obs_clip_;
  for (std::size_t l = 0; l < pol_.mean.layers(); ++l) {
    policy::DenseLayer L;
    L.in = static_cast<std::uint32_t>(pol_.mean.in(l));
    L.out = static_cast<std::uint32_t>(pol_.mean.out(l));
    L.activation = pol_.mean.activation(l);
    const auto W = pol_.mean.W(pp_.data(), l);
    L.weight.resize(static_cast<std::size_t>(L.in) * L.out);
    for (std::uint32_t o = 0; o < L.out; ++o)
      for (std::uint32_t i = 0; i < L.in; ++i) L.weight[o * L.in + i] = W(o, i);
    const auto b = pol_.mean.b(pp_.data(), l);
    L.bias.assign(b.data(), b.data() + b.size());
    s.layers.push_back(std::move(L));
  }
  s.action_head = policy::ActionHead::kLinear;  // the Gaussian mean
  // The layout's action map (scale, offset, command limits): the blob outputs commands.
  robot::ApplyLayoutToSpec(proto_->layout(), s);
  s.provenance.trainer_version = std::string("pbppo-rt ") + PBPPO_VERSION;
  s.provenance.git_revision = GitRevision();
  s.provenance.environment = proto_->name();
  std::string sched = c_.schedule.Describe();
  if (sched.size() > 200) sched.resize(200);
  s.provenance.clip_schedule = sched;
  s.provenance.seed = c_.seed;
  s.provenance.final_return = final_return;
  return s;
}

double Trainer::FreezeCheck(const policy::PolicySpec& spec) {
  typename Mlp<float>::Workspace ws;
  Mat<float> x(d_, 1);
  double worst = 0;
  const long B = static_cast<long>(T_) * N_;
  for (long k = 0; k < 16; ++k) {
    const float* raw = raw_obs_.data() + ((k * 7919) % B) * d_;
    NormalizeInto(raw, x.data());
    const Mat<float>& mu = pol_.mean.Forward(pp_.data(), x, ws);
    const policy::ReferenceOutput ref = policy::ReferenceForward(spec, raw);
    for (int j = 0; j < a_; ++j) {
      const auto q = static_cast<std::size_t>(j);
      const double a = std::clamp(mu(j, 0), proto_->action_low()[q], proto_->action_high()[q]);
      const double mine = std::clamp(a * spec.action_scale[q] + spec.action_offset[q],
                                     static_cast<double>(spec.action_low[q]), static_cast<double>(spec.action_high[q]));
      // The trainer's float forward rounds like the runtime's: allow twice the bound, plus 1e-6.
      const double bound = 2.0 * ref.error_bound[q] + 1e-6;
      worst = std::max(worst, std::fabs(mine - ref.action[q]) / bound);
    }
  }
  return worst;
}

std::string Trainer::CsvHeader() const {
  std::ostringstream h;
  h << "iteration,env_steps,eval_steps,total_steps,arm,epsilon,feedback,feedback_before,improved,success_rate,"
       "train_return,train_return_100,episodes,approx_kl,clip_fraction,explained_variance,entropy,policy_loss,"
       "value_loss,grad_norm,log_std_mean,steps_per_second,task_success_100,learning_rate";
  for (std::size_t i = 0; i < c_.schedule.arms.size(); ++i)
    h << ",arm" << i << "_epsilon,arm" << i << "_value,arm" << i << "_bonus,arm" << i << "_count";
  h << "\n";
  return h.str();
}

std::string Trainer::CsvRow(const IterationStats& s) const {
  std::ostringstream r;
  r.precision(10);
  r << s.iteration << ',' << s.env_steps << ',' << s.eval_steps << ',' << (s.env_steps + s.eval_steps) << ',' << s.arm
    << ',' << s.epsilon << ',' << s.feedback << ',' << s.feedback_before << ',' << (s.improved ? 1 : 0) << ','
    << s.success_rate << ',' << s.train_return << ',' << s.train_return_100 << ',' << s.episodes << ',' << s.approx_kl
    << ',' << s.clip_fraction << ',' << s.explained_variance << ',' << s.entropy << ',' << s.policy_loss << ','
    << s.value_loss << ',' << s.grad_norm << ',' << s.log_std_mean << ',' << s.steps_per_second << ','
    << s.task_success_100 << ',' << s.learning_rate;
  for (const auto& a : s.arms) r << ',' << a.epsilon << ',' << a.value << ',' << a.bonus << ',' << a.count;
  r << "\n";
  return r.str();
}

std::string Trainer::Plots(const std::vector<IterationStats>& its) {
  report::TrainingCurves curves;
  curves.dir = c_.out_dir;
  curves.arms = c_.schedule.arms;
  curves.pulls.assign(curves.arms.size(), 0);
  for (const auto& s : its) curves.pulls[static_cast<std::size_t>(s.arm)]++;
  curves.task_success = !its.empty() && std::isfinite(its.back().task_success_100);
  auto pngs = report::PlotTrainingCurves(curves);
  if (!pngs) return "plots skipped: " + pngs.error().message;
  std::string note = "plots:";
  for (const auto& p : *pngs) note += (note.size() > 6 ? ", " : " ") + p;
  return note;
}

Status Trainer::WriteCheckpoint(double final_return, std::uint64_t env_steps, const std::string& name) {
  if (c_.out_dir.empty()) return {};
  policy::PolicySpec spec = Freeze(final_return);
  spec.provenance.env_steps = env_steps;
  const std::string blob = c_.out_dir + "/" + name;
  if (auto st = policy::WriteBlobFile(blob, spec); !st) return st;
  return policy::WriteGoldenFile(policy::GoldenPathFor(blob), policy::MakeGoldenVectors(spec, 32, c_.seed));
}

Result<TrainResult> Trainer::Run(const std::function<void(const Progress&)>& progress) {
  Setup();
  if (!c_.init_blob.empty()) {
    if (auto st = LoadInit(); !st) return st.error();
  }
  TrainResult res;
  const auto t0 = Clock::now();
  std::ofstream csv;
  if (!c_.out_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(c_.out_dir, ec);
    if (ec) return MakeError(ErrorCode::kIo, "--out: cannot create folder '" + c_.out_dir + "': " + ec.message());
    if (auto st = WriteText(c_.out_dir + "/log.csv", CsvHeader()); !st) {
      return MakeError(ErrorCode::kIo, "--out: folder '" + c_.out_dir + "' is not writable: " + st.error().message);
    }
    csv.open(c_.out_dir + "/log.csv", std::ios::app);
    if (!csv) return MakeError(ErrorCode::kIo, "--out: cannot append to '" + c_.out_dir + "/log.csv'");
    if (c_.snapshots > 0) {
      std::filesystem::create_directories(c_.out_dir + "/snapshots", ec);
      if (ec)
        return MakeError(ErrorCode::kIo, "--snapshots: cannot create '" + c_.out_dir + "/snapshots': " + ec.message());
    }
  }
  auto schedule = MakeClipSchedule(c_.schedule);
  const bool bandit = schedule->uses_feedback();
  const bool eval_feedback = bandit && c_.schedule.feedback == FeedbackSource::kEval;
  const std::uint64_t per_iter = static_cast<std::uint64_t>(T_) * static_cast<std::uint64_t>(N_);
  const int iterations = static_cast<int>((c_.total_steps + per_iter - 1) / per_iter);

  std::uint64_t env_steps = 0, eval_steps = 0;
  auto mean = [](const std::vector<double>& v) {
    if (v.empty()) return kNaN;
    double s = 0;
    for (double x : v) s += x;
    return s / static_cast<double>(v.size());
  };
  auto mean100 = [&] {
    if (last100_.empty()) return kNaN;
    double s = 0;
    for (double x : last100_) s += x;
    return s / static_cast<double>(last100_.size());
  };

  CollectRollout();
  env_steps += per_iter;
  double rollout_return = mean(rollout_returns_);
  int rollout_episodes = static_cast<int>(rollout_returns_.size());
  double feedback_prev = eval_feedback ? Evaluate(-1, &eval_steps) : rollout_return;
  int improved_count = 0, feedback_count = 0;
  auto last_checkpoint = Clock::now();

  for (int it = 0; it < iterations; ++it) {
    // --keep-best: the parameters that collected the best last-100-episode task success (or, for
    // environments without one, return) so far (these episodes were collected by this and the few
    // previous iterations' policies).
    if (c_.keep_best && last100_.size() >= 100) {
      double success = -1.0;
      if (success100_.size() >= 100) {
        success = 0.0;
        for (int x : success100_) success += x;
        success /= static_cast<double>(success100_.size());
      }
      if (success > best_success_ || (success == best_success_ && mean100() > best_return_)) {
        best_success_ = success;
        best_return_ = mean100();
        if (auto s = WriteCheckpoint(best_return_, env_steps, "best.blob"); !s) return s.error();
      }
    }
    IterationStats st;
    st.iteration = it;
    st.train_return = rollout_return;
    st.episodes = rollout_episodes;
    ComputeValuesAndAdvantages();
    {
      double mr = 0, mv = 0;
      const auto n = static_cast<double>(ret_.size());
      for (std::size_t i = 0; i < ret_.size(); ++i) {
        mr += ret_[i];
        mv += ret_[i] - values_[i];
      }
      mr /= n;
      mv /= n;
      double vr = 0, vd = 0;
      for (std::size_t i = 0; i < ret_.size(); ++i) {
        vr += (ret_[i] - mr) * (ret_[i] - mr);
        const double dd = ret_[i] - values_[i] - mv;
        vd += dd * dd;
      }
      st.explained_variance = vr > 0 ? 1.0 - vd / vr : kNaN;
    }
    st.arm = schedule->Choose();
    st.arms = schedule->arms();
    st.epsilon = schedule->epsilon(st.arm);
    // Linear annealing to zero over the budget (CleanRL's anneal_lr), counted in iterations.
    lr_now_ = c_.anneal_lr ? c_.learning_rate * (1.0 - static_cast<double>(it) / iterations) : c_.learning_rate;
    st.learning_rate = lr_now_;
    Update(st.epsilon, st);

    const bool stopping = c_.stop != nullptr && c_.stop->load();
    const bool more = it + 1 < iterations && !stopping;
    if (more) {
      CollectRollout();
      env_steps += per_iter;
      rollout_return = mean(rollout_returns_);
      rollout_episodes = static_cast<int>(rollout_returns_.size());
    }
    st.feedback = kNaN;
    st.feedback_before = feedback_prev;
    if (eval_feedback) {
      st.feedback = Evaluate(it, &eval_steps);
    } else if (bandit && more) {
      st.feedback = rollout_return;
    }
    // No bandit update while the policy is held (--critic-warmup): the return did not change because of ε.
    if (bandit && std::isfinite(st.feedback) && std::isfinite(feedback_prev) && it >= c_.critic_warmup) {
      schedule->Update(st.arm, st.feedback, feedback_prev);
      ++feedback_count;
      st.improved = st.feedback > feedback_prev;
      improved_count += st.improved;
    }
    if (std::isfinite(st.feedback)) feedback_prev = st.feedback;
    st.success_rate = feedback_count > 0 ? static_cast<double>(improved_count) / feedback_count : kNaN;
    st.env_steps = env_steps;
    st.eval_steps = eval_steps;
    st.train_return_100 = mean100();
    if (success100_.empty()) {
      st.task_success_100 = kNaN;
    } else {
      double ok = 0;
      for (int x : success100_) ok += x;
      st.task_success_100 = ok / static_cast<double>(success100_.size());
    }
    const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
    st.steps_per_second = elapsed > 0 ? static_cast<double>(env_steps) / elapsed : 0;
    if (csv.is_open()) {
      csv << CsvRow(st);
      csv.flush();
    }
    res.iterations.push_back(st);
    if (progress) {
      Progress p;
      p.iteration = it;
      p.env_steps = env_steps;
      p.eval_steps = eval_steps;
      p.total_steps = c_.total_steps;
      p.steps_per_second = st.steps_per_second;
      p.eta_seconds =
          st.steps_per_second > 0
              ? static_cast<double>(c_.total_steps > env_steps ? c_.total_steps - env_steps : 0) / st.steps_per_second
              : 0;
      p.mean_return = st.train_return_100;
      p.task_success = st.task_success_100;
      p.epsilon = st.epsilon;
      progress(p);
    }
    // --snapshots N: after iterations ceil(k * iterations / N), k = 1..N (the last is the final policy).
    if (c_.snapshots > 0 && (static_cast<std::int64_t>(it + 1) * c_.snapshots) / iterations >
                                (static_cast<std::int64_t>(it) * c_.snapshots) / iterations) {
      // Named by the training steps that produced these parameters (the rollout just collected
      // with them is not one).
      const std::uint64_t trained = static_cast<std::uint64_t>(it + 1) * per_iter;
      char name[64];
      std::snprintf(name, sizeof name, "snapshots/%012llu.blob", static_cast<unsigned long long>(trained));
      if (auto s = WriteCheckpoint(mean100(), trained, name); !s) return s.error();
    }
    if (!c_.out_dir.empty() &&
        std::chrono::duration<double>(Clock::now() - last_checkpoint).count() >= c_.checkpoint_seconds) {
      if (auto s = WriteCheckpoint(mean100(), env_steps); !s) return s.error();
      last_checkpoint = Clock::now();
    }
    if (stopping) {
      res.interrupted = true;
      break;
    }
  }
  res.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  res.env_steps = env_steps;
  res.eval_steps = eval_steps;
  res.final_return = mean100();
  res.steps_per_second = static_cast<double>(env_steps) / res.wall_seconds;
  res.spec = Freeze(res.final_return);
  res.spec.provenance.env_steps = env_steps;
  res.freeze_check = FreezeCheck(res.spec);
  if (!(res.freeze_check <= 1.0)) {
    return MakeError(ErrorCode::kMismatch, "trainer: the frozen policy does not reproduce the trainer's actions (" +
                                               std::to_string(res.freeze_check) + " x the error bound)");
  }
  if (!c_.out_dir.empty()) {
    csv.close();
    if (auto s = WriteCheckpoint(res.final_return, env_steps); !s) return s.error();
    res.plots_note = c_.plots ? Plots(res.iterations) : "plots skipped: --no-plots";
    nlohmann::json j;
    j["env"] = proto_->name();
    if (c_.exploring_starts > 0) j["exploring_starts"] = c_.exploring_starts;
    if (!c_.progress.empty()) j["progress"] = c_.progress;
    if (!c_.geodesic_margin.empty()) j["geodesic_margin"] = c_.geodesic_margin;
    if (!c_.clearance_penalty.empty()) j["clearance_penalty"] = c_.clearance_penalty;
    if (c_.snapshots > 0) j["snapshots"] = c_.snapshots;
    if (c_.extra_obstacles > 0) j["extra_obstacles"] = c_.extra_obstacles;
    if (c_.critic_warmup > 0) j["critic_warmup"] = c_.critic_warmup;
    j["seed"] = c_.seed;
    if (!c_.init_blob.empty()) j["init"] = c_.init_blob;
    j["schedule"] = c_.schedule.Describe();
    j["iterations"] = res.iterations.size();
    j["env_steps"] = env_steps;
    j["eval_steps"] = eval_steps;
    j["total_env_steps"] = env_steps + eval_steps;
    j["final_return_last100"] = std::isfinite(res.final_return) ? nlohmann::json(res.final_return) : nlohmann::json();
    j["wall_seconds"] = res.wall_seconds;
    j["steps_per_second"] = res.steps_per_second;
    j["interrupted"] = res.interrupted;
    j["threads"] = c_.threads;
    j["envs"] = c_.num_envs;
    j["rollout"] = c_.rollout_steps;
    j["learning_rate"] = c_.learning_rate;
    j["anneal_lr"] = c_.anneal_lr;
    j["success_rate"] =
        feedback_count > 0 ? nlohmann::json(static_cast<double>(improved_count) / feedback_count) : nlohmann::json();
    std::vector<int> pulls(c_.schedule.arms.size(), 0);
    for (const auto& s : res.iterations) pulls[static_cast<std::size_t>(s.arm)]++;
    if (!res.iterations.empty() && std::isfinite(res.iterations.back().task_success_100))
      j["task_success_100"] = res.iterations.back().task_success_100;
    j["arms"] = c_.schedule.arms;
    j["arm_pulls"] = pulls;
    j["blob"] = c_.out_dir + "/policy.blob";
    j["git_revision"] = res.spec.provenance.git_revision;
    j["plots"] = res.plots_note;
    if (auto s = WriteText(c_.out_dir + "/summary.json", j.dump(2) + "\n"); !s) return s.error();
  }
  return res;
}

}  // namespace

Result<TrainResult> Train(const TrainConfig& config, const std::function<void(const Progress&)>& progress) {
  if (auto st = config.Validate(); !st) return st.error();
  envs::EnvOptions eo;
  eo.models_dir = config.models_dir;
  eo.layout = config.layout;
  eo.exploring_starts = config.exploring_starts;
  eo.progress = config.progress;
  eo.geodesic_margin = config.geodesic_margin;
  eo.clearance_penalty = config.clearance_penalty;
  eo.extra_obstacles = config.extra_obstacles;
  auto env = envs::MakeEnv(config.env, eo);
  if (!env) return std::move(env).error();
  Trainer t(config, std::move(env).value());
  return t.Run(progress);
}

}  // namespace pbppo::trainer
