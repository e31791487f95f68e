// Trainer throughput on Pendulum with stable-baselines3's PPO defaults (1 env x 2048 steps,
// minibatch 64, 10 epochs, 64-64 tanh, fixed clip 0.2): environment steps per second, updates
// included. Usage: pbppo_bench_trainer [steps=204800] [threads=2] [envs=1]
#include <cstdio>
#include <cstdlib>

#include "policies/trainer/trainer.hpp"

int main(int argc, char** argv) {
  pbppo::trainer::TrainOptions c;
  c.total_steps = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 204800;
  c.threads = argc > 2 ? std::atoi(argv[2]) : 2;
  c.num_envs = argc > 3 ? std::atoi(argv[3]) : 1;
  c.rollout_steps = 2048 / c.num_envs;
  c.seed = 1;
  auto r = pbppo::trainer::Train(c);
  if (!r) {
    std::fprintf(stderr, "trainer_bench: %s\n", r.error().message.c_str());
    return 1;
  }
  std::printf("pendulum, SB3 defaults (%d env x %d steps, minibatch 64, 10 epochs, 64-64 tanh), %d threads\n",
              c.num_envs, c.rollout_steps, c.threads);
  std::printf("steps %llu  wall %.3f s  steps/s %.0f  (updates included)  final return %.1f\n",
              static_cast<unsigned long long>(r->env_steps), r->wall_seconds, r->steps_per_second, r->final_return);
  return 0;
}
