// The AUV HIL simulator over DDS: sim::AuvNavTask (Simbody plant, sonar, targets) as the vehicle,
// the peer of the robot's DDS transport (its messages as models/auv/robot.yaml declares them). It
// publishes a sensor sample per control period and applies the physical commands ([v, omega])
// the controller sends back.
//
//  lock-step: sample 0 after reset (once the controller has matched); then for each command
//    whose `answers` equals the tick of the last sample: apply it, advance one control period,
//    publish the sample of tick + 1. Commands answering other ticks are ignored and counted. The
//    run depends only on the seed and the commands, never on the machine's speed.
//  real-time: one period per control period of wall time (absolute deadlines); each period
//    applies the newest command received (zero before the first) and publishes a sample.
//
// The run ends at mission complete, collision, the task's time limit, --max-time, a stop
// request (SIGINT/SIGTERM) or, in lock-step, when the controller stays silent too long.
#pragma once

#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>

#include "runtime/core/result.hpp"

namespace pbppo::sim {

struct AuvHilOptions {
  std::string layout = "easy";  // easy | medium | hard
  std::uint64_t seed = 0;
  bool lockstep = true;
  int domain_id = 0;
  std::string dds_naming = "native";                  // native | ros2 (runtime/transport/dds/dds_endpoint.hpp)
  std::string dds_security;                           // a DDS Security folder ("": none)
  std::string dds_identity = "hil";                   // --dds-security: this participant's certificate name
  double max_time_s = 0.0;                            // simulated seconds; 0: the task's episode limit only
  std::string trajectory_csv, plot_png, events_json;  // empty: not written
  std::string robot = "auv";        // the robot, a name or its robot.yaml (plant, layouts, IO layout, DDS profile)
  double peer_timeout_s = 30.0;     // waiting for the controller to appear
  double command_timeout_s = 10.0;  // lock-step: longest wait for the next command
  // Fault injection for tests of the controller's supervisor: from simulated time fault_time_s on,
  // every published sample carries the fault: "nan" (yaw and surge speed NaN) or "range" (surge
  // speed 99 m/s, beyond any plausible value). Empty: none.
  std::string fault;
  double fault_time_s = 0.0;
  double fault_duration_s = HUGE_VAL;  // the fault ends after this long (inf: never)
};

enum class AuvHilOutcome { kSuccess, kCollision, kTimeLimit, kMaxTime, kStopped, kControllerLost, kError };
const char* ToString(AuvHilOutcome o) noexcept;

// Runs one episode; prints a summary to stdout. Returns the process exit code: 0 when the episode
// ran to one of its ends (success, collision, time limits) or was stopped, and every requested
// output was written; 1 otherwise (the reason printed to stderr).
int RunAuvHil(const AuvHilOptions& options, const std::atomic<bool>& stop);

}  // namespace pbppo::sim
