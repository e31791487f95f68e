// The AUV's controller core, independent of the transport: made once at start-up from
// the robot model (supervisor limits, control period, depth set-point, IO layout) and a policy
// blob; then, every control period, Tick() = observe (signal table -> observation
// through the IO layout) -> infer (policy::Forward) -> supervise (safety::SuperviseAuv), each
// stage timed into the profiler. Everything is allocated in Create(); Tick() allocates nothing,
// takes no lock and never throws.
//
// Arming: disarmed ticks send zero speed and keep track of the samples; Arm() starts the policy
// (the first armed tick fills the observation history with the current values). Disarm() sends
// zero again; ResetSupervisor() brings a latched mode back to nominal, only while disarmed.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/latest_mailbox.hpp"
#include "runtime/core/result.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/robot/auv_messages.hpp"
#include "runtime/robot/io_layout.hpp"
#include "runtime/robot/observation_builder.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/rt/tick_profiler.hpp"
#include "runtime/safety/auv_supervisor.hpp"

namespace pbppo::firmware {

struct AuvControllerConfig {
  safety::AuvSupervisorConfig supervisor;
  double control_period_s = 0.1;
  double depth_setpoint_m = 5.0;
};

// The supervisor's limits, the tick period and the depth set-point of the robot model
// (models/auv/robot.yaml); at another tick period, take robot::WithTickPeriod's model.
Result<AuvControllerConfig> AuvControllerConfigOf(const robot::RobotModel& robot);

class AuvController {
 public:
  // tick_period_s > 0: the controller ticks at that period (robot::WithTickPeriod); 0: the robot's.
  static Result<std::unique_ptr<AuvController>> Create(const robot::RobotModel& robot, const std::string& blob_path,
                                                       double tick_period_s = 0);
  // From loaded pieces: refuses a policy trained for another layout (names the first
  // difference) and a layout that is not the AUV's (unknown signal, missing command).
  static Result<std::unique_ptr<AuvController>> Create(const AuvControllerConfig& config, const robot::IoLayout& layout,
                                                       policy::PolicyModel model);

  // One control period. `latest_or_null`: the newest sample the transport holds (null: none
  // yet); a sample is new when its tick or stamp differs from the previous one. `tick`: this
  // controller tick. Writes the command to send.
  void Tick(const robot::AuvSensorSample* latest_or_null, std::uint64_t tick, robot::AuvCommand& out) noexcept;
  // The loop's view of the link and the clock, for the next Tick().
  void SetLinkState(bool peer_lost, std::uint32_t consecutive_deadline_misses) noexcept {
    peer_lost_ = peer_lost;
    deadline_misses_in_row_ = consecutive_deadline_misses;
  }
  // The command that stops the vehicle (zero speed, zero yaw rate, e-stop mode), for shutdown.
  void ShutdownCommand(std::uint64_t tick, robot::AuvCommand& out) const noexcept;

  void Arm() noexcept;
  void Disarm() noexcept { armed_ = false; }
  bool armed() const noexcept { return armed_; }
  // Async-signal-safe: the next tick latches e-stop.
  void RequestEStop() noexcept { estop_request_.store(true, std::memory_order_relaxed); }
  // Back to nominal, only while disarmed (false otherwise).
  bool ResetSupervisor() noexcept;

  const safety::AuvSupervisorState& supervisor() const noexcept { return sup_; }
  const safety::AuvDecision& last_decision() const noexcept { return decision_; }
  const AuvControllerConfig& config() const noexcept { return config_; }
  const robot::IoLayout& layout() const noexcept { return layout_; }
  rt::TickProfiler& profiler() noexcept { return profiler_; }
  std::span<const float> observation() const noexcept { return obs_; }
  std::uint32_t sample_age_ticks() const noexcept { return sample_age_; }
  std::uint64_t ticks() const noexcept { return ticks_; }
  std::uint64_t policy_runs() const noexcept { return policy_runs_; }
  // Counters (published by the tick through a mailbox) and median/max tick time (from the
  // profiler's atomics): callable from one other thread while the tick runs; not for the tick.
  robot::AuvControllerStatus Status() const;

  // Every rise of the supervisor's mode (the first kMaxModeChanges), recorded in the tick with
  // its reason; read them after the loop.
  struct ModeChange {
    std::uint64_t tick = 0;
    safety::AuvMode mode = safety::AuvMode::kNominal;
    char reason[120] = {};
  };
  static constexpr std::size_t kMaxModeChanges = 16;
  std::span<const ModeChange> mode_changes() const noexcept {
    return {changes_.data(), std::min<std::size_t>(change_count_, kMaxModeChanges)};
  }

 private:
  AuvController(AuvControllerConfig config, robot::IoLayout layout, policy::PolicyModel model,
                robot::ObservationBuilder builder);

  AuvControllerConfig config_;
  robot::IoLayout layout_;
  policy::PolicyModel model_;
  robot::ObservationBuilder builder_;
  std::optional<policy::PolicyData> data_;   // made once the model sits at its final address
  std::uint32_t v_index_ = 0, w_index_ = 1;  // action index of surge_speed and yaw_rate
  std::vector<double> signals_;
  std::vector<float> obs_;
  robot::AuvSensorSample sample_{};
  // The tick's counters for Status() on another thread (single reader).
  mutable LatestMailbox<robot::AuvControllerStatus> status_box_;
  std::array<ModeChange, kMaxModeChanges> changes_{};
  std::size_t change_count_ = 0;
  bool have_sample_ = false;
  std::uint32_t sample_age_ = 0;
  safety::AuvSupervisorState sup_;
  safety::AuvDecision decision_;
  rt::TickProfiler profiler_;
  bool armed_ = false, first_armed_tick_ = false;
  bool peer_lost_ = false;
  std::uint32_t deadline_misses_in_row_ = 0;
  std::atomic<bool> estop_request_{false};
  std::uint64_t ticks_ = 0, policy_runs_ = 0;
};

}  // namespace pbppo::firmware
