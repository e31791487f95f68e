// Everything a training run is made of, in one struct: the `pbppo train` command line fills it,
// Train() takes it, and its parts go down as they are (the environment's to envs::MakeEnv, which
// checks them; the rest to the algorithm, the runner, the logger and the exporter). summary.json
// records it with OptionsJson().
#pragma once

#include <atomic>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "policies/envs/env.hpp"
#include "policies/trainer/clip_schedule.hpp"
#include "policies/trainer/collective.hpp"
#include "policies/trainer/lr_schedule.hpp"
#include "runtime/core/result.hpp"
#include "runtime/policy/policy_spec.hpp"

namespace pbppo::trainer {

struct TrainOptions {
  // The environment (--env, --models and the environment's own flags).
  envs::EnvOptions env{};

  // Budget and parallelism.
  std::uint64_t seed = 1;
  std::uint64_t total_steps = 200000;  // --steps: training environment steps (evaluation steps are extra)
  int num_envs = 1;                    // --envs
  int rollout_steps = 2048;            // --rollout: per environment and iteration
  int threads = 1;                     // per rank
  // The ranks of one data-parallel run (mpirun): they split the environments, share the rollout
  // and the update's gradients, and give the weights one process would; rank 0 alone writes.
  // Null: this process alone.
  const Collective* group = nullptr;

  // PPO.
  int minibatch = 64;
  int epochs = 10;
  double learning_rate = 3e-4;  // --lr: the rate, or the first one (anneal, adaptive)
  LrSchedule lr_schedule{};
  double gamma = 0.99;
  double gae_lambda = 0.95;
  double ent_coef = 0.0;
  double vf_coef = 0.5;
  double max_grad_norm = 0.5;  // <= 0: no clipping
  double clip_vf = 0.0;        // <= 0: no value clipping
  bool normalize_advantages = true;
  bool scale_rewards = false;
  ScheduleConfig schedule = [] {  // what sets the clip bound (the command line's default is pbppo)
    ScheduleConfig c;
    c.mode = ScheduleMode::kFixed;
    c.arms = {0.2};
    return c;
  }();

  // Networks.
  std::vector<int> policy_hidden = {64, 64};  // --hidden
  std::vector<int> value_hidden{};            // --value-hidden; empty: as policy_hidden
  policy::Activation activation = policy::Activation::kTanh;
  double log_std_init = 0.0;
  // Running observation normalisation (the actor's is frozen into the blob; a privileged critic
  // observation gets its own).
  bool normalize_observations = false;
  // --init: the policy network and observation normaliser of this blob (same IO layout, widths and
  // activation; the value network and log-std start fresh). Empty: orthogonal initialisation.
  std::string init_blob{};
  // With init_blob: the first this many iterations update only the value network (which starts
  // fresh), so the policy is not moved by the untrained critic's advantages. 0: none.
  int critic_warmup = 0;

  // Outputs.
  std::string out_dir{};  // --out; empty: write nothing
  bool plots = true;
  double checkpoint_seconds = 30.0;
  // Also write best.blob: the policy of the best last-100-episode task success where the
  // environment reports one (ties: the better return), otherwise of the best return.
  bool keep_best = false;
  // Also write this many blobs evenly spaced over the run into snapshots/ (named by the training
  // steps that produced them), to choose among afterwards on held-out episodes. 0: none.
  int snapshots = 0;
  const std::atomic<bool>* stop = nullptr;  // set from a signal handler to stop cleanly
  // Resuming (checkpoint.hpp): every this many iterations (and at a stop) the run's state goes to
  // OUT/resume.bin with these arguments (the command line's, to run again); 0 or no arguments: not
  // written. A run given a state (ReadResumeFile's) continues from it: the same options, any ranks
  // and threads, the same weights as the run would have given uninterrupted.
  int resume_every = 25;
  std::vector<std::string> command_args{};
  std::vector<char> resume_state{};

  int ranks() const noexcept { return group != nullptr ? group->size() : 1; }
  int rank() const noexcept { return group != nullptr ? group->rank() : 0; }
  const std::vector<int>& critic_hidden() const noexcept { return value_hidden.empty() ? policy_hidden : value_hidden; }

  // Checks every option but the environment's (envs::MakeEnv checks those); errors name the flag
  // and the value.
  Status Validate() const;
};

// The options as summary.json records them: one key per flag, named as the flag without its dashes
// and with '_' for '-' ("extra_obstacles", "no_adv_norm"), except --lr ("learning_rate") and
// --schedule ("schedule": the whole clip schedule described, e.g. "pbppo arms=0.05..0.4/6 lambda=1
// gamma_b=0.95 feedback=rollout").
nlohmann::json OptionsJson(const TrainOptions& options);

}  // namespace pbppo::trainer
