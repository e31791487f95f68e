// `pbppo train` and `pbppo eval`: train a policy with a clip schedule, evaluate a frozen blob.
#pragma once

#include <cstdint>
#include <string>

namespace CLI {
class App;
}

namespace pbppo::cli {

struct TrainOptions {
  std::string env = "pendulum";
  std::string layout = "hard";
  double exploring_starts = 0.0;
  std::string progress;
  std::string geodesic_margin;
  std::string clearance_penalty;
  int extra_obstacles = 0;
  std::string terrain = "flat";
  std::string commands;
  std::string schedule = "pbppo";
  std::string arms = "0.02:0.5:6";
  std::string feedback = "eval";
  int eval_episodes = 2;
  double bandit_lambda = -1;  // < 0: the schedule's default
  double bandit_gamma = -1;
  double steps = 2e5;
  std::uint64_t seed = 1;
  std::string out;
  int threads = 1;
  int envs = 1;
  int rollout = 2048;
  int minibatch = 64;
  int epochs = 10;
  double lr = 3e-4;
  bool anneal_lr = false;
  bool keep_best = false;
  int snapshots = 0;
  int critic_warmup = 0;
  double gamma = 0.99;
  double gae_lambda = 0.95;
  double ent_coef = 0.0;
  double vf_coef = 0.5;
  double max_grad_norm = 0.5;
  double clip_vf = 0.0;
  std::string hidden = "64-64";
  std::string value_hidden;  // empty: same as --hidden
  std::string activation = "tanh";
  double log_std_init = 0.0;
  bool normalize_obs = false;
  bool scale_rewards = false;
  bool no_adv_norm = false;
  bool no_plots = false;
  double checkpoint_seconds = 30;
  std::string models;
  std::string init;  // --init BLOB
  bool quiet = false;
};
void AddTrainOptions(CLI::App& sub, TrainOptions& o);
int Train(const TrainOptions& o);

struct EvalOptions {
  std::string blob;
  std::string env = "pendulum";
  std::string layout = "hard";
  std::string plot;          // PNG of the trajectories over the map (auv-nav)
  std::string trajectories;  // CSV of every episode's trajectory (auv-nav)
  std::string outcomes;      // CSV, one row per episode: outcome, end pose, random obstacles (auv-nav)
  int episodes = 0;          // 0: the environment's test size (100; quadruped-walk: the paper's 50 robots)
  std::uint64_t seed = 7;
  std::string models;
  bool json = false;
  std::string terrain = "flat";  // quadruped-walk
  std::string commands;          // quadruped-walk: "VX:VY:YAW" maxima
  bool randomize = false;        // quadruped-walk: randomised robots (friction, mass, gains, latency, pushes)
};
void AddEvalOptions(CLI::App& sub, EvalOptions& o);
int Eval(const EvalOptions& o);

}  // namespace pbppo::cli
