#include "policies/trainer/runner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "policies/trainer/checkpoint.hpp"
#include "policies/trainer/exporter.hpp"
#include "policies/trainer/seed.hpp"
#include "policies/trainer/state_io.hpp"

namespace pbppo::trainer {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Mean(const std::vector<double>& v) {
  if (v.empty()) return kNaN;
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

}  // namespace

Runner::Runner(const TrainOptions& o, std::unique_ptr<envs::Env> env)
    : o_(o),
      proto_(std::move(env)),
      pool_(o.threads),
      d_(static_cast<int>(proto_->observation_size())),
      cd_(static_cast<int>(proto_->critic_observation_size())),
      a_(static_cast<int>(proto_->action_size())),
      N_(o.num_envs),
      T_(o.rollout_steps),
      ppo_(o, d_, cd_ > 0 ? cd_ : d_, a_),
      obs_norm_(d_, o.normalize_observations),
      critic_norm_(cd_, o.normalize_observations),
      rollout_(T_, N_, d_, cd_, a_),
      ret_rms_(1) {
  raw_obs_cur_.assign(static_cast<std::size_t>(N_ * d_), 0.f);
  raw_critic_cur_.assign(static_cast<std::size_t>(N_ * cd_), 0.f);
  ep_return_.assign(static_cast<std::size_t>(N_), 0.0);
  disc_ret_.assign(static_cast<std::size_t>(N_), 0.0);
  block_ = BlockSize(N_);
  rank_ = o.rank();
  ranks_ = o.ranks();
  e0_ = RankBegin(rank_);
  e1_ = RankBegin(rank_ + 1);
  const std::size_t trace_capacity = std::min<std::size_t>(proto_->max_episode_steps(), 100000) * a_;
  for (int e = e0_; e < e1_; ++e) {
    envs_.push_back(proto_->Clone());
    env_rng_.emplace_back(Mix(o.seed, 1000 + static_cast<std::uint64_t>(e)));
    traces_.emplace_back();
    traces_.back().actions.reserve(trace_capacity);
    ResetEnv(e);
  }
  // The rank's blocks over its threads, whole blocks each.
  const int b0 = e0_ / block_, blocks = (e1_ - e0_ + block_ - 1) / block_;
  const int W = std::min(pool_.size(), blocks);
  workers_.assign(static_cast<std::size_t>(W), Worker{});
  for (int w = 0; w < W; ++w) {
    workers_[static_cast<std::size_t>(w)].e0 = std::min(e1_, (b0 + blocks * w / W) * block_);
    workers_[static_cast<std::size_t>(w)].e1 = std::min(e1_, (b0 + blocks * (w + 1) / W) * block_);
  }
}

void Runner::ResetEnv(int e) {
  const auto k = static_cast<std::size_t>(e - e0_);
  traces_[k].start = env_rng_[k];
  traces_[k].actions.clear();
  envs_[k]->Reset(env_rng_[k], {raw_obs_cur_.data() + e * d_, static_cast<std::size_t>(d_)});
  if (cd_ > 0) envs_[k]->CriticObservation({raw_critic_cur_.data() + e * cd_, static_cast<std::size_t>(cd_)});
}

int Runner::RankBegin(int r) const {
  const int blocks = (N_ + block_ - 1) / block_;
  return std::min(N_, blocks * r / ranks_ * block_);
}

void Runner::ValueInput(int e, float* out) const {
  if (cd_ > 0) {
    critic_norm_.Normalize(raw_critic_cur_.data() + e * cd_, out);
  } else {
    obs_norm_.Normalize(raw_obs_cur_.data() + e * d_, out);
  }
}

void Runner::RolloutWorker(Worker& w) {
  RolloutStorage& r = rollout_;
  w.episodes.clear();
  w.policy_seconds = w.env_seconds = 0;
  const float* log_std = ppo_.log_std();
  std::vector<float> stdv(static_cast<std::size_t>(a_)), act(static_cast<std::size_t>(a_));
  const double half_log_2pi = 0.5 * std::log(2.0 * M_PI);
  for (int j = 0; j < a_; ++j) stdv[static_cast<std::size_t>(j)] = std::exp(log_std[j]);
  // Block by block (its forward pass the same product whoever runs it), each block through all its
  // steps before the next: the block's simulations stay in the cache (each environment's steps
  // depend on nothing outside it, so the order changes no result).
  for (int eb = w.e0; eb < w.e1; eb += block_) {
    const int eb1 = std::min(eb + block_, w.e1);
    for (int t = 0; t < T_; ++t) {
      const auto c0 = Clock::now();
      w.x.resize(d_, eb1 - eb);
      for (int e = eb; e < eb1; ++e) {
        const long i = static_cast<long>(t) * N_ + e;
        const float* raw = raw_obs_cur_.data() + e * d_;
        std::copy(raw, raw + d_, r.raw_obs.data() + i * d_);
        obs_norm_.Normalize(raw, w.x.col(e - eb).data());
        r.obs.col(i) = w.x.col(e - eb);
        if (cd_ > 0) {
          const float* raw_c = raw_critic_cur_.data() + e * cd_;
          std::copy(raw_c, raw_c + cd_, r.raw_critic_obs.data() + i * cd_);
          critic_norm_.Normalize(raw_c, r.critic_obs.col(i).data());
        }
      }
      const Mat<float>& mu = ppo_.actor().mean.Forward(ppo_.actor_params(), w.x, w.ws);
      const auto c1 = Clock::now();
      for (int e = eb; e < eb1; ++e) {
        const long i = static_cast<long>(t) * N_ + e;
        const auto ui = static_cast<std::size_t>(i);
        const int c = e - eb;
        Rng& rng = env_rng_[static_cast<std::size_t>(e - e0_)];
        envs::Env& env = *envs_[static_cast<std::size_t>(e - e0_)];
        float lp = 0;
        for (int j = 0; j < a_; ++j) {
          const auto k = static_cast<std::size_t>(j);
          const float sample = mu(j, c) + stdv[k] * static_cast<float>(rng.Normal());
          r.actions(j, i) = sample;
          r.action_mean(j, i) = mu(j, c);
          const float z = (sample - mu(j, c)) * std::exp(-log_std[j]);
          lp += -0.5f * z * z - log_std[j];
          act[k] = std::clamp(sample, env.action_low()[k], env.action_high()[k]);
        }
        r.log_prob[ui] = lp - static_cast<float>(a_ * half_log_2pi);
        const std::span<float> raw{raw_obs_cur_.data() + e * d_, static_cast<std::size_t>(d_)};
        const std::span<float> raw_c{raw_critic_cur_.data() + e * cd_, static_cast<std::size_t>(cd_)};
        std::vector<float>& trace = traces_[static_cast<std::size_t>(e - e0_)].actions;
        trace.insert(trace.end(), act.begin(), act.end());
        const envs::StepResult s = env.Step(act, raw);
        if (cd_ > 0) env.CriticObservation(raw_c);
        r.rewards[ui] = static_cast<float>(s.reward);
        r.terminated[ui] = s.terminated;
        r.truncated[ui] = s.truncated && !s.terminated;
        ep_return_[static_cast<std::size_t>(e)] += s.reward;
        if (s.terminated || s.truncated) {
          if (!s.terminated) ValueInput(e, r.truncation_value_inputs.col(i).data());
          const envs::EpisodeInfo info = env.episode_info();
          w.episodes.push_back({i, ep_return_[static_cast<std::size_t>(e)],
                                info.available ? (info.success ? 1 : 0) : -1, info.tracking_error});
          ep_return_[static_cast<std::size_t>(e)] = 0;
          ResetEnv(e);
        }
      }
      w.policy_seconds += std::chrono::duration<double>(c1 - c0).count();
      w.env_seconds += std::chrono::duration<double>(Clock::now() - c1).count();
    }
  }
  for (int e = w.e0; e < w.e1; ++e) ValueInput(e, r.last_value_inputs.col(e).data());
}

void Runner::CollectRollout() {
  obs_norm_.Freeze();
  critic_norm_.Freeze();
  std::copy(ppo_.log_std(), ppo_.log_std() + a_, rollout_.log_std.begin());
  const auto t0 = Clock::now();
  pool_.Run([&](int w) {
    if (w < static_cast<int>(workers_.size())) RolloutWorker(workers_[static_cast<std::size_t>(w)]);
  });
  const auto t1 = Clock::now();
  time_.rollout += std::chrono::duration<double>(t1 - t0).count();
  if (!workers_.empty()) {
    time_.rollout_policy += workers_[0].policy_seconds;
    time_.rollout_env += workers_[0].env_seconds;
  }
  std::vector<Episode> eps;
  for (auto& w : workers_) eps.insert(eps.end(), w.episodes.begin(), w.episodes.end());
  if (ranks_ > 1) {
    ShareRollout(eps);
    time_.exchange += std::chrono::duration<double>(Clock::now() - t1).count();
  }
  std::sort(eps.begin(), eps.end(), [](const Episode& a, const Episode& b) { return a.index < b.index; });
  rollout_returns_.clear();
  for (const Episode& ep : eps) {
    rollout_returns_.push_back(ep.ret);
    last100_.push_back(ep.ret);
    if (last100_.size() > 100) last100_.pop_front();
    if (ep.success >= 0) {
      success100_.push_back(ep.success);
      if (success100_.size() > 100) success100_.pop_front();
    }
    if (std::isfinite(ep.tracking[0])) {
      tracking100_.push_back(ep.tracking);
      if (tracking100_.size() > 100) tracking100_.pop_front();
    }
  }
  RolloutStorage& r = rollout_;
  obs_norm_.Update(r.raw_obs.data(), r.size());
  critic_norm_.Update(r.raw_critic_obs.data(), r.size());
  if (o_.scale_rewards) {
    // Running discounted return per environment (reset at episode ends), its variance, and
    // rewards divided by its standard deviation and clipped to +-10.
    std::vector<float> rets(r.rewards.size());
    for (long i = 0; i < static_cast<long>(r.rewards.size()); ++i) {
      const auto e = static_cast<std::size_t>(i % N_);
      const auto ui = static_cast<std::size_t>(i);
      disc_ret_[e] = disc_ret_[e] * o_.gamma + r.rewards[ui];
      rets[ui] = static_cast<float>(disc_ret_[e]);
      if (r.terminated[ui] || r.truncated[ui]) disc_ret_[e] = 0;
    }
    ret_rms_.Update(rets.data(), static_cast<long>(rets.size()));
    const double s = std::sqrt(ret_rms_.var()[0] + 1e-8);
    for (float& x : r.rewards) x = static_cast<float>(std::clamp(x / s, -10.0, 10.0));
  }
}

void Runner::ShareRollout(std::vector<Episode>& episodes) {
  RolloutStorage& r = rollout_;
  const int vd = r.value_input_size();
  const auto D = static_cast<std::size_t>(d_), CD = static_cast<std::size_t>(cd_), A = static_cast<std::size_t>(a_),
             VD = static_cast<std::size_t>(vd);
  // Environment e's samples at every step, its last value input, then its rank's finished episodes.
  auto transfer = [&](int e0, int e1, auto&& io) {
    for (int t = 0; t < T_; ++t) {
      for (int e = e0; e < e1; ++e) {
        const long i = static_cast<long>(t) * N_ + e;
        const auto ui = static_cast<std::size_t>(i);
        io(r.raw_obs.data() + ui * D, D);
        io(r.obs.col(i).data(), D);
        if (cd_ > 0) {
          io(r.raw_critic_obs.data() + ui * CD, CD);
          io(r.critic_obs.col(i).data(), CD);
        }
        io(r.actions.col(i).data(), A);
        io(r.action_mean.col(i).data(), A);
        io(&r.log_prob[ui], 1);
        io(&r.rewards[ui], 1);
        io(&r.terminated[ui], 1);
        io(&r.truncated[ui], 1);
        if (r.truncated[ui]) io(r.truncation_value_inputs.col(i).data(), VD);  // read after its flag
      }
    }
    for (int e = e0; e < e1; ++e) io(r.last_value_inputs.col(e).data(), VD);
  };
  ByteWriter mine;
  transfer(e0_, e1_, [&](auto* p, std::size_t n) { mine.Put(p, n); });
  mine.PutVector(episodes);
  const std::vector<std::vector<char>> all = o_.group->AllGather(mine.bytes());
  for (int q = 0; q < ranks_; ++q) {
    if (q == rank_) continue;
    const std::vector<char>& bytes = all[static_cast<std::size_t>(q)];
    ByteReader in(bytes.data(), bytes.size(), "rank " + std::to_string(q) + "'s rollout");
    transfer(RankBegin(q), RankBegin(q + 1), [&](auto* p, std::size_t n) { in.Get(p, n); });
    std::vector<Episode> theirs;
    in.GetVector(theirs, "episodes");
    in.CheckEnd();
    episodes.insert(episodes.end(), theirs.begin(), theirs.end());
  }
}

double Runner::Evaluate(int iteration, std::uint64_t* steps) {
  const auto t0 = Clock::now();
  const int k = o_.schedule.eval_episodes;
  std::vector<double> returns(static_cast<std::size_t>(k), 0.0);
  std::vector<std::uint64_t> counts(static_cast<std::size_t>(k), 0);
  // Episode ep on rank ep % ranks, spread over its threads; each episode's own seed.
  pool_.Run([&](int w) {
    typename Mlp<float>::Workspace ws;
    Mat<float> x(d_, 1);
    std::vector<float> raw(static_cast<std::size_t>(d_)), act(static_cast<std::size_t>(a_));
    for (int ep = rank_ + w * ranks_; ep < k; ep += pool_.size() * ranks_) {
      auto env = proto_->Clone();
      Rng rng(Mix(Mix(o_.seed, 7), static_cast<std::uint64_t>(iteration) * 4096 + static_cast<std::uint64_t>(ep)));
      env->Reset(rng, raw);
      double ret = 0;
      std::uint64_t n = 0;
      for (;;) {
        obs_norm_.Normalize(raw.data(), x.data());
        const Mat<float>& mu = ppo_.actor().mean.Forward(ppo_.actor_params(), x, ws);
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
  const auto t1 = Clock::now();
  time_.evaluation += std::chrono::duration<double>(t1 - t0).count();
  if (ranks_ > 1) {
    ByteWriter mine;
    for (int ep = rank_; ep < k; ep += ranks_) {
      mine.Put(&returns[static_cast<std::size_t>(ep)], 1);
      mine.Put(&counts[static_cast<std::size_t>(ep)], 1);
    }
    const std::vector<std::vector<char>> all = o_.group->AllGather(mine.bytes());
    for (int q = 0; q < ranks_; ++q) {
      if (q == rank_) continue;
      const std::vector<char>& bytes = all[static_cast<std::size_t>(q)];
      ByteReader in(bytes.data(), bytes.size(), "rank " + std::to_string(q) + "'s evaluation returns");
      for (int ep = q; ep < k; ep += ranks_) {
        in.Get(&returns[static_cast<std::size_t>(ep)], 1);
        in.Get(&counts[static_cast<std::size_t>(ep)], 1);
      }
      in.CheckEnd();
    }
    time_.exchange += std::chrono::duration<double>(Clock::now() - t1).count();
  }
  double sum = 0;
  for (int ep = 0; ep < k; ++ep) {
    sum += returns[static_cast<std::size_t>(ep)];
    *steps += counts[static_cast<std::size_t>(ep)];
  }
  return sum / k;
}

bool Runner::StopRequested() const {
  const char mine = o_.stop != nullptr && o_.stop->load() ? 1 : 0;
  if (ranks_ == 1) return mine != 0;
  // Any rank's stop stops them all, at the same iteration.
  for (const std::vector<char>& v : o_.group->AllGather({&mine, 1}))
    if (v.size() == 1 && v[0] != 0) return true;
  return false;
}

double Runner::Mean100() const {
  if (last100_.empty()) return kNaN;
  double s = 0;
  for (double x : last100_) s += x;
  return s / static_cast<double>(last100_.size());
}

std::array<double, 3> Runner::Tracking100() const {
  if (tracking100_.empty()) return {kNaN, kNaN, kNaN};
  std::array<double, 3> m{};
  for (const auto& t : tracking100_)
    for (std::size_t k = 0; k < 3; ++k) m[k] += t[k];
  for (double& x : m) x /= static_cast<double>(tracking100_.size());
  return m;
}

double Runner::TaskSuccess100() const {
  if (success100_.empty()) return kNaN;
  double ok = 0;
  for (int x : success100_) ok += x;
  return ok / static_cast<double>(success100_.size());
}

policy::PolicySpec Runner::Freeze(double final_return, std::uint64_t env_steps) const {
  return FreezeActor(ppo_.actor(), ppo_.actor_params(), obs_norm_, *proto_,
                     {o_.schedule.Describe(), o_.seed, env_steps, final_return});
}

Status Runner::WriteCheckpoint(double final_return, std::uint64_t env_steps, const std::string& name) {
  if (o_.out_dir.empty() || rank_ != 0) return {};  // rank 0 writes
  return WritePolicy(o_.out_dir + "/" + name, Freeze(final_return, env_steps), o_.seed);
}

Result<TrainResult> Runner::Learn(const std::function<void(const Progress&)>& progress) {
  if (!o_.init_blob.empty()) {
    if (auto st = LoadActor(o_.init_blob, *proto_, ppo_.actor(), ppo_.actor_params(), &obs_norm_); !st)
      return st.error();
  }
  TrainResult res;
  const auto t0 = Clock::now();
  Logger log(o_);
  const bool writer = rank_ == 0;  // of the run's results: log, summary, plots, blobs, progress
  auto schedule = MakeClipSchedule(o_.schedule);
  const bool bandit = schedule->uses_feedback();
  const bool eval_feedback = bandit && o_.schedule.feedback == FeedbackSource::kEval;
  const std::uint64_t per_iter = static_cast<std::uint64_t>(T_) * static_cast<std::uint64_t>(N_);
  const int iterations = static_cast<int>((o_.total_steps + per_iter - 1) / per_iter);

  LoopState loop;
  if (!o_.resume_state.empty()) {
    try {
      LoadState(o_.resume_state, loop, res.iterations);
    } catch (const std::exception& e) {
      return MakeError(ErrorCode::kFormat, std::string("--resume: ") + e.what());
    }
    // The schedule's state is what its calls made it: the same calls again.
    for (std::size_t i = 0; i < loop.choices.size(); ++i) {
      const LoopState::Choice& c = loop.choices[i];
      const int arm = schedule->Choose();
      if (arm != c.arm)
        return MakeError(ErrorCode::kMismatch, "--resume: the clip schedule chose arm " + std::to_string(arm) +
                                                   " at iteration " + std::to_string(i) + ", the run arm " +
                                                   std::to_string(c.arm));
      if (c.updated) schedule->Update(c.arm, c.after, c.before);
    }
  }
  if (writer) {
    if (auto st = log.Open(res.iterations); !st) return st.error();
  }
  if (o_.resume_state.empty()) {
    CollectRollout();
    loop.env_steps += per_iter;
    loop.rollout_return = Mean(rollout_returns_);
    loop.rollout_episodes = static_cast<int>(rollout_returns_.size());
    loop.feedback_prev = eval_feedback ? Evaluate(-1, &loop.eval_steps) : loop.rollout_return;
  }
  auto last_checkpoint = Clock::now();
  // Wall seconds of the run so far: the processes' before this one (a resumed run's) and this one's.
  const double seconds_before = loop.seconds_before;
  auto elapsed = [&] { return seconds_before + std::chrono::duration<double>(Clock::now() - t0).count(); };

  for (int it = loop.next_iteration; it < iterations; ++it) {
    // --keep-best: the parameters that collected the best last-100-episode task success (or, for
    // environments without one, return) so far (these episodes were collected by this and the few
    // previous iterations' policies).
    if (o_.keep_best && last100_.size() >= 100) {
      const double success = success100_.size() >= 100 ? TaskSuccess100() : -1.0;
      if (success > best_success_ || (success == best_success_ && Mean100() > best_return_)) {
        best_success_ = success;
        best_return_ = Mean100();
        if (auto s = WriteCheckpoint(best_return_, loop.env_steps, "best.blob"); !s) return s.error();
      }
    }
    IterationStats st;
    st.iteration = it;
    st.train_return = loop.rollout_return;
    st.episodes = loop.rollout_episodes;
    const auto r0 = Clock::now();
    ppo_.ComputeReturns(rollout_, pool_);
    const auto r1 = Clock::now();
    time_.returns += std::chrono::duration<double>(r1 - r0).count();
    const double explained_variance = Ppo::ExplainedVariance(rollout_);
    st.arm = schedule->Choose();
    st.arms = schedule->arms();
    st.epsilon = schedule->epsilon(st.arm);
    if (o_.lr_schedule.kind != LrSchedule::Kind::kAdaptive)
      ppo_.set_learning_rate(o_.lr_schedule.AtIteration(o_.learning_rate, it, iterations));
    // --critic-warmup: the value network learns, the policy stays as it is.
    static_cast<UpdateStats&>(st) = ppo_.Update(rollout_, st.epsilon, it < o_.critic_warmup, pool_, o_.group);
    time_.update += std::chrono::duration<double>(Clock::now() - r1).count() - st.exchange_seconds;
    time_.exchange += st.exchange_seconds;
    st.explained_variance = explained_variance;
    st.learning_rate = ppo_.learning_rate();

    const bool stopping = StopRequested();
    // The next rollout is collected even when stopping: the iteration is then whole (its feedback
    // given), and the run can resume from it.
    const bool more = it + 1 < iterations;
    if (more) {
      CollectRollout();
      loop.env_steps += per_iter;
      loop.rollout_return = Mean(rollout_returns_);
      loop.rollout_episodes = static_cast<int>(rollout_returns_.size());
    }
    st.feedback = kNaN;
    st.feedback_before = loop.feedback_prev;
    if (eval_feedback) {
      st.feedback = Evaluate(it, &loop.eval_steps);
    } else if (bandit && more) {
      st.feedback = loop.rollout_return;
    }
    LoopState::Choice choice{st.arm, 0, st.feedback, loop.feedback_prev};
    // No bandit update while the policy is held (--critic-warmup): the return did not change because of ε.
    if (bandit && std::isfinite(st.feedback) && std::isfinite(loop.feedback_prev) && it >= o_.critic_warmup) {
      schedule->Update(st.arm, st.feedback, loop.feedback_prev);
      choice.updated = 1;
      ++loop.feedback_count;
      st.improved = st.feedback > loop.feedback_prev;
      loop.improved_count += st.improved;
    }
    loop.choices.push_back(choice);
    if (std::isfinite(st.feedback)) loop.feedback_prev = st.feedback;
    st.success_rate = loop.feedback_count > 0 ? static_cast<double>(loop.improved_count) / loop.feedback_count : kNaN;
    st.env_steps = loop.env_steps;
    st.eval_steps = loop.eval_steps;
    st.train_return_100 = Mean100();
    st.task_success_100 = TaskSuccess100();
    st.tracking_error_100 = Tracking100();
    st.steps_per_second = static_cast<double>(loop.env_steps) / elapsed();
    if (writer) log.Log(st);
    res.iterations.push_back(st);
    if (progress && writer) {
      Progress p;
      p.iteration = it;
      p.env_steps = loop.env_steps;
      p.eval_steps = loop.eval_steps;
      p.total_steps = o_.total_steps;
      p.steps_per_second = st.steps_per_second;
      p.eta_seconds = st.steps_per_second > 0
                          ? static_cast<double>(o_.total_steps > loop.env_steps ? o_.total_steps - loop.env_steps : 0) /
                                st.steps_per_second
                          : 0;
      p.mean_return = st.train_return_100;
      p.task_success = st.task_success_100;
      p.tracking_error = st.tracking_error_100;
      p.epsilon = st.epsilon;
      progress(p);
    }
    // --snapshots N: after iterations ceil(k * iterations / N), k = 1..N (the last is the final policy).
    if (o_.snapshots > 0 && (static_cast<std::int64_t>(it + 1) * o_.snapshots) / iterations >
                                (static_cast<std::int64_t>(it) * o_.snapshots) / iterations) {
      // Named by the training steps that produced these parameters (the rollout just collected
      // with them is not one).
      const std::uint64_t trained = static_cast<std::uint64_t>(it + 1) * per_iter;
      char name[64];
      std::snprintf(name, sizeof name, "snapshots/%012llu.blob", static_cast<unsigned long long>(trained));
      if (auto s = WriteCheckpoint(Mean100(), trained, name); !s) return s.error();
    }
    if (!o_.out_dir.empty() &&
        std::chrono::duration<double>(Clock::now() - last_checkpoint).count() >= o_.checkpoint_seconds) {
      if (auto s = WriteCheckpoint(Mean100(), loop.env_steps); !s) return s.error();
      last_checkpoint = Clock::now();
    }
    // --resume-every N: the state to continue from, after every N iterations and at a stop.
    loop.next_iteration = it + 1;
    if (more && !o_.out_dir.empty() && o_.resume_every > 0 && ((it + 1) % o_.resume_every == 0 || stopping)) {
      loop.seconds_before = elapsed();
      const std::vector<char> state = SaveState(loop, res.iterations);
      if (writer) {
        if (auto s = WriteResumeFile(o_.out_dir + "/" + kResumeFile, {o_.command_args, BuildGitRevision(), state}); !s)
          return s.error();
      }
    }
    if (stopping) {
      res.interrupted = true;
      break;
    }
  }
  res.wall_seconds = elapsed();
  res.env_steps = loop.env_steps;
  res.eval_steps = loop.eval_steps;
  res.final_return = Mean100();
  res.steps_per_second = static_cast<double>(loop.env_steps) / res.wall_seconds;
  res.ranks = ranks_;
  res.threads = pool_.size();
  res.time = time_;
  res.time.other =
      res.wall_seconds - (time_.rollout + time_.returns + time_.update + time_.evaluation + time_.exchange);
  res.spec = Freeze(res.final_return, loop.env_steps);
  res.freeze_check = CheckFrozen(res.spec, ppo_.actor(), ppo_.actor_params(), obs_norm_, *proto_,
                                 rollout_.raw_obs.data(), rollout_.size());
  if (!(res.freeze_check <= 1.0)) {
    return MakeError(ErrorCode::kMismatch, "trainer: the frozen policy does not reproduce the trainer's actions (" +
                                               std::to_string(res.freeze_check) + " x the error bound)");
  }
  if (auto s = WriteCheckpoint(res.final_return, loop.env_steps); !s) return s.error();
  if (writer) {
    if (auto s = log.Finish(proto_->name(), proto_->provenance(), res); !s) return s.error();
    // A finished run has nothing to resume.
    if (!res.interrupted && !o_.out_dir.empty()) {
      std::error_code ec;
      std::filesystem::remove(o_.out_dir + "/" + kResumeFile, ec);
    }
  }
  return res;
}

Result<TrainResult> Train(const TrainOptions& options, std::unique_ptr<envs::Env> env,
                          const std::function<void(const Progress&)>& progress) {
  if (auto st = options.Validate(); !st) return st.error();
  Runner runner(options, std::move(env));
  return runner.Learn(progress);
}

Result<TrainResult> Train(const TrainOptions& options, const std::function<void(const Progress&)>& progress) {
  if (auto st = options.Validate(); !st) return st.error();
  auto env = envs::MakeEnv(options.env);
  if (!env) return std::move(env).error();
  return Train(options, std::move(env).value(), progress);
}

}  // namespace pbppo::trainer
