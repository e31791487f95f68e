// Generalised advantage estimation over a rollout stored time-major ([t][env]).
#pragma once

#include <cstdint>
#include <vector>

namespace pbppo::trainer {

struct GaeInput {
  int steps = 0;                             // T
  int envs = 0;                              // N
  const float* rewards = nullptr;            // [T*N]
  const float* values = nullptr;             // [T*N] V(s_t)
  const std::uint8_t* terminated = nullptr;  // [T*N]
  const std::uint8_t* truncated = nullptr;   // [T*N]
  // V of the observation after step t when it ended an episode by truncation (the final
  // observation, before reset); read only where truncated is set. [T*N]
  const float* truncation_values = nullptr;
  const float* last_values = nullptr;  // [N] V of the observation after the last step
};

// advantages, returns (= advantages + values) [T*N]. A terminated step bootstraps nothing; a
// truncated one bootstraps gamma * V(final observation); neither passes advantage across the
// episode boundary.
void ComputeGae(const GaeInput& in, double gamma, double lambda, float* advantages, float* returns);

}  // namespace pbppo::trainer
