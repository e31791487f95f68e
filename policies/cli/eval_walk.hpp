// `pbppo eval --env quadruped-walk`: the paper's quadruped test (policies/envs/walk_eval.hpp) as a
// command: tracking errors per axis, falls, a plot of commanded against measured velocities.
#pragma once

#include "policies/cli/eval.hpp"

namespace pbppo::cli {

int EvalWalk(const EvalOptions& o);

}  // namespace pbppo::cli
