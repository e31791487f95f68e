// Real-time set-up of the calling thread, each step only where permitted: mlockall (no page
// faults later), a pre-faulted stack, SCHED_FIFO at a priority, CPU affinity. A step that fails
// leaves a warning naming the step and the reason (errno text) and the rest goes on: a controller
// on a development machine without the privilege still runs, and says so. Set-up time only.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace pbppo::rt {

struct RtOptions {
  bool lock_memory = true;
  std::size_t prefault_stack_bytes = 256 * 1024;
  int fifo_priority = 80;  // 1..99; 0 keeps the current policy
  int cpu = -1;            // pin to this CPU; -1 keeps the current affinity
};

struct RtSetupResult {
  bool memory_locked = false;
  bool stack_prefaulted = false;
  bool fifo = false;
  int priority = 0;
  bool pinned = false;
  int cpu = -1;
  std::vector<std::string> warnings;  // "SCHED_FIFO 80: Operation not permitted (needs CAP_SYS_NICE ...)"
  // One line: what was applied and what was not.
  std::string Summary() const;
};

RtSetupResult SetUpRealTime(const RtOptions& options);

}  // namespace pbppo::rt
