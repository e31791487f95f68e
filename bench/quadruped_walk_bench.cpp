// Throughput of the quadruped walking environment on one core: environment steps per CPU second
// with the policy in the loop (the runtime's Forward on a blob, then Step: 4 physics steps with
// the joint PD, observation, reward, resets included), beside MuJoCo's bare physics rate for the
// same model (physics steps per CPU second with only the joint PD) divided by the 4 physics steps
// of a policy step: the ceiling the environment could reach. Their ratio is the figure to improve.
// Per-thread CPU time, so other load on the machine does not count; medians of 5 rounds.
// Then training on flat ground with the recipe's settings (tools/train_quadruped.sh: 512 robots x
// 24 steps per iteration, 5 epochs of 3072-sample minibatches, 128-64-32 ELU, the privileged
// critic), rollouts and updates included, on one thread: steps per CPU second, the rate a core
// gives the recipe, beside the same ceiling.
//
//   quadruped_walk_bench [BLOB] [policy_steps] [train_iterations]
//     (defaults: the shipped flat-ground policy, 5000, 20; 0 iterations: no training)
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/cpu_time.hpp"
#include "bench/training_rate.hpp"
#include "policies/envs/quadruped_walk.hpp"
#include "policies/trainer/trainer.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/policy/reference.hpp"

namespace {

using pbppo::bench::CpuSeconds;
using pbppo::bench::Median;
using pbppo::bench::TrainOneThread;

}  // namespace

int main(int argc, char** argv) {
  using namespace pbppo;
  std::string blob = argc > 1 ? argv[1] : std::string(PBPPO_SOURCE_DIR) + "/policies/frozen/quadruped_walk/flat.blob";
  const int steps = argc > 2 ? std::atoi(argv[2]) : 5000;
  const int train_iterations = argc > 3 ? std::atoi(argv[3]) : 20;
  if (steps < 100) {
    std::fprintf(stderr, "quadruped_walk_bench: policy_steps %d is below 100\n", steps);
    return 2;
  }
  if (train_iterations < 0) {
    std::fprintf(stderr, "quadruped_walk_bench: train_iterations %d is negative\n", train_iterations);
    return 2;
  }
  double flat_ceiling = 0;
  // flat; mixed (flat and blocks 1:1, as trained and tested); blocks alone.
  for (const char* terrain : {"flat", "mixed", "blocks"}) {
    envs::QuadrupedWalkOptions o;
    o.models_dir = std::string(PBPPO_SOURCE_DIR) + "/models";
    o.terrain = std::string(terrain) == "flat" ? "flat" : "mixed";
    o.blocks_fraction = std::string(terrain) == "blocks" ? 1.0 : 0.5;
    auto env = envs::QuadrupedWalk::Make(o);
    if (!env) {
      std::fprintf(stderr, "quadruped_walk_bench: %s\n", env.error().message.c_str());
      return 1;
    }
    envs::QuadrupedWalk& e = **env;
    // The shipped policy, or (before one is shipped) random weights of the same shape.
    policy::PolicySpec spec;
    std::string what = blob;
    if (std::filesystem::exists(blob)) {
      auto s = policy::ReadBlobFile(blob);
      if (!s) {
        std::fprintf(stderr, "quadruped_walk_bench: %s\n", s.error().message.c_str());
        return 1;
      }
      spec = *s;
    } else {
      spec = policy::MakeRandomSpec({e.observation_size(), 128, 64, 32, e.action_size()}, policy::Activation::kElu, 1);
      what = "random 45-128-64-32-12 ELU weights (no blob at " + blob + ")";
    }
    auto model = policy::PolicyModel::FromSpec(spec);
    if (!model) {
      std::fprintf(stderr, "quadruped_walk_bench: %s\n", model.error().message.c_str());
      return 1;
    }
    auto data = policy::MakePolicyData(*model);
    std::vector<float> obs(e.observation_size()), act(e.action_size());
    Rng rng(1);
    e.Reset(rng, obs);
    std::vector<double> env_rate, physics_rate;
    for (int round = 0; round < 5; ++round) {
      const double t0 = CpuSeconds();
      for (int k = 0; k < steps; ++k) {
        std::copy(obs.begin(), obs.end(), data->observation().begin());
        (void)policy::Forward(*model, *data);
        robot::ToPolicyUnits(e.layout(), data->action(), act);
        const envs::StepResult r = e.Step(act, obs);
        if (r.terminated || r.truncated) e.Reset(rng, obs);
      }
      env_rate.push_back(steps / (CpuSeconds() - t0));
      physics_rate.push_back(e.BarePhysicsRate(4 * steps));
    }
    const double env_sps = Median(env_rate), physics = Median(physics_rate);
    const double ceiling = physics / e.params().decimation;
    std::printf("quadruped-walk %-6s policy %s\n", terrain, what.c_str());
    std::printf("  environment steps/s per core, policy in the loop: %8.0f\n", env_sps);
    std::printf(
        "  bare MuJoCo physics steps/s (joint PD only):      %8.0f  = %.0f policy steps/s at %d physics steps each\n",
        physics, ceiling, e.params().decimation);
    std::printf("  ratio environment / bare physics ceiling:         %8.2f\n", env_sps / ceiling);
    if (std::string(terrain) == "flat") flat_ceiling = ceiling;
  }
  if (train_iterations == 0) return 0;
  trainer::TrainOptions o;
  o.env.name = "quadruped-walk";
  o.env.flags["terrain"] = "flat";
  o.env.models_dir = std::string(PBPPO_SOURCE_DIR) + "/models";
  o.num_envs = 512;
  o.rollout_steps = 24;
  o.minibatch = 3072;
  o.epochs = 5;
  o.learning_rate = 1e-3;
  o.lr_schedule.kind = trainer::LrSchedule::Kind::kAdaptive;
  o.ent_coef = 0.01;
  o.vf_coef = 1.0;
  o.clip_vf = 0.2;
  o.max_grad_norm = 1.0;
  o.policy_hidden = {128, 64, 32};
  o.activation = policy::Activation::kElu;
  o.total_steps = static_cast<std::uint64_t>(train_iterations) * 512 * 24;
  auto trained = TrainOneThread(o);
  if (!trained) {
    std::fprintf(stderr, "quadruped_walk_bench: %s\n", trained.error().message.c_str());
    return 1;
  }
  const double rate = trained->steps_per_cpu_s;
  std::printf("quadruped-walk flat   training from scratch, recipe settings, %d iterations on one thread\n",
              train_iterations);
  std::printf("  environment steps/s per core, updates included:   %8.0f\n", rate);
  std::printf("  ratio training / bare physics ceiling:            %8.2f\n", rate / flat_ceiling);
  return 0;
}
