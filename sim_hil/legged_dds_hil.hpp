// A legged robot whose motors speak DDS (the Go2: models/go2), behind an emulation of its
// low-level interface: the Simbody plant of its description on the ground, and the robot's side
// of its DDS transport (the peer of pbppo-controller's): the state message (LowState_) at the
// robot's rate, filled from the plant through the robot file's mapping and sealed with its
// checksum; the command message (LowCmd_) read in arrival order, its checksum checked, each
// motor's command taken through the same mapping (mode, q, dq, kp, kd, tau) and turned into a
// torque at the plant's rate, as the motor computes it:
//
//   tau = kp (q_des - q) + kd (dq_des - dq) + tau_ff, clamped to the joint's effort limit
//
// (no position term when q_des is the SDK's PosStopF 2.146e9, no velocity term at VelStopF
// 16000; no torque while the motor's mode is 0). Nothing in it names a robot: any robot file
// whose motors arrive in a DDS message and leave in another runs here.
//
// Lock-step (default): after each state sample the simulator waits for the command that answers
// it (the controller ticks once per sample: pbppo-controller --lockstep), then advances one robot
// period. Real time: one period per period of wall time, the newest command applied.
//
// Faults as data (--fault KIND@SECONDS[+DURATION][:MOTOR]): stop (no state sample), crc (samples
// whose checksum does not match), nan (the motor's position NaN), range (its position 10 rad,
// beyond every joint's limits), lost (the motor's count of lost frames grows by one per sample),
// silent (the motor stops answering: no torque, its state held at the last it reported, its count
// of lost frames growing by one per sample). The report says, per fault, how many periods after it
// began the controller's commands reached damping (every motor kp 0 and kd > 0) or passive (mode 0).
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

namespace pbppo::sim {

struct LeggedDdsFault {
  std::string kind;  // stop, crc, nan, range, lost, silent
  double start_s = 0, duration_s = 1e300;
  int motor = 0;  // nan, range, lost, silent: the motor (the robot's order)
};

struct LeggedDdsHilOptions {
  std::string robot = "go2";  // a name or its robot.yaml
  std::string commands;       // the controller's velocity schedule: per-phase tracking in the report
  std::string report;         // JSON
  std::string trace;          // CSV, one row per 10 periods
  std::string plot;           // PNG: commanded and measured velocity (and <stem>_path.png, the base path)
  bool lockstep = true;
  int domain_id = 0;
  double duration_s = 0;  // simulated; 0: until the controller leaves (or the schedule's end + 3 s)
  double settle_s = 1.0;
  double peer_timeout_s = 30, command_timeout_s = 10;
  std::vector<LeggedDdsFault> faults;
  // The robot's side of a person's hands: a schedule (runtime/loop/schedule.hpp) of a stream its
  // state message carries (the Go2's remote: models/go2_remote's stream remote), played on the
  // robot's clock into every state sample; after its end every field 0 (released, centred).
  std::string remote;
};

// Parses "KIND@SECONDS[+DURATION][:MOTOR]"; the error names the text.
bool ParseLeggedDdsFault(const std::string& text, LeggedDdsFault* out, std::string* error);

// Runs until the duration, the controller leaves or `stop`; prints the run's summary. 0: the
// plant ran and every command was valid; 1: an error, a command outside the robot's limits or a
// checksum that did not match.
int RunLeggedDdsHil(const LeggedDdsHilOptions& options, const std::atomic<bool>& stop);

}  // namespace pbppo::sim
