// One tick for every robot (ros2_control's read -> update -> write; Drake's const system and
// context):
//
//   read       every transport drains what arrived into the RobotData (the only code that
//              knows sockets or DDS)
//   check      the one sample check: every stream's fields against the model's bounds; ages
//   observe    \  the command source: a policy builds its observation from the model's signals
//   infer      /  and runs Forward on its period (the action held between), or a trajectory
//   supervise  the phase (arming, stand-up, hold, run, damping, motor off) and the supervisor,
//              whose causes (transport health, inference status, deadline misses ...) are named
//   write      every transport sends the supervised command
//
// Tick is noexcept and allocates nothing; time comes in as the tick index (the clock is the
// caller's: runtime/loop/runner.hpp). Each stage is timed into the loop's profiler; with a
// recorder attached, every input the tick consumed is logged (runtime/loop/log.hpp) so that a
// replay reproduces the commands bit for bit.
//
// Phases. Arm() starts arming: robots with motors switch each on until it answers, then stand up
// (a smoothstep from the measured pose to the default pose; velocity-commanded motors, wheels,
// hold zero speed), hold, and run the command source;
// robots without motors run at once. A robot that sits (robot.yaml phases.sit_down_s, its
// description's sit_pose) sits down on the operator's request: the same smoothstep from the
// measured pose to the sit pose, then passive (the damping values, motors on) until arm stands it
// up again from where it is. RequestStop() shuts down: motors are damped (the
// supervisor's safe-stop values), then switched off until each answers; a robot without motors
// sends its e-stop command once (Shutdown). An e-stop request while arming (not supervised: the
// motors are not answering yet) switches the motors off as a stop does, and the supervisor takes
// the request there and latches e-stop. Every transition and every rise of the supervisor's
// mode is logged with its tick and reason.
//
// Recovery (robot.yaml supervisor.recovery). The supervisor's modes latch; once it has stopped the
// armed robot (safe-stop or e-stop), the robot runs again only by the robot file's rule, and only
// after it has been healthy for healthy_s (no finding but command and rate limits: every stream
// fresh and valid, every link healthy, no overrun, no signal out of range, no e-stop request):
//   request    a person's RequestRearm() (pbppo-controller: SIGUSR1); one that comes too early or
//              with nothing to recover from is refused, counted and said (RecoveryStatus)
//   automatic  the same at once, if every cause that raised the mode to safe-stop or e-stop is one
//              the robot file lists, at most max_automatic times a run (then only a request)
// Operator requests (robot.yaml operator: fields such as a gamepad's buttons; runtime/robot/
// robot_model.hpp). A field's rise to at least 0.5 asks, at that tick, as the calls below do:
//   arm      Arm(): from disarmed (a robot without motors runs), and from passive: stand up; not
//            while a fault is latched (re-arm first). Disarmed, nothing is sent to the motors, and
//            their silence is not judged until arming has them answering
//   walk     from hold, run the command source; without it the source starts after hold_s
//   sit      from stand-up, hold and run (no fault latched): sit down, then passive; arm stands up
//   stop     RequestStop(): damping, then motors off
//   estop    an e-stop request at that tick (the supervisor's e-stop latches: motors off, or with
//            supervisor.estop: damping, on with the damping commands)
//   rearm    RequestRearm(): run again after a safe-stop or e-stop, by the recovery rule below
//            (with operator.rearm_to: passive, a robot re-armed is left passive, arm stands it up)
//   switch_policy  the next of several command sources (runtime/loop/policy_set.hpp), in hold or
//            run and while no fault is latched (safe-stop, e-stop)
//   deadman  its level: the source runs only while it is held (the hold phase waits for it);
//            released while running, a robot with motors stands up from the measured pose to
//            the default pose and holds (the source is started clean when it runs again); one
//            without motors disarms (an arm request runs it again). With deadman_sit_after_s, a
//            robot not holding the dead-man again that long into that hold sits down (passive)
// A stream whose sample the check found invalid makes no request but e-stop that tick. Which
// field made which request is derived from the fields, so a recorded run replays them. A request
// the phase does not take (arm outside disarmed and passive, walk outside hold, without the dead-man or
// before hold_s is over, a switch with one source, outside hold and run or with a fault latched)
// changes nothing and is refused, counted and said (OperatorStatus); so is a sit outside stand-up,
// hold and run or with a fault latched, and an arm with a fault latched.
//
// Re-arming is arming again at a tick boundary: the supervisor back to nominal (its counters kept),
// then robots with motors arm, stand up from the measured pose and hold before the command source
// starts again; robots without run the source at once. The source starts clean (a policy's history
// and last action). The mode change list says "nominal: re-armed ..." with the rule and the causes.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/latest_mailbox.hpp"
#include "runtime/core/result.hpp"
#include "runtime/loop/state_bytes.hpp"
#include "runtime/robot/robot_data.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/robot/signals.hpp"
#include "runtime/rt/tick_clock.hpp"
#include "runtime/rt/tick_profiler.hpp"
#include "runtime/safety/supervisor.hpp"

