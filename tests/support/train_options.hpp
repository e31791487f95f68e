// Training options for the trainer's tests: an environment from the shipped models, and a clip
// schedule written as on the command line (--schedule, --arms).
#pragma once

#include <doctest/doctest.h>

#include <string>

#include "policies/trainer/clip_schedule.hpp"
#include "policies/trainer/options.hpp"
#include "policies/trainer/trainer.hpp"
#include "tests/support/test_paths.hpp"

namespace pbppo::test {

inline trainer::TrainOptions ForEnv(const std::string& env) {
  trainer::TrainOptions o;
  o.env.name = env;
  o.env.models_dir = SourcePath("models");
  return o;
}

// Trains `c` into `out_dir` (no plots); the run must succeed.
inline trainer::TrainResult TrainInto(trainer::TrainOptions c, const std::string& out_dir) {
  c.out_dir = out_dir;
  c.plots = false;
  auto r = trainer::Train(c);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  return std::move(*r);
}

inline trainer::ScheduleConfig Schedule(const std::string& schedule, const std::string& arms) {
  auto a = trainer::ParseArms(arms);
  REQUIRE_MESSAGE(a.ok(), a.error().message);
  auto s = trainer::ParseSchedule(schedule, *a);
  REQUIRE_MESSAGE(s.ok(), s.error().message);
  return *s;
}

}  // namespace pbppo::test
