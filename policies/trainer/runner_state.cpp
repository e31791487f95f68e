// The runner's resumable state (Runner::SaveState, LoadState): what resume.bin holds
// (checkpoint.hpp) after a whole iteration, and the run rebuilt from it, its environments by replay.
#include <array>
#include <cstdint>
#include <deque>
#include <stdexcept>
#include <string>
#include <vector>

#include "policies/trainer/runner.hpp"
#include "policies/trainer/state_io.hpp"

namespace pbppo::trainer {
namespace {

void PutIteration(ByteWriter& w, const IterationStats& s) {
  w.Put(static_cast<const UpdateStats&>(s));
  w.Put(s.iteration);
  w.Put(s.env_steps);
  w.Put(s.eval_steps);
  w.Put(s.arm);
  for (double x : {s.epsilon, s.feedback, s.feedback_before, s.success_rate, s.train_return, s.train_return_100,
                   s.task_success_100, s.steps_per_second, s.learning_rate})
    w.Put(x);
  w.Put(s.improved);
  w.Put(s.tracking_error_100);
  w.Put(s.episodes);
  w.PutVector(s.arms);
}

IterationStats GetIteration(ByteReader& r) {
  IterationStats s;
  static_cast<UpdateStats&>(s) = r.Get<UpdateStats>("an iteration's update");
  s.iteration = r.Get<int>("an iteration's index");
  s.env_steps = r.Get<std::uint64_t>("an iteration's steps");
  s.eval_steps = r.Get<std::uint64_t>("an iteration's evaluation steps");
  s.arm = r.Get<int>("an iteration's arm");
  for (double* x : {&s.epsilon, &s.feedback, &s.feedback_before, &s.success_rate, &s.train_return, &s.train_return_100,
                    &s.task_success_100, &s.steps_per_second, &s.learning_rate})
    *x = r.Get<double>("an iteration's figures");
  s.improved = r.Get<bool>("an iteration's improvement");
  s.tracking_error_100 = r.Get<std::array<double, 3>>("an iteration's tracking errors");
  s.episodes = r.Get<int>("an iteration's episodes");
  r.GetVector(s.arms, "an iteration's arms");
  return s;
}

template <typename T>
std::vector<T> AsVector(const std::deque<T>& d) {
  return {d.begin(), d.end()};
}

template <typename T>
void GetDeque(ByteReader& r, std::deque<T>& d, const char* field) {
  std::vector<T> v;
  r.GetVector(v, field);
  d.assign(v.begin(), v.end());
}

}  // namespace

std::vector<char> Runner::SaveState(const LoopState& loop, const std::vector<IterationStats>& iterations) {
  // This rank's environments, then every rank's on rank 0 (in environment order).
  ByteWriter mine;
  for (int e = e0_; e < e1_; ++e) {
    const auto k = static_cast<std::size_t>(e - e0_);
    mine.Put(env_rng_[k]);
    mine.Put(traces_[k].start);
    mine.PutVector(traces_[k].actions);
    mine.Put(ep_return_[static_cast<std::size_t>(e)]);
  }
  std::vector<std::vector<char>> parts;
  if (ranks_ > 1) {
    parts = o_.group->AllGather(mine.bytes());
  } else {
    parts.push_back(std::move(mine.bytes()));
  }
  if (rank_ != 0) return {};
  ByteWriter w;
  for (int x : {N_, T_, d_, cd_, a_}) w.Put(x);
  w.Put(loop.next_iteration);
  w.Put(loop.env_steps);
  w.Put(loop.eval_steps);
  for (double x : {loop.rollout_return, loop.feedback_prev, loop.seconds_before}) w.Put(x);
  for (int x : {loop.rollout_episodes, loop.improved_count, loop.feedback_count}) w.Put(x);
  w.PutVector(loop.choices);
  w.Put(static_cast<std::uint64_t>(iterations.size()));
  for (const IterationStats& st : iterations) PutIteration(w, st);
  ppo_.Save(w);
  obs_norm_.Save(w);
  critic_norm_.Save(w);
  ret_rms_.Save(w);
  w.PutVector(disc_ret_);
  w.PutVector(AsVector(last100_));
  w.PutVector(AsVector(success100_));
  w.PutVector(AsVector(tracking100_));
  w.Put(best_return_);
  w.Put(best_success_);
  w.Put(time_);
  const RolloutStorage& r = rollout_;
  w.PutMatrix(r.obs);
  w.PutMatrix(r.critic_obs);
  w.PutMatrix(r.actions);
  w.PutMatrix(r.action_mean);
  w.PutVector(r.log_std);
  w.PutVector(r.raw_obs);
  w.PutVector(r.raw_critic_obs);
  w.PutVector(r.log_prob);
  w.PutVector(r.rewards);
  w.PutVector(r.terminated);
  w.PutVector(r.truncated);
  w.PutMatrix(r.truncation_value_inputs);
  w.PutMatrix(r.last_value_inputs);
  for (const std::vector<char>& part : parts) w.Put(part.data(), part.size());
  return std::move(w.bytes());
}

void Runner::LoadState(const std::vector<char>& bytes, LoopState& loop, std::vector<IterationStats>& iterations) {
  ByteReader in(bytes.data(), bytes.size(), "the resume state");
  static constexpr const char* kShape[] = {"--envs", "--rollout", "the observation size",
                                           "the critic's observation size", "the action size"};
  const int shape[] = {N_, T_, d_, cd_, a_};
  for (int k = 0; k < 5; ++k) {
    const int x = in.Get<int>(kShape[k]);
    if (x != shape[k])
      throw std::runtime_error("the resume state: " + std::string(kShape[k]) + " was " + std::to_string(x) +
                               ", the run has " + std::to_string(shape[k]));
  }
  loop.next_iteration = in.Get<int>("the next iteration");
  if (loop.next_iteration < 0)
    throw std::runtime_error("the resume state: iteration " + std::to_string(loop.next_iteration) + " is negative");
  loop.env_steps = in.Get<std::uint64_t>("the steps");
  loop.eval_steps = in.Get<std::uint64_t>("the evaluation steps");
  for (double* x : {&loop.rollout_return, &loop.feedback_prev, &loop.seconds_before}) *x = in.Get<double>("the loop");
  for (int* x : {&loop.rollout_episodes, &loop.improved_count, &loop.feedback_count}) *x = in.Get<int>("the loop");
  in.GetVector(loop.choices, "the schedule's choices", loop.next_iteration);
  const auto logged = in.Get<std::uint64_t>("the iterations");
  if (logged != static_cast<std::uint64_t>(loop.next_iteration))
    throw std::runtime_error("the resume state: " + std::to_string(logged) + " iterations logged, " +
                             std::to_string(loop.next_iteration) + " run");
  iterations.resize(static_cast<std::size_t>(logged));
  for (IterationStats& st : iterations) st = GetIteration(in);
  ppo_.Load(in);
  obs_norm_.Load(in);
  critic_norm_.Load(in);
  ret_rms_.Load(in);
  in.GetVector(disc_ret_, "the discounted returns", N_);
  GetDeque(in, last100_, "the last 100 returns");
  GetDeque(in, success100_, "the last 100 successes");
  GetDeque(in, tracking100_, "the last 100 tracking errors");
  best_return_ = in.Get<double>("the best return");
  best_success_ = in.Get<double>("the best success");
  time_ = in.Get<TimeShares>("the time shares");
  RolloutStorage& r = rollout_;
  const long B = r.size();
  in.GetMatrix(r.obs, "the rollout's observations");
  in.GetMatrix(r.critic_obs, "the rollout's critic observations");
  in.GetMatrix(r.actions, "the rollout's actions");
  in.GetMatrix(r.action_mean, "the rollout's action means");
  in.GetVector(r.log_std, "the rollout's log-std", a_);
  in.GetVector(r.raw_obs, "the rollout's raw observations", B * d_);
  in.GetVector(r.raw_critic_obs, "the rollout's raw critic observations", B * cd_);
  in.GetVector(r.log_prob, "the rollout's log-probabilities", B);
  in.GetVector(r.rewards, "the rollout's rewards", B);
  in.GetVector(r.terminated, "the rollout's terminations", B);
  in.GetVector(r.truncated, "the rollout's truncations", B);
  in.GetMatrix(r.truncation_value_inputs, "the rollout's truncation value inputs");
  in.GetMatrix(r.last_value_inputs, "the rollout's last value inputs");
  // Every environment's record; this rank's environments replay their episodes so far.
  std::vector<EpisodeTrace> traces(static_cast<std::size_t>(e1_ - e0_));
  for (int e = 0; e < N_; ++e) {
    const Rng now = in.Get<Rng>("an environment's generator");
    EpisodeTrace t{in.Get<Rng>("an environment's episode start"), {}};
    in.GetVector(t.actions, "an environment's episode trace");
    const double ret = in.Get<double>("an environment's episode return");
    if (t.actions.size() % static_cast<std::size_t>(a_) != 0)
      throw std::runtime_error("the resume state: environment " + std::to_string(e) + "'s trace holds " +
                               std::to_string(t.actions.size()) + " values, not whole actions of " +
                               std::to_string(a_));
    if (e < e0_ || e >= e1_) continue;
    const auto k = static_cast<std::size_t>(e - e0_);
    env_rng_[k] = now;
    ep_return_[static_cast<std::size_t>(e)] = ret;
    traces[k] = std::move(t);
  }
  in.CheckEnd();
  std::vector<std::string> errors(static_cast<std::size_t>(pool_.size()));
  pool_.Run([&](int w) {
    for (int e = e0_ + w; e < e1_; e += pool_.size()) {
      const auto k = static_cast<std::size_t>(e - e0_);
      EpisodeTrace& t = traces[k];
      Rng g = t.start;
      envs::Env& env = *envs_[k];
      const std::span<float> raw{raw_obs_cur_.data() + e * d_, static_cast<std::size_t>(d_)};
      env.Reset(g, raw);
      const std::size_t steps = t.actions.size() / static_cast<std::size_t>(a_);
      for (std::size_t j = 0; j < steps; ++j) {
        const envs::StepResult sr =
            env.Step({t.actions.data() + j * static_cast<std::size_t>(a_), static_cast<std::size_t>(a_)}, raw);
        if (sr.terminated || sr.truncated) {
          errors[static_cast<std::size_t>(w)] = "the resume state: environment " + std::to_string(e) +
                                                "'s episode ended at step " + std::to_string(j + 1) + " of " +
                                                std::to_string(steps) + " of its replay (another environment?)";
          break;
        }
      }
      if (cd_ > 0) env.CriticObservation({raw_critic_cur_.data() + e * cd_, static_cast<std::size_t>(cd_)});
      traces_[k].start = t.start;
      traces_[k].actions.assign(t.actions.begin(), t.actions.end());
    }
  });
  for (const std::string& e : errors)
    if (!e.empty()) throw std::runtime_error(e);
}

}  // namespace pbppo::trainer
