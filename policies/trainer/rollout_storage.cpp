#include "policies/trainer/rollout_storage.hpp"

#include <algorithm>

namespace pbppo::trainer {

int BlockSize(int envs) noexcept {
  return std::clamp(envs / 16, 1, 32);
}

RolloutStorage::RolloutStorage(int steps_, int envs_, int obs_size_, int critic_size_, int action_size_)
    : steps(steps_), envs(envs_), obs_size(obs_size_), critic_size(critic_size_), action_size(action_size_) {
  const long B = size();
  const auto b = static_cast<std::size_t>(B);
  obs.resize(obs_size, B);
  critic_obs.resize(critic_size, critic_size > 0 ? B : 0);
  actions.resize(action_size, B);
  action_mean.resize(action_size, B);
  log_std.assign(static_cast<std::size_t>(action_size), 0.f);
  raw_obs.assign(b * static_cast<std::size_t>(obs_size), 0.f);
  raw_critic_obs.assign(b * static_cast<std::size_t>(critic_size), 0.f);
  truncation_value_inputs.resize(value_input_size(), B);
  last_value_inputs.resize(value_input_size(), envs);
  for (auto* v : {&log_prob, &rewards, &values, &truncation_values, &advantages, &returns}) v->assign(b, 0.f);
  last_values.assign(static_cast<std::size_t>(envs), 0.f);
  terminated.assign(b, 0);
  truncated.assign(b, 0);
}

}  // namespace pbppo::trainer
