// Training throughput as the bench programs report it: a run on one thread, whose CPU time (the
// calling thread did all the work) divides its environment steps.
#pragma once

#include <utility>

#include "bench/cpu_time.hpp"
#include "policies/trainer/trainer.hpp"

namespace pbppo::bench {

struct TrainingRate {
  trainer::TrainResult result;
  double steps_per_cpu_s = 0;  // environment steps per CPU second, updates included
};

// Trains `options` with one thread (options.threads is set to 1).
inline Result<TrainingRate> TrainOneThread(trainer::TrainOptions options) {
  options.threads = 1;
  const double t0 = CpuSeconds();
  auto trained = trainer::Train(options);
  const double cpu = CpuSeconds() - t0;
  if (!trained) return std::move(trained).error();
  const double rate = static_cast<double>(trained->env_steps) / cpu;
  return TrainingRate{std::move(*trained), rate};
}

}  // namespace pbppo::bench
