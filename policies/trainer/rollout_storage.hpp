// One iteration's rollout, time-major (column t*N + e for step t of environment e), as the runner
// collects it and the algorithm learns from it (rsl_rl's RolloutStorage).
//
// The value network's input is the critic's privileged observation where the environment gives one
// (value_input_size() = its size), otherwise the actor's observation; both are stored normalised,
// and raw for the normalisers' statistics.
#pragma once

#include <cstdint>
#include <vector>

#include "policies/trainer/mlp.hpp"

namespace pbppo::trainer {

// Environments per block of a run with N environments: N/16, within [1, 32]. The runner steps the
// environments, and runs the actor, block by block, a thread or rank taking whole blocks, so every
// forward pass has the same shape however the work is shared (up to 16 threads or ranks have work at
// any N of 16 or more).
int BlockSize(int envs) noexcept;

struct RolloutStorage {
  RolloutStorage() = default;
  // critic_size 0: the critic sees the actor's observation.
  RolloutStorage(int steps, int envs, int obs_size, int critic_size, int action_size);

  int steps = 0, envs = 0;  // T, N
  int obs_size = 0;         // the actor's observation
  int critic_size = 0;      // the critic's privileged observation (0: none)
  int action_size = 0;
  long size() const noexcept { return static_cast<long>(steps) * envs; }
  int value_input_size() const noexcept { return critic_size > 0 ? critic_size : obs_size; }
  // The value network's inputs, [value_input_size() x size()].
  const Mat<float>& value_inputs() const noexcept { return critic_size > 0 ? critic_obs : obs; }

  Mat<float> obs;                     // [obs_size x B], normalised
  Mat<float> critic_obs;              // [critic_size x B], normalised (empty without)
  Mat<float> actions;                 // [action_size x B], as sampled (before the environment's clipping)
  Mat<float> action_mean;             // [action_size x B], the actor's mean where it sampled them
  std::vector<float> log_std;         // [action_size], the actor's log-std during the rollout
  std::vector<float> raw_obs;         // [B][obs_size], for the actor's normaliser
  std::vector<float> raw_critic_obs;  // [B][critic_size]
  std::vector<float> log_prob, rewards;
  std::vector<std::uint8_t> terminated, truncated;  // truncated: a time limit, not a termination
  // The value network's input after a truncated step (the episode's final state, before the reset),
  // read where truncated is set, and after the last step of every environment.
  Mat<float> truncation_value_inputs;  // [value_input_size() x B]
  Mat<float> last_value_inputs;        // [value_input_size() x N]

  // Filled by the algorithm: V of every stored state, of the truncation and last inputs, and the
  // advantages and returns from them.
  std::vector<float> values, truncation_values, last_values, advantages, returns;
};

}  // namespace pbppo::trainer
