// What a training run reports (rsl_rl's logging, CleanRL's writer): one log.csv row per iteration,
// the progress callback's figures, summary.json at the end (the options, OptionsJson, beside the
// results) and the curves drawn from log.csv (report/).
#pragma once

#include <array>
#include <cstdint>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "policies/trainer/clip_schedule.hpp"
#include "policies/trainer/options.hpp"
#include "policies/trainer/ppo.hpp"
#include "runtime/core/result.hpp"
#include "runtime/policy/policy_spec.hpp"

namespace pbppo::trainer {

// For a progress line.
struct Progress {
  int iteration = 0;
  std::uint64_t env_steps = 0;
  std::uint64_t eval_steps = 0;
  std::uint64_t total_steps = 0;  // the budget
  double steps_per_second = 0;
  double eta_seconds = 0;
  double mean_return = 0;                                          // last 100 training episodes
  double task_success = std::numeric_limits<double>::quiet_NaN();  // fraction of them that completed the task
  // Their mean tracking errors (vx, vy m/s, yaw rate rad/s) where the task tracks a velocity, NaN otherwise.
  std::array<double, 3> tracking_error{std::numeric_limits<double>::quiet_NaN(),
                                       std::numeric_limits<double>::quiet_NaN(),
                                       std::numeric_limits<double>::quiet_NaN()};
  double epsilon = 0;
};

// One iteration: the bandit's choice and feedback, the returns, and the update's figures.
struct IterationStats : UpdateStats {
  int iteration = 0;
  std::uint64_t env_steps = 0, eval_steps = 0;
  int arm = 0;
  double epsilon = 0;
  double feedback = 0, feedback_before = 0;  // NaN where not available
  bool improved = false;
  double success_rate = 0;      // the fraction of bandit updates so far that improved the return
  double train_return = 0;      // mean of episodes completed in this iteration's rollout
  double train_return_100 = 0;  // mean of the last 100 training episodes
  double task_success_100 = 0;  // fraction of the last 100 training episodes that completed the task (NaN: n/a)
  std::array<double, 3> tracking_error_100{};  // their mean tracking errors (NaN: n/a)
  int episodes = 0;
  double steps_per_second = 0;
  double learning_rate = 0;  // the rate of this iteration's update (adaptive: after its last minibatch)
  std::vector<ArmState> arms;
};

// Where a run's wall time went, in seconds, as rank 0 saw it.
struct TimeShares {
  double rollout = 0;         // stepping the environments with the actor sampling (ranks exchanging excluded)
  double rollout_policy = 0;  // the part of `rollout` the actor's forward passes took (its first thread's share)
  double rollout_env = 0;     // the part the environments' steps and resets took (the same)
  double returns = 0;         // values and GAE
  double update = 0;          // the PPO update (exchanging gradients excluded)
  double evaluation = 0;      // evaluation episodes for the schedule's feedback
  double exchange = 0;        // ranks exchanging samples, returns and gradients, and waiting for each other there
  double other = 0;           // the rest: normaliser statistics, the schedule, logging, checkpoints
};

struct TrainResult {
  std::vector<IterationStats> iterations;
  std::uint64_t env_steps = 0;
  std::uint64_t eval_steps = 0;
  double final_return = 0;  // mean of the last 100 training episodes
  double wall_seconds = 0;
  double steps_per_second = 0;  // training steps per wall second, updates included
  TimeShares time;
  int ranks = 1, threads = 1;
  bool interrupted = false;
  policy::PolicySpec spec;  // the frozen policy (what the blob holds)
  // max |trainer's deterministic action - blob reference forward| over observations of the last
  // rollout, in units of the reference's own error bound (<= 1: the blob acts like the trainer).
  double freeze_check = 0;
  std::string plots_note;
};

class Logger {
 public:
  explicit Logger(const TrainOptions& options) : o_(options) {}

  // Creates the output folder (and snapshots/ when asked) and log.csv with its header and the rows
  // of a resumed run's iterations so far; nothing without an output folder. Errors name --out (or
  // --snapshots) and the path.
  Status Open(const std::vector<IterationStats>& resumed = {});
  void Log(const IterationStats& s);
  // The curves (unless --no-plots) and summary.json; `env_name` is the environment's full name,
  // `env_provenance` its whole provenance text (the blob holds its first 256 bytes).
  Status Finish(const std::string& env_name, const std::string& env_provenance, TrainResult& result);

  // log.csv's header and rows.
  static std::string CsvHeader(std::size_t arms);
  static std::string CsvRow(const IterationStats& s);

 private:
  std::string Plots(const std::vector<IterationStats>& its) const;
  const TrainOptions& o_;
  std::ofstream csv_;
};

}  // namespace pbppo::trainer