namespace pbppo::loop {

// (Numbered as logs store them: later phases come last.)
// The phases (runtime/robot/phase.hpp, where a robot file's operator.from names them).
using robot::kPhaseCount;
using robot::Phase;
using robot::ToString;

class LoopData;
class Recorder;

// What the run phase commands: a policy (policy_source.hpp), a scripted trajectory
// (trajectory_source.hpp), ... The loop does not care which.
class CommandSource {
 public:
  virtual ~CommandSource() = default;
  // The run phase begins (the first run tick follows).
  virtual void Start(const robot::RobotModel& model, const robot::RobotData& data, LoopData& loop) noexcept = 0;
  // A run tick: writes its commands into `desired` (holding each command's neutral value on
  // entry); false when it has finished (the loop holds the default pose, or shuts down).
  virtual bool Compute(const robot::RobotModel& model, const robot::RobotData& data, LoopData& loop,
                       std::span<double> desired) noexcept = 0;
  // The inference status to supervise (a policy's Forward); nullptr: fine.
  virtual const char* failure() const noexcept { return nullptr; }
  // What Compute carries from one tick to the next (a policy's history and last action), for a
  // log's snapshot (SaveState below): written without allocation; read back into a source made
  // from the same files, false (the reader's error set) where it does not fit.
  virtual void SaveState(StateWriter& out) const noexcept { (void)out; }
  virtual bool LoadState(StateReader& in) {
    (void)in;
    return true;
  }
  // The operator asks for the next of several sources (runtime/loop/policy_set.hpp): true if
  // taken (at the next Compute), false: there is no other.
  virtual bool Switch() noexcept { return false; }
};

struct LoopOptions {
  bool shutdown_after_source = false;  // the source finished: shut down (else hold the default pose)
  // Lock-step with a simulator (robot.yaml timing.lockstep.end_field): a fresh sample whose end
  // field is 1 stops the run after the tick that took it (the simulator's episode ended).
  bool stop_at_end_field = false;
};

// The requests a tick consumed (LoopData::Arm ...), as the log records them.
struct TickEvents {
  bool arm = false, disarm = false, stop = false, estop = false, rearm = false;
  // From the operator's fields (not recorded: derived from the recorded fields).
  bool walk = false, deadman = true;
  std::uint8_t operator_rises = 0;  // bit i: request i of OperatorRequest rose this tick
};

// The operator's requests from fields (robot.yaml operator), in the order of their bits.
enum class OperatorRequest : std::uint8_t { kArm, kWalk, kStop, kEStop, kRearm, kSwitch, kSit };
inline constexpr std::size_t kOperatorRequestCount = 7;

// What became of the operator's requests: each counted, a refused one said (a re-arm's is
// RecoveryStatus's).
struct OperatorStatus {
  std::uint64_t requests = 0, refused = 0;
  std::uint64_t last_tick = 0;  // of the last refusal
  char last[120] = {};          // "walk refused at tick 1200: not holding (stand-up)"
};
// "12 requests, 1 refused; the last: ..." for a summary; "" when there was none.
std::string Describe(const OperatorStatus& status);

// How the robot came back after the supervisor stopped it (see Recovery above).
struct RecoveryStatus {
  std::uint64_t stops = 0;                     // rises to safe-stop or e-stop from below (while supervised)
  std::uint64_t automatic = 0, requested = 0;  // re-arms
  std::uint64_t refused = 0;                   // requests refused
  std::uint64_t last_tick = 0;                 // of the last re-arm or refusal
  bool last_refused = false;
  char last[160] = {};  // "re-armed on request after 1000 healthy ticks (stopped by: transport fault)"
};

struct ModeChange {
  std::uint64_t tick = 0;
  safety::Mode mode = safety::Mode::kNominal;
  char reason[120] = {};
};

struct PhaseChange {
  std::uint64_t tick = 0;
  Phase from = Phase::kDisarmed, to = Phase::kDisarmed;
};

// A snapshot for another (non-real-time) thread: status publication, progress lines.
struct LoopStatus {
  std::uint64_t tick = 0;
  Phase phase = Phase::kDisarmed;
  safety::Mode mode = safety::Mode::kNominal;
  safety::Cause latched = safety::Cause::kEStopRequest;
  bool any_latched = false;
  safety::CauseCounts counts;
  std::uint64_t rearms = 0, refused = 0;  // RecoveryStatus: automatic + requested, refused
  char recovery[160] = {};                // RecoveryStatus::last
};

class LoopData {
 public:
  static constexpr std::size_t kMaxChanges = 32;

