#include "policies/trainer/gae.hpp"

namespace pbppo::trainer {

void ComputeGae(const GaeInput& in, double gamma, double lambda, float* advantages, float* returns) {
  const int T = in.steps, N = in.envs;
  for (int e = 0; e < N; ++e) {
    double next_adv = 0.0;
    for (int t = T - 1; t >= 0; --t) {
      const int i = t * N + e;
      double next_value;
      bool boundary;
      if (in.terminated[i]) {
        next_value = 0.0;
        boundary = true;
      } else if (in.truncated[i]) {
        next_value = in.truncation_values[i];
        boundary = true;
      } else {
        next_value = t + 1 < T ? in.values[i + N] : in.last_values[e];
        boundary = false;
      }
      const double delta = in.rewards[i] + gamma * next_value - in.values[i];
      const double adv = delta + (boundary ? 0.0 : gamma * lambda * next_adv);
      advantages[i] = static_cast<float>(adv);
      returns[i] = static_cast<float>(adv + in.values[i]);
      next_adv = adv;
    }
  }
}

}  // namespace pbppo::trainer
