#include "policies/trainer/options.hpp"

#include "policies/envs/registry.hpp"
#include "policies/trainer/rollout_storage.hpp"

namespace pbppo::trainer {
namespace {

Error Invalid(const std::string& flag, const std::string& what) {
  return MakeError(ErrorCode::kInvalidValue, flag + ": " + what);
}

}  // namespace

Status TrainOptions::Validate() const {
  if (total_steps < 1) return Invalid("--steps", "must be at least 1");
  if (num_envs < 1 || num_envs > 4096) return Invalid("--envs", std::to_string(num_envs) + " is not in [1, 4096]");
  if (rollout_steps < 1) return Invalid("--rollout", std::to_string(rollout_steps) + " is not positive");
  if (threads < 1 || threads > 256) return Invalid("--threads", std::to_string(threads) + " is not in [1, 256]");
  if (const int block = BlockSize(num_envs), blocks = (num_envs + block - 1) / block; blocks < ranks())
    return Invalid("--envs", std::to_string(num_envs) + " gives " + std::to_string(blocks) + " block(s) of " +
                                 std::to_string(block) + ", fewer than the run's " + std::to_string(ranks()) +
                                 " ranks (each rank steps whole blocks of N/16 environments, within 1 and 32)");
  if (minibatch < 2) return Invalid("--minibatch", std::to_string(minibatch) + " is below 2");
  if (epochs < 1) return Invalid("--epochs", std::to_string(epochs) + " is not positive");
  if (critic_warmup < 0) return Invalid("--critic-warmup", std::to_string(critic_warmup) + " is negative");
  if (critic_warmup > 0 && init_blob.empty())
    return Invalid("--critic-warmup", "needs --init (it holds a trained policy while the fresh value network learns)");
  if (resume_every < 0) return Invalid("--resume-every", std::to_string(resume_every) + " is negative");
  if (snapshots < 0 || snapshots > 1000)
    return Invalid("--snapshots", std::to_string(snapshots) + " is not in [0, 1000]");
  if (!(learning_rate > 0)) return Invalid("--lr", std::to_string(learning_rate) + " is not positive");
  if (!(gamma > 0 && gamma <= 1)) return Invalid("--gamma", std::to_string(gamma) + " is not in (0, 1]");
  if (!(gae_lambda >= 0 && gae_lambda <= 1))
    return Invalid("--gae-lambda", std::to_string(gae_lambda) + " is not in [0, 1]");
  if (policy_hidden.empty()) return Invalid("--hidden", "needs at least one hidden layer");
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

nlohmann::json OptionsJson(const TrainOptions& o) {
  const envs::EnvOptions& e = o.env;
  const ScheduleConfig& c = o.schedule;
  // clang-format off: a table, one group of flags per line or two
  nlohmann::json j = {
      // The environment (its own flags below).
      {"env", e.name}, {"models", e.models_dir},
      // Budget and parallelism.
      {"seed", o.seed}, {"steps", o.total_steps}, {"envs", o.num_envs}, {"rollout", o.rollout_steps},
      {"threads", o.threads}, {"ranks", o.ranks()},
      // PPO.
      {"minibatch", o.minibatch}, {"epochs", o.epochs}, {"learning_rate", o.learning_rate},
      {"lr_schedule", o.lr_schedule.Describe()}, {"gamma", o.gamma}, {"gae_lambda", o.gae_lambda},
      {"ent_coef", o.ent_coef}, {"vf_coef", o.vf_coef}, {"max_grad_norm", o.max_grad_norm}, {"clip_vf", o.clip_vf},
      {"no_adv_norm", !o.normalize_advantages}, {"scale_rewards", o.scale_rewards},
      // The clip schedule.
      {"schedule", c.Describe()}, {"arms", c.arms}, {"feedback", ToString(c.feedback)},
      {"eval_episodes", c.eval_episodes}, {"bandit_lambda", c.lambda}, {"bandit_gamma", c.gamma},
      // Networks.
      {"hidden", o.policy_hidden}, {"value_hidden", o.critic_hidden()}, {"activation", policy::ToString(o.activation)},
      {"log_std_init", o.log_std_init}, {"normalize_obs", o.normalize_observations}, {"init", o.init_blob},
      {"critic_warmup", o.critic_warmup},
      // Outputs.
      {"out", o.out_dir}, {"no_plots", !o.plots}, {"checkpoint_seconds", o.checkpoint_seconds},
      {"keep_best", o.keep_best}, {"snapshots", o.snapshots}, {"resume_every", o.resume_every}};
  // clang-format on
  // The environment's flags, each by its key: as given, else the environment's default.
  auto resolved = envs::ResolveEnvOptions(e);
  j.update(envs::FlagsJson(resolved ? *resolved : e, envs::EnvFlag::kTrain));
  return j;
}

}  // namespace pbppo::trainer
