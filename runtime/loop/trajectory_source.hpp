// A scripted trajectory as the loop's command source (the stand test): joint sinusoids around the
// default pose, q = default + A sin(2 pi f t + phi) - A sin(phi), for duration_s, from a file like
// models/quadruped/stand_trajectory.yaml (the robot's files.stand_trajectory). A
// velocity-commanded joint (a wheel) takes a speed instead, never a position:
// dq = speed_rad_s + A (sin(2 pi f t + phi) - sin(phi)), A = amplitude_rad_s. It tracks the
// measured positions (and speeds) against it. Works for any robot with motors.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/loop/loop.hpp"

namespace pbppo::loop {

struct JointSinusoid {
  std::uint32_t motor = 0;  // index into RobotModel::motors
  double amplitude_rad = 0, frequency_hz = 0, phase_rad = 0;
  bool velocity = false;  // a velocity-commanded joint: speed_rad_s and amplitude_rad_s instead
  double speed_rad_s = 0, amplitude_rad_s = 0;
};

struct Trajectory {
  double duration_s = 0;
  std::vector<JointSinusoid> joints;
};

// Every sweep must stay inside its joint's limits (a speed inside its velocity limit); a position
// given to a velocity-commanded joint or a speed to a position-commanded one is refused; errors
// name the file, the joint and the field.
Result<Trajectory> ParseTrajectory(const std::string& yaml_text, const std::string& origin,
                                   const robot::RobotModel& robot);
// The robot's own (files.stand_trajectory), read with the robot.
Result<Trajectory> RobotTrajectory(const robot::RobotModel& robot);

class TrajectorySource final : public CommandSource {
 public:
  TrajectorySource(const robot::RobotModel& robot, Trajectory trajectory);

  void Start(const robot::RobotModel& model, const robot::RobotData& data, LoopData& loop) noexcept override;
  bool Compute(const robot::RobotModel& model, const robot::RobotData& data, LoopData& loop,
               std::span<double> desired) noexcept override;
  // When it started and its tracking so far.
  void SaveState(StateWriter& out) const noexcept override;
  bool LoadState(StateReader& in) override;

  const Trajectory& trajectory() const noexcept { return trajectory_; }
  // Tracking while it ran: the largest |q - q_des| per motor (velocity-commanded: |dq - dq_des|,
  // rad/s), the RMS over the position-commanded motors (rad) and over the others (rad/s), the ticks.
  double max_tracking_error_rad(std::size_t motor) const noexcept { return track_max_[motor]; }
  double rms_tracking_error_rad() const noexcept;
  double rms_speed_error_rad_s() const noexcept;
  std::uint64_t ticks() const noexcept { return track_n_; }

 private:
  Trajectory trajectory_;
  std::vector<double> q_des_, dq_des_, track_max_;
  double track_sq_ = 0, speed_sq_ = 0;
  std::size_t speed_motors_ = 0;
  std::uint64_t track_n_ = 0, start_tick_ = 0;
};

}  // namespace pbppo::loop