  Phase phase() const noexcept { return phase_; }
  std::uint64_t phase_start(Phase p) const noexcept { return phase_start_[static_cast<std::size_t>(p)]; }
  const safety::SupervisorState& supervisor() const noexcept { return sup_; }
  const safety::Decision& decision() const noexcept { return sup_.last; }
  rt::TickProfiler& profiler() noexcept { return profiler_; }
  const rt::TickProfiler& profiler() const noexcept { return profiler_; }
  // The first kMaxChanges mode and phase changes, and how many there were in all.
  std::span<const ModeChange> mode_changes() const noexcept { return Changes(modes_, mode_count_); }
  std::span<const PhaseChange> phase_changes() const noexcept { return Changes(phases_, phase_count_); }
  std::uint64_t mode_change_count() const noexcept { return mode_count_; }
  std::uint64_t phase_change_count() const noexcept { return phase_count_; }
  // Another thread's view (single reader).
  LoopStatus Status() const noexcept;

  // Any thread, async-signal-safe: take effect at the next tick.
  void Arm() noexcept { arm_.store(true, std::memory_order_relaxed); }
  void Disarm() noexcept { disarm_.store(true, std::memory_order_relaxed); }
  void RequestStop() noexcept { stop_.store(true, std::memory_order_relaxed); }
  void RequestEStop() noexcept { estop_.store(true, std::memory_order_relaxed); }
  // A person's request to run again after a safe-stop or e-stop (Recovery above).
  void RequestRearm() noexcept { rearm_.store(true, std::memory_order_relaxed); }
  const RecoveryStatus& recovery() const noexcept { return recovery_; }
  const OperatorStatus& operator_status() const noexcept { return operator_status_; }
  // Consecutive healthy supervised ticks (saturating at 2^32 - 1).
  std::uint32_t healthy_ticks() const noexcept { return healthy_ticks_; }
  // The run reached the robot's end field (LoopOptions::stop_at_end_field).
  bool ended() const noexcept { return ended_; }
  // Back to nominal, only while disarmed.
  bool ResetSupervisor() noexcept;

  Recorder* recorder = nullptr;  // logs every consumed input when set (set-up time)

 private:
  friend std::unique_ptr<LoopData> MakeLoopData(const robot::RobotModel&, CommandSource*, const LoopOptions&);
  friend struct TickImpl;
  friend struct StateImpl;
  template <typename T>
  static std::span<const T> Changes(const std::array<T, kMaxChanges>& a, std::uint64_t n) noexcept {
    return {a.data(), n < kMaxChanges ? n : kMaxChanges};
  }

