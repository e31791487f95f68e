// Trainer throughput.
//
//   pbppo_bench_trainer [pendulum] [steps=204800] [threads=2] [envs=1]
//     Pendulum with stable-baselines3's PPO defaults (1 env x 2048 steps, minibatch 64, 10 epochs,
//     64-64 tanh, fixed clip 0.2): environment steps per second, updates included.
//   pbppo_bench_trainer update [repeats=5]
//     The PPO update alone (ppo.hpp) at locomotion shapes: 48 actor inputs, 12 actions, a 65-input
//     critic, ELU networks 128-64-32, 256-128-64 and 512-256-128, rollouts of 64 x 24 to 512 x 24
//     steps in 4 minibatches, 5 epochs, on 1 and 2 threads: samples per second (rollout samples x
//     epochs / update time) of wall time, per CPU second and per CPU second of the busiest thread,
//     the median of `repeats` updates; and the critic's values and GAE (ComputeReturns).
//   pbppo_bench_trainer recipes [repeats=7] [NAME] [THREADS]
//     The PPO update alone at the shapes and settings of the project's recipes: tools/train_auv.sh
//     (16 x 256, minibatch 512, 64-64 tanh, 2 threads), tools/train_quadruped.sh (512 x 24,
//     minibatch 3072, 128-64-32 ELU, the privileged critic, 2 threads), tools/mujoco_table.sh
//     (1 x 2048, minibatch 64, 64-64 tanh, 1 thread) and tools/learn_pendulum.sh (4 x 1024,
//     minibatch 64, 1 and 2 threads), the input and action sizes from the environments themselves:
//     samples per second of wall time and of the busiest thread's CPU time, the median of `repeats`
//     updates after one unmeasured. NAME: only the recipes whose name contains it; THREADS: on that
//     many threads instead of each recipe's own.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "policies/envs/env.hpp"
#include "policies/trainer/ppo.hpp"
#include "policies/trainer/trainer.hpp"

