// The AUV's messages as plain fixed-size C++ structs: what the vehicle (or the HIL simulator)
// publishes each control period, what the controller sends back, and the controller's status.
// The DDS types (models/auv/idl/) carry the same fields; the transport converts between the two
// on its own threads, so the control tick only ever sees these structs (no allocation, no DDS).
#pragma once

#include <array>
#include <cstdint>

namespace pbppo::robot {

inline constexpr std::uint32_t kAuvMaxSonarBeams = 32;

// One sensor sample of the vehicle. In lock-step runs `tick` is the controller tick whose command
// produced this state (0 for the first sample after reset); in real-time runs it is the
// publisher's sequence number.
struct AuvSensorSample {
  std::uint64_t tick = 0;
  std::int64_t stamp_ns = 0;  // vehicle time (simulated time in HIL)
  // Pose in the world frame (z up, yaw counter-clockwise from +x, wrapped to (-pi, pi]).
  double x_m = 0, y_m = 0, depth_m = 0;
  double roll_rad = 0, pitch_rad = 0, yaw_rad = 0;
  // Body-frame velocities.
  double surge_mps = 0, sway_mps = 0, heave_mps = 0;
  double roll_rate_radps = 0, pitch_rate_radps = 0, yaw_rate_radps = 0;
  // Sonar ranges in metres, beam i at i * 360 / beams degrees counter-clockwise from the bow.
  std::uint32_t sonar_beams = 0;
  std::array<float, kAuvMaxSonarBeams> sonar_m{};
  // Mission: the current target (index into the layout's list) and where it is.
  std::int32_t target_index = 0;
  double target_x_m = 0, target_y_m = 0;
  double target_distance_m = 0;   // l_AT
  double target_bearing_rad = 0;  // phi_AT relative to the heading, (-pi, pi]
  // The bearing of the mission computer's planned route (over the chart, and the sonar map with
  // task.route_map: chart_and_sonar) relative to the heading, (-pi, pi]; the target bearing where
  // it has no route.
  double route_bearing_rad = 0;
  double clearance_m = 0;         // distance to the nearest obstacle surface (HIL ground truth)
  bool mission_complete = false;  // every target reached
  bool episode_end = false;       // chi: the vehicle's episode ended (collision, done, time)
};

// The command the controller sends: speed setpoints for the vehicle's low-level loops.
struct AuvCommand {
  std::uint64_t tick = 0;      // the controller tick that computed it
  std::int64_t stamp_ns = 0;   // controller clock
  std::uint64_t answers = 0;   // tick of the sensor sample it was computed from
  double surge_speed_mps = 0;  // v
  double yaw_rate_radps = 0;   // omega
  std::uint8_t mode = 0;       // supervisor mode (0 nominal, 1 degraded, 2 safe-stop, 3 e-stop)
};

// Controller status / telemetry, published at a low rate from a non-real-time thread.
struct AuvControllerStatus {
  std::uint64_t tick = 0;
  std::uint8_t mode = 0;
  std::uint32_t cause = 0;  // supervisor cause bits of the latest mode change
  std::uint64_t deadline_misses = 0;
  std::uint64_t stale_samples = 0;
  std::uint64_t invalid_samples = 0;
  std::uint64_t limited_commands = 0;
  double tick_median_us = 0;
  double tick_max_us = 0;
};

}  // namespace pbppo::robot
