// The PPO trainer: rollouts on N environments stepped in parallel, GAE, clipped-surrogate
// updates with the clip bound chosen each iteration by a clip schedule (Pb-PPO), a per-iteration
// CSV log, a JSON summary, plots, and the frozen policy blob with golden vectors.
// Same seed and same thread count give a bit-identical run.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "policies/trainer/clip_schedule.hpp"
#include "runtime/core/result.hpp"
#include "runtime/policy/policy_spec.hpp"

namespace pbppo::trainer {

struct TrainConfig {
  std::string env = "pendulum";
  std::string models_dir;         // empty: envs::DefaultModelsDir()
  std::string layout = "hard";    // obstacle layout of environments that have several (auv-nav)
  double exploring_starts = 0.0;  // auv-nav: probability of an episode starting anywhere (training only)
  std::string progress;           // auv-nav: "euclidean" or "geodesic" reward progress; empty: auv.yaml's
  std::string geodesic_margin;    // auv-nav: "D:C", the geodesic path's margin; empty: auv.yaml's
  std::string clearance_penalty;  // auv-nav: "D:W", the reward's clearance term; empty: auv.yaml's
  int extra_obstacles = 0;        // auv-nav, training: random obstacles beyond each layout's count
  std::string terrain = "flat";   // quadruped-walk: flat or mixed
  std::string commands;           // quadruped-walk: "VX:VY:YAW" command maxima; empty: walk.yaml's
  std::uint64_t seed = 1;
  std::uint64_t total_steps = 200000;  // training environment steps (evaluation steps are extra)
  int num_envs = 1;
  int rollout_steps = 2048;  // per environment and iteration
  int threads = 1;
  int minibatch = 64;
  int epochs = 10;
  double learning_rate = 3e-4;
  bool anneal_lr = false;  // linear decay of the learning rate to 0 over the budget
  // Also write best.blob: the policy of the best last-100-episode task success where the
  // environment reports one (ties: the better return), otherwise of the best return.
  bool keep_best = false;
  // Also write this many blobs evenly spaced over the run into snapshots/ (named by the training
  // steps that produced them), to choose among afterwards on held-out episodes. 0: none.
  int snapshots = 0;
  double gamma = 0.99;
  double gae_lambda = 0.95;
  double ent_coef = 0.0;
  double vf_coef = 0.5;
  double max_grad_norm = 0.5;  // <= 0: no clipping
  double clip_vf = 0.0;        // <= 0: no value clipping
  bool normalize_advantages = true;
  std::vector<int> policy_hidden = {64, 64};
  std::vector<int> value_hidden = {64, 64};
  policy::Activation activation = policy::Activation::kTanh;
  double log_std_init = 0.0;
  bool normalize_observations = false;
  bool scale_rewards = false;
  // Warm start: the policy network and observation normaliser of this blob (same IO layout,
  // widths and activation; the value network and log-std start fresh). Empty: orthogonal init.
  std::string init_blob;
  // With init_blob: the first this many iterations update only the value network (which starts
  // fresh), so the policy is not moved by the untrained critic's advantages. 0: none.
  int critic_warmup = 0;
  ScheduleConfig schedule = [] {
    ScheduleConfig c;
    c.mode = ScheduleMode::kFixed;
    c.arms = {0.2};
    return c;
  }();

  std::string out_dir;  // empty: write nothing
  bool plots = true;
  double checkpoint_seconds = 30.0;
  const std::atomic<bool>* stop = nullptr;  // set from a signal handler to stop cleanly

  Status Validate() const;
};

struct Progress {
  int iteration = 0;
  std::uint64_t env_steps = 0;
  std::uint64_t eval_steps = 0;
  std::uint64_t total_steps = 0;  // the budget
  double steps_per_second = 0;
  double eta_seconds = 0;
  double mean_return = 0;                                          // last 100 training episodes
  double task_success = std::numeric_limits<double>::quiet_NaN();  // fraction of them that completed the task
  double epsilon = 0;
};

struct IterationStats {
  int iteration = 0;
  std::uint64_t env_steps = 0, eval_steps = 0;
  int arm = 0;
  double epsilon = 0;
  double feedback = 0, feedback_before = 0;  // NaN where not available
  bool improved = false;
  double success_rate = 0;
  double train_return = 0;      // mean of episodes completed in this iteration's rollout
  double train_return_100 = 0;  // mean of the last 100 training episodes
  double task_success_100 = 0;  // fraction of the last 100 training episodes that completed the task (NaN: n/a)
  int episodes = 0;
  double approx_kl = 0, clip_fraction = 0, explained_variance = 0, entropy = 0;
  double policy_loss = 0, value_loss = 0, grad_norm = 0, log_std_mean = 0;
  double steps_per_second = 0;
  double learning_rate = 0;
  std::vector<ArmState> arms;
};

struct TrainResult {
  std::vector<IterationStats> iterations;
  std::uint64_t env_steps = 0;
  std::uint64_t eval_steps = 0;
  double final_return = 0;  // mean of the last 100 training episodes
  double wall_seconds = 0;
  double steps_per_second = 0;  // training steps per wall second, updates included
  bool interrupted = false;
  policy::PolicySpec spec;  // the frozen policy (what the blob holds)
  // max |trainer's deterministic action - blob reference forward| over observations of the last
  // rollout, in units of the reference's own error bound (<= 1: the blob acts like the trainer).
  double freeze_check = 0;
  std::string plots_note;
};

Result<TrainResult> Train(const TrainConfig& config, const std::function<void(const Progress&)>& progress = {});

}  // namespace pbppo::trainer
