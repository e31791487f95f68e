// `pbppo eval`: a frozen blob on an environment through the runtime's forward, episode by episode.
#pragma once

#include <cstdint>
#include <string>

#include "policies/envs/env.hpp"

namespace CLI {
class App;
}

namespace pbppo::cli {

struct EvalOptions {
  std::string blob;
  envs::EnvOptions env = [] {  // --env, --layout, --models, --terrain, --commands
    envs::EnvOptions e;
    e.randomize = false;  // the nominal robot unless --randomize
    return e;
  }();
  std::string plot;          // PNG of the trajectories over the map (auv-nav)
  std::string trajectories;  // CSV of every episode's trajectory (auv-nav)
  std::string outcomes;      // CSV, one row per episode: outcome, end pose, random obstacles (auv-nav)
  std::string schedule;      // quadruped-walk: one robot commanded by a velocity schedule (models/quadruped/schedules)
  double settle_s = 1.0;     // --schedule: tracking is judged this long after each phase starts
  int episodes = 0;          // 0: the environment's test size (100; quadruped-walk: the paper's 50 robots)
  std::uint64_t seed = 7;
  // MuJoCo tasks: every episode runs the task's full length, stepping on through terminations (the
  // paper's released evaluation: 1000 deterministic steps, ignoring episode ends).
  bool through_ends = false;
  // The forward kernel: auto (AVX-512 where the CPU has it), portable or avx512. The kernels round
  // differently, so a chaotic task's deterministic episodes can differ between machines; portable
  // gives every machine the same figures.
  std::string kernel = "auto";
  bool json = false;
};
void AddEvalOptions(CLI::App& sub, EvalOptions& o);
int Eval(const EvalOptions& o);

}  // namespace pbppo::cli
