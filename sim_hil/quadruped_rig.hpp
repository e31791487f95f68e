// The quadruped's controller and its HIL ticked in one thread, in lock-step: each tick the
// controller (runtime/loop over the CAN transport, its operator stream from a schedule) reads
// what the HIL sent last tick, then the HIL reads what the controller just sent and the plant
// advances 1 ms. The buses are the in-process network (sim-to-sim on every build, no kernel
// needed) or SocketCAN interfaces (vcan in the VM). The same frames, codecs, quantisation and
// watchdogs run either way.
//
// Every tick is traced (base pose and velocity, the command in force, the loop's phase and mode)
// so that tracking per schedule phase, falls and the commands on the bus can be judged.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/loop/schedule.hpp"
#include "runtime/loop/source_files.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/rt/tick_clock.hpp"
#include "runtime/transport/can/can_transport.hpp"
#include "runtime/transport/can/memory_bus.hpp"
#include "sim_hil/quadruped_hil.hpp"

namespace pbppo::sim {

struct RigOptions {
  std::string policy;                             // blob ("" : hold the default pose)
  std::vector<std::string> switch_policies;       // more blobs the operator switches to (loop::PolicySet)
  bool self_test = true;                          // the blob's golden vectors at arming
  policy::Kernel kernel = policy::Kernel::kAuto;  // the policy's forward kernel (one this CPU has)
  std::vector<std::string> interfaces;            // SocketCAN interfaces; empty: the in-process network
  std::int64_t wait_ns = 2'000'000'000;           // SocketCAN lock-step: the longest wait for a tick's frames
  std::size_t command_record_capacity = 0;        // commands kept by the CAN transport (tests)
  // The operator instead of the schedule (the robot's DDS transport of velocity commands, opened
  // through the transport table); the schedule then only names the phases of the report. Must
  // outlive the rig.
  robot::Transport* operator_transport = nullptr;
  // RunSchedule ticks at the robot's tick period on the controller's own clock (rt::FreeRunningClock,
  // as pbppo-controller free-running): the loop's profile then holds wake-up jitter and deadline
  // misses. Else as fast as the plant allows (lock-step).
  bool realtime = false;
  // realtime: whether the supervisor acts on late ticks (they are counted in the profile either
  // way). The plant steps in the controller's thread, so on a loaded or sanitised build the
  // simulator, not the controller, makes ticks late; a run that only needs the wall clock (an
  // operator over DDS) turns this off.
  bool supervise_deadlines = true;
  // RunSchedule arms the loop on its first tick; false: the operator's arm request does
  // (robot.yaml operator.arm, through operator_transport).
  bool arm = true;
  // Every how many ticks the trace keeps a sample (0: no trace; a run of days keeps it bounded).
  std::uint32_t trace_every = 1;
};

// One tick of the trace.
struct RigSample {
  double t_s = 0;                                    // double: a float would lose the tick after a day
  float x_m = 0, y_m = 0, z_m = 0, yaw_rad = 0;      // base, world
  float vx_mps = 0, vy_mps = 0, yaw_rate_radps = 0;  // base frame
  float cmd_vx = 0, cmd_vy = 0, cmd_yaw_rate = 0;    // the command the controller holds
  float tilt_rad = 0;                                // from upright
  std::int32_t schedule_phase = -1;                  // -1: after the schedule
  std::uint8_t loop_phase = 0, mode = 0;
  std::uint8_t feet = 0;  // contact bits
  bool body_contact = false;
};

struct PhaseTracking {
  std::string name;
  double start_s = 0, end_s = 0;
  double command[3] = {0, 0, 0};         // vx, vy, yaw rate
  double mean_abs_error[3] = {0, 0, 0};  // after the settling time
  double mean_measured[3] = {0, 0, 0};
  std::uint64_t samples = 0;
};

struct RigReport {
  std::vector<PhaseTracking> phases;
  bool fell = false;  // a tilt beyond 60 degrees, or a body contact before any safe-stop
  double fell_at_s = -1;
  double distance_m = 0;
  double max_planar_error = 0;  // the largest per-phase mean |error| of vx, vy
};

class QuadrupedRig {
 public:
  static Result<std::unique_ptr<QuadrupedRig>> Make(const robot::RobotModel& model, QuadrupedHilOptions hil,
                                                    loop::Schedule schedule, const RigOptions& options);
  ~QuadrupedRig();

