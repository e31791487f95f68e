// The quadruped's stand-test controller over CAN: arming, ramp to the default pose, hold, joint
// sinusoids from a file, and shutdown to damping then motor-off. The safety supervisor
// (runtime/safety) sees every tick's commands, replies, reply ages and bus health and has the
// last word: degraded keeps going with limited commands, safe-stop damps every joint (kp 0,
// kd damping), e-stop switches every driver out of motor mode.
//
//   arming      enter motor mode on every joint, every tick, until each motor has answered;
//               the answers give the measured pose (time out: e-stop)
//   ramp        smoothstep from the measured pose to the default pose over ramp_s
//   hold        the default pose (hold_s, then the trajectory if one was given)
//   trajectory  default + A sin(2 pi f t + phi) - A sin(phi) per listed joint, for duration_s
//   shutdown    damping for damping_s, then exit motor mode until every motor has answered
//
// Everything is allocated in Make(); Tick() allocates nothing, takes no lock and never throws.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/can_map.hpp"
#include "runtime/robot/urdf.hpp"
#include "runtime/safety/supervisor.hpp"
#include "runtime/transport/can/can_table.hpp"
#include "runtime/transport/can/candump_log.hpp"
#include "runtime/transport/can/socketcan.hpp"

namespace pbppo::firmware {

// models/quadruped/stand_trajectory.yaml: sinusoids around the default pose.
struct JointSinusoid {
  std::uint32_t joint = 0;  // actuated joint index
  double amplitude_rad = 0, frequency_hz = 0, phase_rad = 0;
};
struct Trajectory {
  double duration_s = 0;
  std::vector<JointSinusoid> joints;
};
Result<Trajectory> LoadTrajectory(const std::string& path, const robot::RobotDescription& robot);
Result<Trajectory> ParseTrajectory(const std::string& yaml_text, const std::string& origin,
                                   const robot::RobotDescription& robot);

enum class Phase : std::uint8_t { kArming, kRamp, kHold, kTrajectory, kShutdownDamping, kMotorOff, kDone, kFailed };
const char* ToString(Phase phase) noexcept;

struct StandControllerOptions {
  std::vector<std::string> interfaces;  // per bus of the CAN map
  bool receive_all = false;             // no kernel filter: count strays (unknown identifiers)
  double tick_s = 1e-3;
  double ramp_s = 1.0;
  double hold_s = 0.2;
  double damping_s = 0.5;
  std::uint32_t arming_timeout_ticks = 1000;
  std::uint32_t motor_off_timeout_ticks = 100;
  bool has_trajectory = false;
  Trajectory trajectory;
  bool shutdown_after_trajectory = false;   // else hold after it until asked to stop
  std::string candump_path;                 // every frame sent and received ("" : none)
  std::size_t command_record_capacity = 0;  // commands kept for RecordedCommands() (0: none)
};

// A command as the controller meant it (after the supervisor's limits), before quantisation.
struct CommandRecord {
  std::uint64_t tick = 0;
  std::uint32_t motor = 0;
  double q_rad = 0, dq_rad_s = 0, kp = 0, kd = 0, tau_nm = 0;
};

class StandController {
 public:
  static Result<std::unique_ptr<StandController>> Make(const robot::RobotDescription& robot, const robot::CanMap& map,
                                                       const StandControllerOptions& options);
  ~StandController();

  // One control tick: receive (waiting for expect_per_bus frames for at most wait_ns: lock-step;
  // null: just drain), supervise, send.
  void Tick(const std::uint32_t* expect_per_bus, std::int64_t wait_ns) noexcept;
  // Async-signal-safe: start the shutdown sequence at the next tick.
  void RequestShutdown() noexcept { shutdown_requested_.store(true, std::memory_order_relaxed); }
  void Stop();  // flushes the candump log

  Phase phase() const noexcept { return phase_; }
  std::uint64_t tick() const noexcept { return tick_; }
  std::size_t joint_count() const noexcept { return q_.size(); }
  double q_rad(std::size_t j) const noexcept { return q_[j]; }
  double q_des_rad(std::size_t j) const noexcept { return q_des_[j]; }
  std::uint32_t sent_last_tick(std::size_t bus) const noexcept { return sent_last_[bus]; }
  std::uint64_t commands_sent(std::size_t motor) const noexcept { return frames_sent_[motor]; }
  std::uint64_t replies(std::size_t motor) const noexcept { return rx_.reply_count[motor]; }
  std::uint64_t imu_samples() const noexcept { return rx_.imu_count.empty() ? 0 : rx_.imu_count[0]; }
  const can::ImuSample& imu() const noexcept { return rx_.imu[0]; }
  const can::BusStats& bus_stats(std::size_t bus) const noexcept { return buses_[bus]->stats(); }
  std::size_t bus_count() const noexcept { return buses_.size(); }
  const safety::SupervisorModel& supervisor_model() const noexcept { return sup_model_; }
  const safety::SupervisorData& supervisor() const noexcept { return sup_; }
  std::uint64_t clamped_fields() const noexcept { return clamped_fields_; }
  // Tracking during the trajectory phase: largest |q - q_des| per joint, and the RMS over all.
  double max_tracking_error_rad(std::size_t j) const noexcept { return track_max_[j]; }
  double rms_tracking_error_rad() const noexcept;
  std::uint64_t trajectory_ticks() const noexcept { return track_n_; }
  std::uint64_t phase_start_tick(Phase p) const noexcept { return phase_start_[static_cast<std::size_t>(p)]; }
  const std::vector<CommandRecord>& RecordedCommands() const noexcept { return records_; }
  std::uint64_t records_dropped() const noexcept { return records_dropped_; }
  std::uint64_t candump_dropped() const noexcept;

 private:
  StandController() = default;
  void Enter(Phase p) noexcept;
  void ComputeCommands() noexcept;
  void SendCommands() noexcept;

  const robot::RobotDescription* robot_ = nullptr;
  StandControllerOptions options_;
  can::CanCodecTable table_;
  can::CanRxData rx_;
  std::vector<std::unique_ptr<can::SocketCanBus>> buses_;
  std::unique_ptr<can::CandumpLogger> log_;
  std::vector<std::vector<can::CanFrame>> rx_buf_, tx_buf_;
  std::vector<std::uint32_t> sent_last_;
  std::vector<std::size_t> joint_of_motor_, motor_of_joint_;
  std::vector<std::uint64_t> seen_replies_, frames_sent_;
  std::vector<std::uint32_t> age_;
  std::vector<bool> answered_;
  std::vector<double> q_, dq_, q0_, q_des_, dq_des_;
  std::vector<double> command_, feedback_;  // supervisor layout: per motor (q, dq, kp, kd, tau) / (q, dq)
  std::vector<safety::TransportHealth> health_;
  std::vector<can::BusStats> last_stats_;
  safety::SupervisorModel sup_model_;
  safety::SupervisorData sup_;
  std::vector<double> track_max_;
  double track_sq_ = 0;
  std::uint64_t track_n_ = 0;
  std::uint64_t clamped_fields_ = 0;
  std::vector<CommandRecord> records_;
  std::uint64_t records_dropped_ = 0;
  Phase phase_ = Phase::kArming;
  std::uint64_t phase_start_[8] = {};
  std::uint64_t tick_ = 0;
  std::atomic<bool> shutdown_requested_{false};
};

}  // namespace pbppo::firmware
