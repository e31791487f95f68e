// `pbppo eval`: a frozen blob on an environment through the runtime's forward, episode by episode,
// with what the environment adds to them or its own test in their place (envs::EnvEvaluation).
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
  // --env, --models and the environment's flags, pbppo eval's included (--plot, --schedule, ...).
  envs::EnvOptions env = [] {
    envs::EnvOptions e;
    e.purpose = envs::EnvPurpose::kEval;
    return e;
  }();
  int episodes = 0;  // 0: the environment's test size
  std::uint64_t seed = 7;
  // The forward kernel: auto (AVX-512 or NEON where the CPU has it), portable, avx512 or neon. The kernels round
  // differently, so a chaotic task's deterministic episodes can differ between machines; portable
  // gives every machine the same figures.
  std::string kernel = "auto";
  bool json = false;
};
void AddEvalOptions(CLI::App& sub, EvalOptions& o);
int Eval(const EvalOptions& o);

}  // namespace pbppo::cli