  CommandSource* source_ = nullptr;
  LoopOptions options_;
  Phase phase_ = Phase::kDisarmed;
  std::array<std::uint64_t, kPhaseCount> phase_start_{};
  bool source_done_ = false;
  bool ended_ = false;
  std::vector<std::uint8_t> answered_;  // per motor: answered since the phase began
  std::vector<double> q0_;              // per motor: the pose the stand-up starts from
  std::vector<double> desired_;         // the source's (or the phase's) command
  robot::SignalProgram limit_signals_;  // the supervised signals
  std::vector<double> limit_values_;
  safety::SupervisorState sup_;
  rt::TickProfiler profiler_;
  std::array<ModeChange, kMaxChanges> modes_{};
  std::uint64_t mode_count_ = 0;
  std::array<PhaseChange, kMaxChanges> phases_{};
  std::uint64_t phase_count_ = 0;
  mutable LatestMailbox<LoopStatus> status_;
  std::atomic<bool> arm_{false}, disarm_{false}, stop_{false}, estop_{false}, rearm_{false};
  std::uint32_t healthy_ticks_ = 0;
  std::uint32_t stopped_by_ = 0;  // bit (1 << Cause) of each cause that raised the mode to safe-stop or e-stop
  RecoveryStatus recovery_;
  // Operator requests (robot.yaml operator): each request field's level at the last tick (0, 1),
  // for its rises (OperatorRequest's order). Kept in snapshots only for robots with one.
  bool operator_ = false;
  std::array<std::uint8_t, kOperatorRequestCount> operator_held_{};
  OperatorStatus operator_status_;
};

// The summary's lines of the first kMaxChanges phase changes ("phase: tick 200: arming ->
// stand-up"; with_phases false: none) and mode changes ("mode change: tick 730: e-stop: ..."),
// and a line for each when there were more.
std::vector<std::string> DescribeChanges(const LoopData& loop, bool with_phases);

// The loop's data for a model and a command source (null: hold the default pose); the only
// allocation. The source must outlive it.
std::unique_ptr<LoopData> MakeLoopData(const robot::RobotModel& model, CommandSource* source,
                                       const LoopOptions& options = {});

// Everything a tick carries to the next, at a tick boundary (after the tick's Read): the robot's
// data (fields, the streams' ages and checks, the last command), the loop's (phase, stand-up pose,
// the supervisor's state and counters, recovery, the mode and phase changes) and the command
// source's. A log's snapshot (runtime/loop/log.hpp) holds it, so that a log rotated mid-run
// replays on its own. SaveState allocates nothing (a StateWriter without a buffer only counts);
// LoadState puts it back into data and loop made for the same model and source, refusing what
// does not fit, naming the field. Not included: the profiler's timings (a replay does not compare
// them) and the inference status's text in the supervisor's decisions (a static string).
void SaveState(const robot::RobotModel& model, const robot::RobotData& data, const LoopData& loop,
               StateWriter& out) noexcept;
Status LoadState(const robot::RobotModel& model, robot::RobotData& data, LoopData& loop,
                 std::span<const std::uint8_t> bytes);

enum class TickStatus : std::uint8_t {
  kRunning,  // keep ticking
  kDone,     // shut down: the robot is safe (motors off, the stop command sent)
  kFailed,   // arming failed (a motor never answered): motors switched off
};

// The check stage: every stream's age (0 when fresh this tick), and its current fields against
// the model's bounds (the one sample check; the first invalid field is the supervisor's input).
// `stopping` (damping, motor-off, done: the commands are the stop's own, whatever comes in): only
// the motors' streams are judged (their replies carry the stop through); every other stream's age
// is held where it was, so an operator's schedule that ended the run, or a command stream gone
// while the robot shuts down, is not a stale sample of something nothing reads.
void CheckSample(const robot::RobotModel& model, robot::RobotData& data, bool stopping = false) noexcept;

// One tick: read -> check -> observe -> infer -> supervise -> write. `timing` is the clock's
// (tick index, wake time, consecutive deadline misses).
TickStatus Tick(const robot::RobotModel& model, robot::RobotData& data, LoopData& loop,
                std::span<robot::Transport* const> transports, const rt::TickTiming& timing) noexcept;

// The last write of a robot whose clock stopped, as tick `tick`: every command at its e-stop
// value, motors switched off, the mode e-stop (the AUV's stop command). Phase done.
void Shutdown(const robot::RobotModel& model, robot::RobotData& data, LoopData& loop,
              std::span<robot::Transport* const> transports, std::uint64_t tick) noexcept;

}  // namespace pbppo::loop