  // One controller tick, then one HIL tick (realtime: first waits for the tick's deadline). False
  // once the plant failed. The same in two halves (a harness that measures the controller's tick
  // alone): TickController(), then TickPlant().
  bool Tick() noexcept;
  // Realtime: the clock's first deadline is now (RunSchedule does it; a harness of its own calls it).
  void StartClock() noexcept;
  void TickController() noexcept;
  bool TickPlant() noexcept;
  // The last controller tick's own time (loop::Tick, not the wait for its deadline), ns.
  std::int64_t last_tick_ns() const noexcept { return last_tick_ns_; }
  // Arms (RigOptions::arm), then ticks until the schedule has ended (plus `extra_s`) or the loop stopped.
  bool RunSchedule(double extra_s = 0);
  // Per schedule phase (`by_command`: per command held at least 0.2 s, as an operator over DDS
  // gives them on its own clock): mean |velocity error| after `settle_s` of each phase.
  RigReport Report(double settle_s, bool by_command = false) const;

  const robot::RobotModel& model() const noexcept { return model_; }
  QuadrupedHil& hil() noexcept { return *hil_; }
  can::CanTransport& can() noexcept { return *can_; }
  loop::ScheduleTransport& operator_source() noexcept { return *schedule_; }
  const policy::PolicyModel* policy() const noexcept { return source_.policy.get(); }  // null: no blob
  const loop::LoadedSource& source() const noexcept { return source_; }
  loop::LoopData& loop() noexcept { return *loop_; }
  const loop::LoopData& loop() const noexcept { return *loop_; }
  const robot::RobotData& data() const noexcept { return data_; }
  can::MemoryCanNetwork* network() noexcept { return network_.get(); }
  const std::vector<RigSample>& trace() const noexcept { return trace_; }
  std::uint64_t ticks() const noexcept { return tick_; }
  loop::TickStatus status() const noexcept { return status_; }

 private:
  explicit QuadrupedRig(const robot::RobotModel& model) : model_(model) {}
  const robot::RobotModel& model_;
  std::unique_ptr<can::MemoryCanNetwork> network_;
  std::unique_ptr<QuadrupedHil> hil_;
  std::unique_ptr<can::CanTransport> can_;
  std::unique_ptr<loop::ScheduleTransport> schedule_;
  loop::LoadedSource source_;
  robot::RobotData data_;
  std::unique_ptr<loop::LoopData> loop_;
  robot::Transport* transports_[2] = {};
  std::vector<RigSample> trace_;
  std::uint32_t trace_every_ = 1;
  std::int64_t last_tick_ns_ = 0;
  std::int32_t cmd_field_[3] = {-1, -1, -1};
  std::int64_t wait_ns_ = 0;
  std::unique_ptr<rt::FreeRunningClock> clock_;  // realtime
  bool supervise_deadlines_ = true;
  bool arm_ = true;
  bool memory_ = true;
  std::uint64_t tick_ = 0;
  loop::TickStatus status_ = loop::TickStatus::kRunning;
};

// Prints the report: per phase the commands and mean |error|, the distance walked, a fall.
void PrintRigReport(const RigReport& report);

// The base's part of a trace sample (pose, base-frame velocity, tilt, contacts) from the plant.
void FillBaseSample(const QuadrupedPlant& plant, RigSample* sample) noexcept;

// The report of a trace: per phase of `schedule` (`by_command`: per command held at least 0.2 s)
// the mean |velocity error| after `settle_s`, falls and distance (QuadrupedRig::Report).
RigReport ReportOfTrace(const std::vector<RigSample>& trace, const loop::Schedule& schedule, double settle_s,
                        bool by_command);

// Writes the trace as CSV (one row per `every` ticks); errors name the path.
Status WriteRigTrace(const std::vector<RigSample>& trace, const std::string& path, std::uint32_t every = 10);

// Plots a trace: `png` the commanded (dashed) and measured vx, vy and yaw rate against time (one
// point per `every` samples; `phases`: a panel of the loop's phase and mode too, for a robot whose
// operator moves them), and <stem>_path.png the base's path from above. `what` names the run in
// the titles ("quadruped HIL").
Status PlotRigTrace(const std::vector<RigSample>& trace, const std::string& what, bool phases, const std::string& png,
                    std::uint32_t every = 10);

// "out.png" -> "out": the stem the other plots' names extend.
std::string PngStem(const std::string& png);

}  // namespace pbppo::sim
