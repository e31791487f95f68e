// `pbppo eval --env quadruped-walk`: the paper's quadruped test (policies/envs/walk_eval.hpp) as a
// command: tracking errors per axis, falls, a plot of commanded against measured velocities.
#pragma once

#include "policies/cli/eval.hpp"
#include "policies/envs/quadruped_walk.hpp"
#include "runtime/policy/policy_model.hpp"

namespace pbppo::cli {

// `model` and `env` as pbppo eval loaded and built them from `o`.
int EvalWalk(const EvalOptions& o, const policy::PolicyModel& model, envs::QuadrupedWalk& env);

}  // namespace pbppo::cli
