// The robot as one immutable model: models/<robot>/robot.yaml names every piece of the robot and
// LoadRobotModel reads every file it names, once, into a RobotModel. The controller, the HIL
// simulator and the trainer's environments all take the same `const RobotModel&`; nothing reads a
// robot file again (ReadTextFile counts, a test checks). What changes per tick lives in a
// RobotData made from the model (runtime/robot/robot_data.hpp). Set-up time only.
//
// The model speaks of generic things only:
//   fields     the robot's inputs, one double each, grouped in streams that arrive together (a
//              DDS sample, one motor's reply, an IMU sample); each field has the bounds of the
//              one sample check;
//   commands   the robot's outputs, one double each, with the supervisor's limits and what
//              safe-stop does with them;
//   signals    what an IO layout may observe, computed from fields (runtime/robot/signals.hpp);
//   motors     actuators that are switched on at arming and off at shutdown (MIT drivers);
//   files      the files the runtime itself uses, as read: the DDS profile, the stand trajectory,
//              the trusted keys; and the robot-specific ones (its plant, task and layouts) as
//              documents by role, for the code that knows them (sim_hil, the environments).
// Streams, fields and commands of MIT motors and IMUs are made from the CAN map and the URDF;
// all others are declared in robot.yaml. Quantities per tick (stale ages, rate limits, the
// policy period) follow from the tick period; WithTickPeriod gives the same robot at another.
#pragma once

#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/can_map.hpp"
#include "runtime/robot/io_layout.hpp"
#include "runtime/robot/phase.hpp"
#include "runtime/robot/transport_spec.hpp"
#include "runtime/robot/urdf.hpp"
#include "runtime/robot/yaml_fields.hpp"
#include "runtime/safety/supervisor.hpp"

namespace pbppo::robot {

// Ages beyond which a stream is stale (degraded, safe-stop) or lost (e-stop): "older than".
struct StaleLimits {
  double degraded = 0, safe_stop = 0, lost = 0;  // in the stream's periods, as robot.yaml gives them
};

struct FieldSpec {
  std::string name;
  double min = -HUGE_VAL, max = HUGE_VAL;  // the one sample check: finite and inside
  std::uint32_t stream = 0;
};

enum class StreamKind : std::uint8_t { kDeclared, kMotor, kImu };

struct StreamSpec {
  std::string name;
  std::string transport;  // the transport that delivers it (TransportSpec::name)
  StreamKind kind = StreamKind::kDeclared;
  std::uint32_t device = 0;  // kMotor: motor index in the CAN map; kImu: IMU index
  std::uint32_t first_field = 0, field_count = 0;
  double period_s = 0;  // how often a new sample is due
  StaleLimits stale_after;
  std::uint32_t invalid_safe_stop = 1;  // consecutive invalid checks that ask for safe-stop
  // false: silence before the first sample is no fault (an operator who has not spoken yet);
  // once a sample came, the stream is stale and lost like any other.
  bool required = true;
  // > 0 (zero_after in robot.yaml): a command source, such as a velocity command from a navigation
  // stack, whose silence is no fault: older than this many periods, every field of the stream reads
  // 0 (the command stops) until the next sample. stale_after is not given then.
  double zero_after = 0;
  // Per tick (derived from the tick period): ages in ticks, "older than".
  std::uint32_t stale_degraded_ticks = 0, stale_safe_stop_ticks = 0, lost_ticks = 0, zero_after_ticks = 0;
};

struct CommandSpec {
  std::string name, unit;
  double min = 0, max = 0;                    // limits: the supervisor clamps into them
  double degraded_min = 0, degraded_max = 0;  // limits in degraded mode
  double rate_per_s = HUGE_VAL;               // largest change per second (inf: none)
  // What safe-stop sends: a ramp to zero (stop_ramp_per_s), stop_value, or the measured value of
  // the field hold_input (a joint's position), inside the range.
  safety::StopKind stop = safety::StopKind::kValue;
  double stop_ramp_per_s = 0, stop_value = 0;
  std::int32_t hold_input = -1;
  double neutral = 0;       // before a command source writes it: the default pose, the gains, zero
  std::int32_t motor = -1;  // the motor it drives (MotorSpec), -1: none
  double rate = HUGE_VAL;   // per tick (derived)
  double stop_rate = 0;     // per tick (derived)
};

// A command index a motor does not have (a velocity-commanded motor's q_des_ and kp_).
inline constexpr std::uint32_t kNoCommand = 0xffffffffu;

// An actuator that is switched on at arming and off at shutdown (an MIT driver), answering on
// its stream. A position-commanded motor has five commands (q_des_, dq_des_, kp_, kd_, tau_ff_);
// a velocity-commanded one (a wheel) three (dq_des_, kd_, tau_ff_): its frames carry kp 0 and
// p_des 0, so nothing can give it a position target.
struct MotorSpec {
  std::string joint;
  std::uint32_t stream = 0;
  std::uint32_t q_field = 0, dq_field = 0, tau_field = 0;  // its reply
  // Without a CAN map, with motors.lost_per_sample_max: lost_<joint>, how much the driver's count
  // of lost frames grew since the previous sample (in [0, that max]); else -1.
  std::int32_t lost_field = -1;
  std::uint32_t q = 0, dq = 0, kp = 0, kd = 0, tau = 0;  // its commands (q, kp: kNoCommand when velocity)
  JointControl control = JointControl::kPosition;
  // A continuous joint: no position bound anywhere; q_<joint> is the multi-turn angle the transport
  // unwraps from the driver's position, which wraps in the MIT range [p_min, p_max).
  bool continuous = false;
  double default_q_rad = 0;  // position-commanded: the pose stand-up ends in and hold keeps
  double sit_q_rad = 0;      // position-commanded: the pose a sit-down ends in (the description's sit_pose)
  // The gains a policy's position targets are tracked with (robot.yaml motors.policy_gains); < 0: the
  // commands' neutral gains. Position-commanded motors only.
  double policy_kp = -1, policy_kd = -1;

