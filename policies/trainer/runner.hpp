// The on-policy runner (rsl_rl's OnPolicyRunner): N environments stepped by worker threads with
// the actor sampling actions, evaluation episodes for the bandit's feedback, and the learning loop
// (collect, returns, clip bound from the schedule, update, feedback, log, checkpoints), which ends
// in the frozen blob (exporter.hpp).
//
// Data-parallel over ranks (TrainOptions::group): each rank steps its share of the environments
// and its share of the evaluation episodes, the ranks exchange what they collected, and every rank
// then holds the whole rollout and does what follows from it the same way (normaliser statistics,
// returns, the schedule's choice and feedback); the update's chunk gradients are computed once,
// on their rank, and exchanged (Ppo::Update). The environments are stepped and the actor run in
// blocks of a fixed number of environments that depend on N alone, and a rank or thread takes whole
// blocks: every matrix product has the same shape however the work is split, so the same seed and
// N give bit-identical weights for any number of ranks and threads.
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
  // The learning loop's own state between iterations (what a resumed run continues from).
  struct LoopState {
    int next_iteration = 0;
    std::uint64_t env_steps = 0, eval_steps = 0;
    double rollout_return = 0, feedback_prev = 0, seconds_before = 0;
    int rollout_episodes = 0, improved_count = 0, feedback_count = 0;
    // Per iteration: the arm chosen, and the schedule's feedback if it had any (replayed on resume:
    // the schedule's state is what its calls made it).
    struct Choice {
      int arm = 0;
      std::uint8_t updated = 0;
      double after = 0, before = 0;
    };
    std::vector<Choice> choices;
  };
  // An environment's episode so far: the generator's state before its reset and the actions it has
  // taken since (a resumed run replays them to rebuild the environment's state).
  struct EpisodeTrace {
    Rng start;
    std::vector<float> actions;
  };
  // A finished training episode.
  struct Episode {
    long index = 0;  // t*N+e of its last step
    double ret = 0;
    int success = -1;                  // 1, 0, or -1: the environment has no notion of success
    std::array<double, 3> tracking{};  // EpisodeInfo::tracking_error
  };
  // A worker thread's share of the environments, [e0, e1) (whole blocks), and its scratch.
  struct Worker {
    int e0 = 0, e1 = 0;
    double policy_seconds = 0, env_seconds = 0;  // this iteration's rollout: the actor's forward passes, the steps
    Mat<float> x;
    typename Mlp<float>::Workspace ws;
    std::vector<Episode> episodes;
  };

  void CollectRollout();
  void RolloutWorker(Worker& w);
  // Ranks: every rank's samples, last value inputs and finished episodes onto every rank.
  void ShareRollout(std::vector<Episode>& episodes);
  // The first environment of rank r's blocks (r = ranks: N).
  int RankBegin(int r) const;
  // The critic's input for the state environment e's buffers hold, into `out`.
  void ValueInput(int e, float* out) const;
  // Mean return of the schedule's k deterministic evaluation episodes; their steps are added to *steps.
  double Evaluate(int iteration, std::uint64_t* steps);
  // A stop was asked for (TrainOptions::stop), on any rank.
  bool StopRequested() const;
  // The state of the run after a whole iteration (its next rollout collected), as resume.bin holds it
  // (every rank calls it; rank 0 gets the bytes); and the run rebuilt from them.
  std::vector<char> SaveState(const LoopState& loop, const std::vector<IterationStats>& iterations);
  void LoadState(const std::vector<char>& bytes, LoopState& loop, std::vector<IterationStats>& iterations);
  // Environment e (this rank's) resets and its episode trace starts again.
  void ResetEnv(int e);
  double Mean100() const;
  double TaskSuccess100() const;              // NaN: no episode reported success
  std::array<double, 3> Tracking100() const;  // NaN: no episode reported tracking errors
  policy::PolicySpec Freeze(double final_return, std::uint64_t env_steps) const;
  Status WriteCheckpoint(double final_return, std::uint64_t env_steps, const std::string& name = "policy.blob");

  const TrainOptions& o_;
  std::unique_ptr<envs::Env> proto_;
  WorkerPool pool_;
  int d_ = 0, cd_ = 0, a_ = 0, N_ = 0, T_ = 0;  // observation, critic observation, action sizes; envs; steps
  int block_ = 1;                               // environments per block (BlockSize)
  int rank_ = 0, ranks_ = 1, e0_ = 0, e1_ = 0;  // this rank, of ranks_; its environments [e0_, e1_)
  Ppo ppo_;
  ObservationNormalizer obs_norm_, critic_norm_;
  RolloutStorage rollout_;
  std::vector<std::unique_ptr<envs::Env>> envs_;     // this rank's, from e0_
  std::vector<Rng> env_rng_;                         // this rank's, from e0_
  std::vector<EpisodeTrace> traces_;                 // this rank's, from e0_
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
  TimeShares time_{};
};

// Checks the options, builds the environment (envs::MakeEnv) and runs.
Result<TrainResult> Train(const TrainOptions& options, const std::function<void(const Progress&)>& progress = {});
// The same on a given environment (tests bring their own).
Result<TrainResult> Train(const TrainOptions& options, std::unique_ptr<envs::Env> env,
                          const std::function<void(const Progress&)>& progress = {});

}  // namespace pbppo::trainer
