// pbppo-hil quadruped: the quadruped HIL program (usage in hil_main.cpp).
#pragma once

#include <atomic>

namespace pbppo::sim {

// argv[0] is "quadruped". Exit status: 0 done, 1 a failure at run time, 2 bad arguments or files.
int RunQuadrupedHil(int argc, char** argv, const std::atomic<bool>& stop);

}  // namespace pbppo::sim