  bool velocity_commanded() const noexcept { return control == JointControl::kVelocity; }
};

// A signal declared in robot.yaml (runtime/robot/signals.hpp resolves and computes them).
struct SignalSpec {
  enum class Op : std::uint8_t { kField, kWrap, kCos, kSin, kMinus, kMin, kGravityX, kGravityY, kGravityZ };
  std::string name;
  Op op = Op::kField;
  std::vector<std::uint32_t> fields;  // kMin: several; kGravity*: the IMU's qw, qx, qy, qz; else one
  double value = 0;                   // kMinus: the parameter subtracted
};

struct PhaseSpec {
  bool enable_motors = false;  // arming switches motors on (the robot has motors)
  double arming_timeout_s = 0, stand_up_s = 0, hold_s = 0, damping_s = 0, motor_off_timeout_s = 0;
  // A sit-down (a ramp from the measured pose to the description's sit_pose, then passive: damped,
  // motors on) takes sit_down_s; 0: the robot does not sit (its description has no sit pose).
  double sit_down_s = 0;
  // Per tick (derived).
  std::uint32_t arming_timeout_ticks = 0, stand_up_ticks = 0, hold_ticks = 0, damping_ticks = 0,
                motor_off_timeout_ticks = 0, sit_down_ticks = 0;
};

struct SignalLimitSpec {
  std::string signal;
  double min = 0, max = 0;
  std::uint32_t stream = 0;  // the stream the signal is computed from (checked once it was seen)
};

// How the robot's controller runs as a service (robot.yaml `service`).
struct ServiceSpec {
  // A controller started again by its service after a run that ended in failure (a crash, the
  // watchdog, an error exit) arms the robot again. Default false: it refuses, and a person starts it.
  bool rearm_after_failure = false;
};

// A person's requests through fields of the robot's inputs (robot.yaml `operator`): a gamepad's
// buttons (a transport of kind evdev), a remote's keys in a DDS message. Each names a field (-1:
// none); a request is the field's rise (from below 0.5 to at least 0.5), the dead-man its level.
// runtime/loop/loop.hpp says what each does to the phases.
//
//   operator:
//     arm: start_button       # stand up from the measured pose, then hold the default pose
//     walk: walk_button       # from hold, run the command source (without it: after hold_s)
//     sit: sit_button         # sit down (to the description's sit_pose), then passive: damped, motors
//                             # on, until arm stands it up again (phases.sit_down_s)
//     stop: stop_button       # shut down: damping, then motors off
//     estop: estop_button     # e-stop (the supervisor latches it)
//     rearm: rearm_button     # run again after a safe-stop or e-stop (supervisor.recovery's rule)
//     deadman: deadman_button # the command source runs only while it is held; released: stand
//     switch_policy: next_button   # the next of several policies (runtime/loop/policy_set.hpp)
//     switch: {rule: blend, duration_s: 0.5}  # blend the commands in, or hold the default pose
enum class SwitchRule : std::uint8_t { kBlend, kHold };
struct OperatorSpec {
  std::int32_t arm = -1, walk = -1, stop = -1, estop = -1, rearm = -1, deadman = -1, switch_policy = -1, sit = -1;
  SwitchRule switch_rule = SwitchRule::kBlend;
  double switch_s = 0.5;
  std::uint32_t switch_ticks = 0;  // derived
  // After the dead-man's release the robot stands up and holds; not held again by this long into
  // the hold, it sits down (then passive). 0: it holds.
  double deadman_sit_after_s = 0;
  std::uint32_t deadman_sit_after_ticks = 0;  // derived
  // operator.from: the phases a request is taken in, a subset of the controller's (phase.hpp); 0:
  // all of the controller's.
  PhaseSet from_arm = 0, from_sit = 0, from_switch = 0;
  // operator.rearm_to: passive: a re-armed robot (the recovery rule) is left passive (damped,
  // motors on; arm stands it up), not stood up.
  bool rearm_to_passive = false;
  bool any() const noexcept {
    return arm >= 0 || walk >= 0 || stop >= 0 || estop >= 0 || rearm >= 0 || deadman >= 0 || switch_policy >= 0 ||
           sit >= 0;
  }
};

// What it takes to run again after the supervisor stopped the armed robot (safe-stop or e-stop)
// and the cause went away (robot.yaml supervisor.recovery; runtime/loop/loop.hpp says how).
struct RecoverySpec {
  bool automatic = false;           // rule: automatic; else only a person's request (the default)
  double healthy_s = 1.0;           // healthy this long first: no finding but command and rate limits
  std::uint32_t causes = 0;         // automatic: bit (1 << Cause) of each cause allowed to stop and recover
  std::uint32_t max_automatic = 3;  // automatic re-arms per run; then only a request
  std::uint32_t healthy_ticks = 0;  // derived
};

struct SupervisorSpec {
  bool command_limit_degrades = false;  // command_limit: degraded (else: count)
  bool estop_damps = false;             // estop: damping (else: motors_off)
  std::uint32_t overrun_degraded = 2, overrun_safe_stop = 5;
  std::vector<SignalLimitSpec> signal_limits;
  RecoverySpec recovery;
};

// A file robot.yaml names that runtime/robot does not interpret itself, as read.
struct RobotDocument {
  std::string path;
  std::string text;
  YAML::Node yaml;  // parsed, for .yaml files
};

// A public key the robot trusts to have signed its policies (files.trusted_keys[.NAME]).
struct TrustedKeyFile {
  std::string name;  // "trusted_keys", or NAME
  RobotDocument file;
};

struct RobotModel {
  std::string name, description;
  std::string path, dir;  // robot.yaml and its folder
  double tick_period_s = 0, policy_period_s = 0;
  std::uint32_t policy_period_ticks = 1;  // derived
  std::int32_t policy_trigger = -1;       // a stream whose new samples run the policy; -1: every period
  // Lock-step with a simulator over a stream (timing.lockstep): one tick per new sample of
  // lockstep_stream (-1: none), and the run ends after the tick that takes a sample whose field
  // lockstep_end_field is not 0 (-1: none; the simulator's episode end).
  std::int32_t lockstep_stream = -1, lockstep_end_field = -1;
  std::map<std::string, double> parameters;
  std::optional<IoLayout> io;  // the policy's layout, when the robot has one
  std::optional<RobotDescription> body;
  std::optional<CanMap> can;
  std::vector<TransportSpec> transports;
  std::vector<FieldSpec> fields;
  std::vector<StreamSpec> streams;
  std::vector<CommandSpec> commands;
  std::vector<MotorSpec> motors;
  std::vector<SignalSpec> signals;
  PhaseSpec phases;
  SupervisorSpec supervisor;
  ServiceSpec service;
  OperatorSpec op;                                 // robot.yaml operator
  std::optional<RobotDocument> dds_profile;        // files.dds_profile: Fast DDS XML profiles (transports of kind dds)
  std::optional<RobotDocument> stand_trajectory;   // files.stand_trajectory: the robot's own joint trajectory
  std::vector<TrustedKeyFile> trusted_keys;        // files.trusted_keys[.NAME] (PEM); none: unsigned blobs run
  std::map<std::string, RobotDocument> documents;  // the robot-specific files by role: "plant", "layouts.hard", ...
  std::uint64_t hash = 0;                          // FNV-1a over every file read, in order
  // The supervisor's model at this tick period (derived; validated at load).
  safety::SupervisorModel supervisor_model;

