// `pbppo sweep --out DIR --grid KEY=V1,V2 ... --seeds 1-5 [--jobs N] -- TRAIN_FLAGS...`: a grid of
// `pbppo train` runs, each in its own child process and folder (DIR/KEY=V/.../seed=N), every one's
// final policy evaluated with `pbppo eval`, and a table per grid cell over the seeds (docs/sweep.md).
// Every run's argument list is checked with pbppo train's own parser before anything runs or is
// written. A finished run (result.json) is never repeated; started under mpirun, the ranks share the
// pending runs. Exit 0: every run finished; 1: a run failed; 2: usage; 130: interrupted.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace pbppo::cli {

struct SweepOptions {
  std::string out;                       // DIR
  std::vector<std::string> grid;         // KEY=V1,V2,... (a comma inside a value written '\,')
  std::string seeds = "1";               // 1-5, 1,3,7 or both: 1-3,8
  int jobs = 1;                          // runs at once on this machine (1 under mpirun)
  int final_episodes = 10;               // deterministic episodes of each final policy
  std::uint64_t eval_seed = 7;           // their initial states' seed (pbppo eval --seed)
  bool dry_run = false;                  // print the plan, write nothing
  std::vector<std::string> train_flags;  // after --: pbppo train flags shared by every run
};

// Adds the subcommand to `app`; Sweep runs it.
CLI::App* AddSweep(CLI::App& app, SweepOptions& o);
int Sweep(const SweepOptions& o);

}  // namespace pbppo::cli
