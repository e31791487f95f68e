// pbppo sweep's plan: the grid axes (--grid KEY=V1,V2), the seeds, and every run's `pbppo train`
// and `pbppo eval` argument lists, each checked with pbppo train's own parser, TrainOptions::Validate
// and envs::MakeEnv before anything runs or is written.
#pragma once

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "policies/cli/sweep.hpp"
#include "runtime/core/result.hpp"

namespace pbppo::cli {

using Json = nlohmann::ordered_json;

struct Axis {
  std::string key;
  std::vector<std::string> values;
};

struct Run {
  std::size_t cell = 0;  // index into Plan::cells
  std::uint64_t seed = 0;
  std::string rel;                                 // KEY=V/.../seed=N below DIR
  std::vector<std::string> train_args, eval_args;  // after the program's name
};

struct Plan {
  std::vector<Axis> axes;
  std::vector<std::uint64_t> seeds;
  std::vector<std::vector<std::string>> cells;  // each cell's values, one per axis; the first axis outermost
  std::vector<Run> runs;                        // cell by cell, seeds inside
  Json record;                                  // DIR/sweep.json
};

// The cell's grid values as "KEY=V KEY=V" ("(no grid)" without axes).
std::string CellName(const Plan& p, std::size_t cell);

// Every run of the sweep `o`; nothing is written. Errors name the flag or the grid value.
Result<Plan> MakePlan(const SweepOptions& o);

}  // namespace pbppo::cli