  int FieldIndex(std::string_view name) const noexcept;
  int CommandIndex(std::string_view name) const noexcept;
  int StreamIndex(std::string_view name) const noexcept;
  int TransportIndex(std::string_view name) const noexcept;
  // A document by role; the error names robot.yaml and the role.
  Result<const RobotDocument*> Document(const std::string& role) const;
  // Names of the documents under a group ("layouts" -> easy, medium, hard).
  std::vector<std::string> DocumentGroup(const std::string& group) const;
  Result<double> Parameter(const std::string& name) const;
};

// Reads robot.yaml and every file it names; errors name the file, the field and the value. The
// robot is a path or an installed robot's name (runtime/robot/find_robot.hpp).
Result<RobotModel> LoadRobotModel(const std::string& name_or_path);
// The same robot ticking every tick_period_s: stale ages in ticks, rates per tick, phase lengths
// and the policy period follow (a sample a little late at a faster tick still counts as on time:
// stale limits are n and a half periods). Refuses a policy period that is not a whole number of
// ticks.
Result<RobotModel> WithTickPeriod(const RobotModel& model, double tick_period_s);

// "sonar_{i}_m" with i = 3 -> "sonar_3_m".
std::string ExpandIndex(const std::string& pattern, std::uint32_t i);

}  // namespace pbppo::robot
