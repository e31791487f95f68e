// The on-policy runner (rsl_rl's OnPolicyRunner): N environments stepped by worker threads with
// the actor sampling actions, evaluation episodes for the bandit's feedback, and the learning loop
// (collect, returns, clip bound from the schedule, update, feedback, log, checkpoints), which ends
// in the frozen blob (exporter.hpp). Same seed and same thread count give a bit-identical run.
#pragma once

#include <array>
#include <deque>
#include <functional>
#include <memory>
#include <tuple>
#include <vector>

#include "policies/envs/env.hpp"
#include "policies/trainer/logger.hpp"
#include "policies/trainer/normalizer.hpp"
#include "policies/trainer/options.hpp"
#include "policies/trainer/ppo.hpp"
#include "policies/trainer/rollout_storage.hpp"
#include "policies/trainer/worker_pool.hpp"
#include "runtime/core/random.hpp"

namespace pbppo::trainer {

class Runner {
 public:
  // `env` is the prototype: every worker environment is a Clone() of it.
  Runner(const TrainOptions& options, std::unique_ptr<envs::Env> env);

  Result<TrainResult> Learn(const std::function<void(const Progress&)>& progress);

 private:
  // A finished training episode.
  struct Episode {
    long index = 0;  // t*N+e of its last step
    double ret = 0;
    int success = -1;                  // 1, 0, or -1: the environment has no notion of success
    std::array<double, 3> tracking{};  // EpisodeInfo::tracking_error
  };
  // A worker thread's share of the environments, [e0, e1), and its scratch.
  struct Worker {
    int e0 = 0, e1 = 0;
    Mat<float> x;
    typename Mlp<float>::Workspace ws;
    std::vector<Episode> episodes;
  };

  void CollectRollout();
  void RolloutWorker(Worker& w);
  // The critic's input for the state environment e's buffers hold, into `out`.
  void ValueInput(int e, float* out) const;
  // Mean return of the schedule's k deterministic evaluation episodes; their steps are added to *steps.
  double Evaluate(int iteration, std::uint64_t* steps);
  double Mean100() const;
  double TaskSuccess100() const;              // NaN: no episode reported success
  std::array<double, 3> Tracking100() const;  // NaN: no episode reported tracking errors
  policy::PolicySpec Freeze(double final_return, std::uint64_t env_steps) const;
  Status WriteCheckpoint(double final_return, std::uint64_t env_steps, const std::string& name = "policy.blob");

  const TrainOptions& o_;
  std::unique_ptr<envs::Env> proto_;
  WorkerPool pool_;
  int d_ = 0, cd_ = 0, a_ = 0, N_ = 0, T_ = 0;  // observation, critic observation, action sizes; envs; steps
  Ppo ppo_;
  ObservationNormalizer obs_norm_, critic_norm_;
  RolloutStorage rollout_;
  std::vector<std::unique_ptr<envs::Env>> envs_;
  std::vector<Rng> env_rng_;
  std::vector<float> raw_obs_cur_, raw_critic_cur_;  // [N][d], [N][cd]: each environment's latest
  std::vector<double> ep_return_, disc_ret_;
  RunningMeanStd ret_rms_;
  std::vector<Worker> workers_;
  std::vector<double> rollout_returns_;
  std::deque<double> last100_;
  std::deque<int> success100_;                     // task success of the last 100 training episodes (where known)
  std::deque<std::array<double, 3>> tracking100_;  // tracking errors of the last 100 (where known)
  double best_return_ = -std::numeric_limits<double>::infinity();
  double best_success_ = -1.0;  // -1: no task success known
};

// Checks the options, builds the environment (envs::MakeEnv) and runs.
Result<TrainResult> Train(const TrainOptions& options, const std::function<void(const Progress&)>& progress = {});
// The same on a given environment (tests bring their own).
Result<TrainResult> Train(const TrainOptions& options, std::unique_ptr<envs::Env> env,
                          const std::function<void(const Progress&)>& progress = {});

}  // namespace pbppo::trainer