namespace {

using namespace pbppo;
using namespace pbppo::trainer;
using Clock = std::chrono::steady_clock;

int Pendulum(int argc, char** argv) {
  TrainOptions c;
  c.total_steps = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 204800;
  c.threads = argc > 2 ? std::atoi(argv[2]) : 2;
  c.num_envs = argc > 3 ? std::atoi(argv[3]) : 1;
  c.rollout_steps = 2048 / c.num_envs;
  c.seed = 1;
  auto r = Train(c);
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

// A rollout of random observations whose actions the actor sampled, with random advantages and
// returns: what the update reads, at the given shape.
RolloutStorage SyntheticRollout(const Ppo& ppo, int steps, int envs, int obs, int critic, int actions, Rng& rng) {
  RolloutStorage r(steps, envs, obs, critic, actions);
  const long B = r.size();
  for (long i = 0; i < B; ++i) {
    for (int j = 0; j < obs; ++j) r.obs(j, i) = static_cast<float>(rng.Normal());
    for (int j = 0; j < critic; ++j) r.critic_obs(j, i) = static_cast<float>(rng.Normal());
  }
  typename Mlp<float>::Workspace ws;
  const Mat<float>& mu = ppo.actor().mean.Forward(ppo.actor_params(), r.obs, ws);
  const float* log_std = ppo.log_std();
  std::copy(log_std, log_std + actions, r.log_std.begin());
  for (long i = 0; i < B; ++i) {
    float lp = 0;
    for (int j = 0; j < actions; ++j) {
      const float z = static_cast<float>(rng.Normal());
      r.action_mean(j, i) = mu(j, i);
      r.actions(j, i) = mu(j, i) + std::exp(log_std[j]) * z;
      lp += -0.5f * z * z - log_std[j] - 0.9189385f;
    }
    const auto u = static_cast<std::size_t>(i);
    r.log_prob[u] = lp;
    r.advantages[u] = static_cast<float>(rng.Normal());
    r.returns[u] = static_cast<float>(rng.Normal());
    r.values[u] = static_cast<float>(rng.Normal());
  }
  for (int e = 0; e < envs; ++e)
    for (int j = 0; j < r.value_input_size(); ++j) r.last_value_inputs(j, e) = static_cast<float>(rng.Normal());
  return r;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double CpuSeconds(clockid_t clock = CLOCK_PROCESS_CPUTIME_ID) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Each pool thread's CPU seconds so far.
std::vector<double> ThreadCpu(WorkerPool& pool) {
  std::vector<double> t(static_cast<std::size_t>(pool.size()));
  pool.Run([&](int w) { t[static_cast<std::size_t>(w)] = CpuSeconds(CLOCK_THREAD_CPUTIME_ID); });
  return t;
}

struct Shape {
  std::vector<int> hidden;
  int envs, steps;
};

int Update(int repeats) {
  const int obs = 48, critic = 65, actions = 12;
  std::printf(
      "PPO update at locomotion shapes: %d actor inputs, %d actions, %d critic inputs, ELU, 4 minibatches, 5 epochs.\n"
      "Samples per second of wall time and per core (per CPU second of the process: spinning at a barrier\n"
      "counts), median of %d updates; busiest: per CPU second of the busiest thread (what the wall rate would be\n"
      "with a core per thread); values: the critic's values and GAE (ComputeReturns), samples per wall second.\n",
      obs, actions, critic, repeats);
  std::printf("%-12s %-8s %5s %6s %3s  %9s %9s %9s  %9s\n", "networks", "rollout", "mb", "chunks", "thr", "update/s",
              "per core", "busiest", "values/s");
  const std::vector<Shape> shapes = {{{128, 64, 32}, 512, 24},  {{256, 128, 64}, 64, 24},  {{256, 128, 64}, 128, 32},
                                     {{256, 128, 64}, 256, 48}, {{512, 256, 128}, 64, 24}, {{512, 256, 128}, 128, 32}};
  for (const Shape& shape : shapes) {
    for (int threads : {1, 2}) {
      TrainOptions o;
      o.policy_hidden = shape.hidden;
      o.activation = policy::Activation::kElu;
      o.epochs = 5;
      o.minibatch = shape.envs * shape.steps / 4;
      o.threads = threads;
      o.max_grad_norm = 1.0;
      o.clip_vf = 0.2;
      Ppo ppo(o, obs, critic, actions);
      Rng rng(7);
      RolloutStorage r = SyntheticRollout(ppo, shape.steps, shape.envs, obs, critic, actions, rng);
      WorkerPool pool(threads);
      std::vector<double> wall, cpu, busiest, values_s;
      for (int k = 0; k < repeats; ++k) {
        const auto v0 = Clock::now();
        ppo.ComputeReturns(r, pool);
        values_s.push_back(std::chrono::duration<double>(Clock::now() - v0).count());
        const std::vector<double> t0 = ThreadCpu(pool);
        const double c0 = CpuSeconds();
        const auto w0 = Clock::now();
        (void)ppo.Update(r, 0.2, false, pool);
        wall.push_back(std::chrono::duration<double>(Clock::now() - w0).count());
        cpu.push_back(CpuSeconds() - c0);
        const std::vector<double> t1 = ThreadCpu(pool);
        double most = 0;
        for (std::size_t w = 0; w < t0.size(); ++w) most = std::max(most, t1[w] - t0[w]);
        busiest.push_back(most);
      }
      const double samples = static_cast<double>(r.size()) * o.epochs;
      char net[32], roll[32];
      std::snprintf(net, sizeof net, "%d-%d-%d", shape.hidden[0], shape.hidden[1], shape.hidden[2]);
      std::snprintf(roll, sizeof roll, "%dx%d", shape.envs, shape.steps);
      std::printf("%-12s %-8s %5d %6d %3d  %9.0f %9.0f %9.0f  %9.0f\n", net, roll, o.minibatch,
                  Ppo::Chunks(o.minibatch), threads, samples / Median(wall), samples / Median(cpu),
                  samples / Median(busiest), static_cast<double>(r.size()) / Median(values_s));
      std::fflush(stdout);
    }
  }
  return 0;
}

struct Recipe {
  const char* name;
  envs::EnvOptions env;
  int envs, steps, minibatch, epochs, threads;
  std::vector<int> hidden;
  policy::Activation activation;
  bool walking;  // legged_gym's PPO settings (tools/train_quadruped.sh)
};

int Recipes(int repeats, const std::string& only, int threads) {
  const auto tanh = policy::Activation::kTanh;
  auto env = [](const char* name) {
    envs::EnvOptions e;
    e.name = name;
    return e;
  };
  envs::EnvOptions auv = env("auv-nav");
  auv.flags["layout"] = "mixed";
  const std::vector<Recipe> recipes = {
      {"train_auv", auv, 16, 256, 512, 10, 2, {64, 64}, tanh, false},
      {"train_quadruped", env("quadruped-walk"), 512, 24, 3072, 5, 2, {128, 64, 32}, policy::Activation::kElu, true},
      {"mujoco_table hopper", env("hopper"), 1, 2048, 64, 10, 1, {64, 64}, tanh, false},
      {"mujoco_table ant", env("ant"), 1, 2048, 64, 10, 1, {64, 64}, tanh, false},
      {"learn_pendulum", env("pendulum"), 4, 1024, 64, 10, 1, {64, 64}, tanh, false},
      {"learn_pendulum", env("pendulum"), 4, 1024, 64, 10, 2, {64, 64}, tanh, false},
  };
  std::printf(
      "PPO update at the recipes' shapes: samples per second (rollout samples x epochs / update time) of wall\n"
      "time and of the busiest thread's CPU time, median of %d updates.\n",
      repeats);
  std::printf("%-20s %5s %4s %4s %4s %9s %5s %3s  %10s %10s\n", "recipe", "obs", "crit", "act", "mb", "rollout", "ep",
              "thr", "wall/s", "busiest/s");
  for (Recipe rc : recipes) {
    if (std::string(rc.name).find(only) == std::string::npos) continue;
    if (threads > 0) rc.threads = threads;
    auto made = envs::MakeEnv(rc.env);
    if (!made) {
      std::fprintf(stderr, "trainer_bench: %s: %s\n", rc.name, made.error().message.c_str());
      return 1;
    }
    const envs::Env& e = **made;
    const int obs = static_cast<int>(e.observation_size()), critic = static_cast<int>(e.critic_observation_size());
    const int actions = static_cast<int>(e.action_size());
    TrainOptions o;
    o.num_envs = rc.envs;
    o.rollout_steps = rc.steps;
    o.minibatch = rc.minibatch;
    o.epochs = rc.epochs;
    o.threads = rc.threads;
    o.policy_hidden = rc.hidden;
    o.activation = rc.activation;
    if (rc.walking) {
      o.learning_rate = 1e-3;
      o.lr_schedule = ParseLrSchedule("adaptive:0.01").value();
      o.ent_coef = 0.01;
      o.vf_coef = 1.0;
      o.clip_vf = 0.2;
      o.max_grad_norm = 1.0;
    }
    Ppo ppo(o, obs, critic > 0 ? critic : obs, actions);
    Rng rng(7);
    RolloutStorage r = SyntheticRollout(ppo, rc.steps, rc.envs, obs, critic, actions, rng);
    WorkerPool pool(rc.threads);
    std::vector<double> wall, busiest;
    for (int k = 0; k <= repeats; ++k) {
      const std::vector<double> t0 = ThreadCpu(pool);
      const auto w0 = Clock::now();
      (void)ppo.Update(r, 0.2, false, pool);
      const double w = std::chrono::duration<double>(Clock::now() - w0).count();
      const std::vector<double> t1 = ThreadCpu(pool);
      double most = 0;
      for (std::size_t i = 0; i < t0.size(); ++i) most = std::max(most, t1[i] - t0[i]);
      if (k == 0) continue;  // the first update: workspaces and caches warm up
      wall.push_back(w);
      busiest.push_back(most);
    }
    const double samples = static_cast<double>(r.size()) * o.epochs;
    char roll[32];
    std::snprintf(roll, sizeof roll, "%dx%d", rc.envs, rc.steps);
    std::printf("%-20s %5d %4d %4d %4d %9s %5d %3d  %10.0f %10.0f\n", rc.name, obs, critic, actions, rc.minibatch, roll,
                rc.epochs, rc.threads, samples / Median(wall), samples / Median(busiest));
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "update") return Update(argc > 2 ? std::max(1, std::atoi(argv[2])) : 5);
  if (argc > 1 && std::string(argv[1]) == "recipes")
    return Recipes(argc > 2 ? std::max(1, std::atoi(argv[2])) : 7, argc > 3 ? argv[3] : "",
                   argc > 4 ? std::atoi(argv[4]) : 0);
  if (argc > 1 && std::string(argv[1]) == "pendulum") return Pendulum(argc - 1, argv + 1);
  return Pendulum(argc, argv);
}
