// The MuJoCo locomotion tasks (hopper, walker2d, half-cheetah, ant): throughput and behaviour.
//
//   mujoco_tasks_bench [TASK...] [--train-steps N] [--episodes N]
//
// Per task, on one core (per-thread CPU time, so other load does not count; medians of 5 rounds):
//   - physics: MuJoCo's bare rate for the model (mj_step with random controls), in environment
//     steps per second (physics steps / frame skip): the ceiling;
//   - env: Step() with random actions, resets included (observation, reward, termination);
//   - train: `pbppo train`'s loop with the paper's PPO settings (1 environment, 2048-step rollouts,
//     minibatch 64, 10 epochs, 64-64 tanh, fixed clip 0.2), updates included, over --train-steps
//     (default 20480) on one thread, the time 10^6 steps would take at that rate, and the run's
//     final training return (mean of its last 100 episodes).
// And the behaviour docs/mujoco_tasks.md compares with the standard tasks: episodes of uniform
// random actions (length and return, mean and standard deviation over --episodes, default 100,
// seed 1) and of the zero action.
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "bench/cpu_time.hpp"
#include "bench/training_rate.hpp"
#include "policies/envs/mujoco_tasks.hpp"
#include "policies/trainer/trainer.hpp"

namespace {

using pbppo::bench::CpuSeconds;
using pbppo::bench::Median;
using pbppo::bench::TrainOneThread;

using namespace pbppo;

struct Stats {
  double mean = 0, sd = 0;
};

Stats MeanSd(const std::vector<double>& v) {
  Stats s;
  for (double x : v) s.mean += x;
  s.mean /= static_cast<double>(v.size());
  for (double x : v) s.sd += (x - s.mean) * (x - s.mean);
  s.sd = std::sqrt(s.sd / static_cast<double>(v.size()));
  return s;
}

// Episodes with uniform random actions (zero = false) or the zero action: lengths and returns.
void Episodes(envs::MujocoTask& env, int episodes, bool zero, std::vector<double>& lengths,
              std::vector<double>& returns) {
  Rng rng(1);
  std::vector<float> obs(env.observation_size()), act(env.action_size(), 0.0f);
  for (int e = 0; e < episodes; ++e) {
    env.Reset(rng, obs);
    double ret = 0;
    int n = 0;
    for (;;) {
      if (!zero)
        for (auto& a : act) a = static_cast<float>(rng.Uniform(-1.0, 1.0));
      const auto r = env.Step(act, obs);
      ret += r.reward;
      ++n;
      if (r.terminated || r.truncated) break;
    }
    lengths.push_back(n);
    returns.push_back(ret);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> tasks;
  long train_steps = 20480;
  int episodes = 100;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if ((a == "--train-steps" || a == "--episodes") && i + 1 < argc) {
      const long v = std::strtol(argv[++i], nullptr, 10);
      if (v < 1) {
        std::fprintf(stderr, "mujoco_tasks_bench: %s '%s' is not a positive count\n", a.c_str(), argv[i]);
        return 2;
      }
      if (a == "--train-steps")
        train_steps = v;
      else
        episodes = static_cast<int>(std::min(v, 100000L));
    } else if (envs::FindMujocoTask(a) != nullptr) {
      tasks.push_back(a);
    } else {
      std::fprintf(stderr, "mujoco_tasks_bench: '%s' is not a task (hopper, walker2d, half-cheetah, ant)\n", a.c_str());
      return 2;
    }
  }
  if (tasks.empty()) tasks = envs::MujocoTaskNames();

  std::printf("%-13s %12s %12s %12s %14s %10s   %-26s %-26s %s\n", "task", "physics/s", "env/s", "train/s", "1e6 steps",
              "return", "random: length, return", "(mean +- sd)", "zero action: length, return");
  for (const auto& name : tasks) {
    auto made = envs::MujocoTask::Make(*envs::FindMujocoTask(name), envs::DefaultModelsDir());
    if (!made) {
      std::fprintf(stderr, "mujoco_tasks_bench: %s\n", made.error().message.c_str());
      return 1;
    }
    auto& env = *made.value();
    const mjModel* m = env.model();
    const int skip = env.spec().frame_skip;

    // Bare physics: random controls, 2000 environment steps' worth of mj_step per round.
    std::vector<double> physics, stepping;
    Rng rng(7);
    for (int round = 0; round < 5; ++round) {
      mjData* d = mj_makeData(m);
      const double t0 = CpuSeconds();
      for (int s = 0; s < 2000; ++s) {
        for (int i = 0; i < m->nu; ++i) d->ctrl[i] = rng.Uniform(-1.0, 1.0);
        for (int k = 0; k < skip; ++k) mj_step(m, d);
        if (s % 200 == 199) mj_resetData(m, d);
      }
      physics.push_back(2000 / (CpuSeconds() - t0));
      mj_deleteData(d);

      std::vector<float> obs(env.observation_size()), act(env.action_size());
      env.Reset(rng, obs);
      const double t1 = CpuSeconds();
      for (int s = 0; s < 2000; ++s) {
        for (auto& a : act) a = static_cast<float>(rng.Uniform(-1.0, 1.0));
        const auto r = env.Step(act, obs);
        if (r.terminated || r.truncated) env.Reset(rng, obs);
      }
      stepping.push_back(2000 / (CpuSeconds() - t1));
    }

    trainer::TrainOptions o;
    o.env.name = name;
    o.total_steps = static_cast<std::uint64_t>(train_steps);
    o.seed = 1;
    auto trained = TrainOneThread(o);
    if (!trained) {
      std::fprintf(stderr, "mujoco_tasks_bench: %s\n", trained.error().message.c_str());
      return 1;
    }
    const double train_rate = trained->steps_per_cpu_s;

    std::vector<double> rl, rr, zl, zr;
    Episodes(env, episodes, false, rl, rr);
    Episodes(env, 1, true, zl, zr);
    const Stats len = MeanSd(rl), ret = MeanSd(rr);
    char random[64], spread[64];
    std::snprintf(random, sizeof random, "%.1f, %.1f", len.mean, ret.mean);
    std::snprintf(spread, sizeof spread, "(+- %.1f, +- %.1f)", len.sd, ret.sd);
    std::printf("%-13s %12.0f %12.0f %12.0f %12.1f s %10.1f   %-26s %-26s %.0f, %.1f\n", name.c_str(), Median(physics),
                Median(stepping), train_rate, 1e6 / train_rate, trained->result.final_return, random, spread, zl[0],
                zr[0]);
    std::fflush(stdout);
  }
  return 0;
}
