// A soak run of the walking quadruped: the controller (runtime/loop, a walking policy) and the HIL
// (sim_hil/quadruped_rig.hpp) in lock-step in one process for a given number of ticks, under a
// seeded schedule of velocity commands (a phase every few seconds, hundreds of them) and of faults
// that end after a while: a motor that stops answering, the IMU lost, a bus off and restarted, a
// motor reporting an out-of-range position, the operator silent (the command source lost), frame
// drops, pushes. The robot file's recovery rule is automatic for the causes these faults raise,
// so the robot stops, recovers and walks again, fault after fault.
//
// What it checks, tick by tick (each broken promise is a violation, named with its tick):
//   - the controller's tick allocates nothing (every tick, from arming on);
//   - every supervised command is finite and inside the model's limits;
//   - a fault that begins while the robot walks reaches the safe state (safe-stop or e-stop)
//     within 3 ticks of the tick the robot file's limits make it detectable; a fault that must
//     not stop the robot (frame drops, a push, a short operator silence) does not;
//   - the robot runs again only by the recovery rule: a re-arm comes after the fault ended and
//     the robot was healthy for the rule's time, and every stop is followed by one (the robot
//     recovered), unless it fell;
// and it measures the process's resident memory over the run and the controller's tick time per
// tenth of the run (the tail must not drift: a figure, for benchmarks; RunQuadrupedSoak reports
// it, bench/soak.sh judges it).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/loop/log.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/rt/latency_histogram.hpp"

namespace pbppo::sim {

enum class SoakFaultKind : std::uint8_t {
  kSilentMotor,     // a motor stops answering
  kImuSilent,       // the IMU stops
  kBusOff,          // a bus goes off, then is restarted
  kBadReplies,      // a motor reports a position out of its bounds
  kOperatorSilent,  // the operator's velocity commands stop
  kDropFrames,      // 10 % of the frames a driver receives are lost (bursts of at most 2): degraded at most
  kPush,            // the base is pushed: nothing to stop for
};
inline constexpr std::size_t kSoakFaultKinds = 7;
const char* ToString(SoakFaultKind kind) noexcept;

struct SoakFault {
  SoakFaultKind kind = SoakFaultKind::kPush;
  std::uint64_t start = 0, end = 0;  // ticks: from start, up to (not including) end
  int subject = -1;                  // the motor or bus (CAN map index)
  std::uint64_t bound = 0;           // a stopping fault: the safe state by start + bound; 0: must not stop
  // What happened.
  bool while_walking = false;    // the robot walked (run phase, below safe-stop) when it began
  std::int64_t safe_tick = -1;   // the first tick in safe-stop or e-stop from start on (-1: none)
  std::int64_t rearm_tick = -1;  // the re-arm after it (-1: none)
};

struct SoakReport;

struct SoakOptions {
  std::uint64_t ticks = 100'000;
  std::uint64_t seed = 1;
  std::string policy;                      // the walking policy's blob
  double first_fault_s = 4.0;              // after the stand-up and a little walking
  double spacing_s[2] = {8.0, 12.0};       // between the starts of two faults (uniform)
  double command_phase_s[2] = {3.0, 8.0};  // the length of a velocity command's phase (uniform)
  std::uint64_t rss_every = 10'000;        // ticks between two samples of resident memory
  std::uint32_t trace_every = 0;           // the rig's trace (plots): a sample every this many ticks; 0: none
  // Real time: the controller ticks on its own clock at the robot's period (deadline misses acted
  // on, as on the robot); else lock-step, as fast as the plant allows.
  bool realtime = false;
  // A log of the controller's ticks ("": none; runtime/loop/log.hpp), rotated as record_options say.
  std::string record;
  loop::RecordOptions record_options;
  // Called every progress_every ticks (0: never) with the tick and the report so far.
  std::uint64_t progress_every = 0;
  std::function<void(std::uint64_t, const SoakReport&)> progress;
};

struct SoakReport {
  std::uint64_t ticks = 0;
  double wall_s = 0;
  std::vector<SoakFault> faults;  // in order
  std::uint64_t command_phases = 0;
  std::uint64_t allocations = 0;              // by the controller's ticks
  std::uint64_t commands_outside_limits = 0;  // ticks with a supervised command not finite or out of its limits
  std::uint64_t rearms = 0, stops = 0;        // re-arms (automatic), rises to safe-stop or e-stop
  std::uint64_t falls = 0;                    // tilted beyond 60 degrees (then no recovery is owed)
  std::vector<std::pair<std::uint64_t, std::uint64_t>> rss_kib;  // (tick, resident KiB)
  std::array<rt::LatencyStats, 10> tick_latency{};               // the controller's tick, per tenth of the run
  std::vector<std::string> violations;                           // "tick 123: ...", the first 100
  std::uint64_t violation_count = 0;
  std::vector<std::uint8_t> mode_by_second;  // the highest mode in each simulated second
  std::vector<std::string> summary;          // the loop's mode changes (the first 32) and counts
  // The log (SoakOptions::record): records, dropped, files begun and deleted, the recorder's error.
  std::uint64_t records = 0, records_dropped = 0;
  std::uint32_t record_files = 0, record_files_deleted = 0;
  std::string record_error;
};

// The soak's robot: `model` with an automatic recovery rule for every cause the faults raise (what
// RunQuadrupedSoak runs, and what a replay of its log loads). In real time, deadline overruns too:
// the plant shares the controller's thread, and a virtual machine's host can stall it for
// milliseconds (an hour's run here: five late ticks in a row once, a safe-stop that the rule
// without overruns never lifted).
robot::RobotModel SoakModel(const robot::RobotModel& model, bool realtime = false);

// The soak of `model` (a walking quadruped with a CAN map; its recovery rule is replaced by an
// automatic one for the faults' causes). Errors: the model, the policy, the rig's set-up.
Result<SoakReport> RunQuadrupedSoak(const robot::RobotModel& model, const SoakOptions& options);

// Resident memory of this process, KiB (/proc/self/statm; 0 if unreadable). No allocation.
std::uint64_t ResidentKiB() noexcept;

}  // namespace pbppo::sim
