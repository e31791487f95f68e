// The AUV's signal table: every signal an AUV IO layout may name, in a fixed order, and how each
// is computed. The navigation task (training) and the AUV controller (deployment) both fill the
// table through AuvSignals, then build the observation with one ObservationBuilder, so a policy
// sees the same numbers in both places. No allocation after set-up.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/robot/auv_messages.hpp"

namespace pbppo::robot {

// Signal indices; sonar_0 ... sonar_{n-1} follow at kAuvSonarSignal0 + i.
enum AuvSignal : std::uint32_t {
  kAuvTargetDistance,  // l_AT, m
  kAuvYaw,             // theta, rad in (-pi, pi]
  kAuvTargetBearing,   // phi_AT relative to the heading, rad in (-pi, pi]
  kAuvEpisodeEnd,      // chi: 1 in the last observation of an episode
  kAuvSurgeSpeed,      // body u, m/s
  kAuvSwaySpeed,       // body v, m/s
  kAuvYawRate,         // body r, rad/s
  kAuvCosYaw,
  kAuvSinYaw,
  kAuvCosTargetBearing,
  kAuvSinTargetBearing,
  kAuvX,            // m
  kAuvY,            // m
  kAuvDepthError,   // depth - set-point, m (positive: too deep)
  kAuvClearance,    // nearest obstacle or wall, m: the simulator's exact value (no vehicle sensor gives it)
  kAuvTargetIndex,  // 0, 1, 2 ...
  kAuvTargetX,      // current target in the world frame, m
  kAuvTargetY,
  kAuvNearestEcho,  // shortest sonar range over all beams, m (+inf without beams)
  // The mission computer's route: the bearing of its planned path (over the chart, and the sonar
  // map with task.route_map: chart_and_sonar) relative to the heading, rad in (-pi, pi] (the
  // target bearing where it has no route).
  kAuvRouteBearing,
  kAuvCosRouteBearing,
  kAuvSinRouteBearing,
  kAuvSonarSignal0
};

// Size of a signal array for any sonar the messages can carry.
inline constexpr std::uint32_t kAuvSignalCapacity = kAuvSonarSignal0 + kAuvMaxSonarBeams;

// The names, in index order, for a sonar of `sonar_beams` beams (set-up time; allocates).
std::vector<std::string> AuvSignalNames(std::uint32_t sonar_beams);

// What the signals are computed from. yaw_rad may be on any branch: the yaw signal is wrapped to
// (-pi, pi], cos_yaw and sin_yaw take it as given.
struct AuvSignalInputs {
  double x_m = 0, y_m = 0, depth_m = 0, yaw_rad = 0;
  double surge_mps = 0, sway_mps = 0, yaw_rate_radps = 0;
  double target_distance_m = 0, target_bearing_rad = 0, clearance_m = 0, route_bearing_rad = 0;
  std::int32_t target_index = 0;
  double target_x_m = 0, target_y_m = 0;
  bool episode_end = false;
};

// Fills signals[0, kAuvSonarSignal0 + sonar_beams) (sonar_beams is capped at kAuvMaxSonarBeams).
void AuvSignals(const AuvSignalInputs& in, double depth_setpoint_m, const double* sonar_m, std::uint32_t sonar_beams,
                double* signals) noexcept;

// The same from a sensor sample (the controller's path).
void AuvSignalsFromSample(const AuvSensorSample& sample, double depth_setpoint_m, double* signals) noexcept;

// An angle wrapped to (-pi, pi]; exact (and the identity) for angles already in that range.
double WrapAngleRad(double a) noexcept;

}  // namespace pbppo::robot
