// A quadruped HIL scenario as data (models/quadruped/scenarios/*.yaml): the mount, the terrain,
// the contact, the start pose, pushes and device faults, each at a time. Read once at start-up
// with the one YAML field reader; errors name the file, the field and the value.
//
//   mount: ground                 # or stand
//   terrain: {kind: blocks, seed: 3, blocks: 300, half_size_m: 10, size_m: [0.3, 1.0],
//             height_m: [0.05, 0.15], clear_radius_m: 0.8}     # or {kind: flat}
//   contact: {friction: 1.0, stiffness: 1.2e6, dissipation: 1.0, transition_mps: 0.1}
//   start: {x_m: 0, y_m: 0, height_m: 0.47, yaw_rad: 0}
//   events:
//     - {at_s: 6.0, push: [0.5, 0.0, 0.0]}
//     - {at_s: 3.0, silent_motor: LF_KFE}
//     - {at_s: 3.2, motor_back: LF_KFE}     # it answers again
//     - {at_s: 3.0, bad_replies: LF_KFE}    # replies at the top of its MIT range (out of bounds)
//     - {at_s: 3.2, good_replies: LF_KFE}
//     - {at_s: 3.0, imu_silent: true}       # false: the IMU comes back
//     - {at_s: 3.0, drop_frames: 0.1, max_burst: 3}
//     - {at_s: 3.0, bus_off: front}
//     - {at_s: 3.5, bus_restored: front}   # the bus recovers (a "restarted" error frame)
#pragma once

#include <string>

#include "runtime/core/result.hpp"
#include "runtime/robot/robot_model.hpp"
#include "sim_hil/quadruped_hil.hpp"

namespace pbppo::sim {

struct QuadrupedScenario {
  std::string path;
  QuadrupedHilOptions hil;  // plant, start pose and faults filled; buses left to the caller
};

// Parses a scenario for `model` (joint and bus names are the model's); `tick_s` converts times.
Result<QuadrupedScenario> ParseQuadrupedScenario(const std::string& yaml_text, const std::string& origin,
                                                 const robot::RobotModel& model, double tick_s);
Result<QuadrupedScenario> LoadQuadrupedScenario(const std::string& path, const robot::RobotModel& model, double tick_s);

}  // namespace pbppo::sim
