// Where each member of the AUV's sensor sample (runtime/robot/auv_messages.hpp) goes among the robot
// model's fields (by name: x_m, sonar_3_m, ...): the one map from what the vehicle reports to what
// the controller observes. The AUV's transport (auv_transport.hpp) writes each received sample
// with it; the navigation task (sim_hil/scenarios/auv_nav_task), and so the trainer's auv-nav,
// writes its own sample with it, so that both observe the same fields. Needs only runtime/robot.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "runtime/core/result.hpp"
#include "runtime/robot/auv_messages.hpp"
#include "runtime/robot/robot_model.hpp"

namespace pbppo::auv {

// Made once at set-up; Write is noexcept and allocates nothing.
class SampleFields {
 public:
  // Errors name the member the robot has no field for.
  static Result<SampleFields> Create(const robot::RobotModel& model);
  void Write(const robot::AuvSensorSample& sample, std::span<double> fields) const noexcept;
  std::uint32_t stream() const noexcept { return stream_; }
  std::uint32_t tick_field() const noexcept { return f_.tick; }

 private:
  struct Map {
    std::uint32_t tick, x, y, depth, roll, pitch, yaw, surge, sway, heave, roll_rate, pitch_rate, yaw_rate, target_x,
        target_y, target_distance, target_bearing, route_bearing, clearance, target_index, mission_complete,
        episode_end, sonar_beams;
  } f_{};
  std::array<std::uint32_t, robot::kAuvMaxSonarBeams> sonar_{};
  std::uint32_t beams_ = 0, stream_ = 0;
};

}  // namespace pbppo::auv
