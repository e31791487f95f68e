#include "runtime/robot/auv_signals.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace pbppo::robot {
namespace {

constexpr double kPi = 3.14159265358979323846;

constexpr const char* kNames[kAuvSonarSignal0] = {"target_distance",
                                                  "yaw",
                                                  "target_bearing",
                                                  "episode_end",
                                                  "surge_speed",
                                                  "sway_speed",
                                                  "yaw_rate",
                                                  "cos_yaw",
                                                  "sin_yaw",
                                                  "cos_target_bearing",
                                                  "sin_target_bearing",
                                                  "x",
                                                  "y",
                                                  "depth_error",
                                                  "clearance",
                                                  "target_index",
                                                  "target_x",
                                                  "target_y",
                                                  "nearest_echo",
                                                  "route_bearing",
                                                  "cos_route_bearing",
                                                  "sin_route_bearing"};

}  // namespace

std::vector<std::string> AuvSignalNames(std::uint32_t sonar_beams) {
  std::vector<std::string> names(kNames, kNames + kAuvSonarSignal0);
  for (std::uint32_t i = 0; i < sonar_beams; ++i) names.push_back("sonar_" + std::to_string(i));
  return names;
}

double WrapAngleRad(double a) noexcept {
  a = std::remainder(a, 2.0 * kPi);  // [-pi, pi]
  return a <= -kPi ? a + 2.0 * kPi : a;
}

void AuvSignals(const AuvSignalInputs& in, double depth_setpoint_m, const double* sonar_m, std::uint32_t sonar_beams,
                double* signals) noexcept {
  double* g = signals;
  g[kAuvTargetDistance] = in.target_distance_m;
  g[kAuvYaw] = WrapAngleRad(in.yaw_rad);
  g[kAuvTargetBearing] = in.target_bearing_rad;
  g[kAuvEpisodeEnd] = in.episode_end ? 1.0 : 0.0;
  g[kAuvSurgeSpeed] = in.surge_mps;
  g[kAuvSwaySpeed] = in.sway_mps;
  g[kAuvYawRate] = in.yaw_rate_radps;
  g[kAuvCosYaw] = std::cos(in.yaw_rad);
  g[kAuvSinYaw] = std::sin(in.yaw_rad);
  g[kAuvCosTargetBearing] = std::cos(in.target_bearing_rad);
  g[kAuvSinTargetBearing] = std::sin(in.target_bearing_rad);
  g[kAuvX] = in.x_m;
  g[kAuvY] = in.y_m;
  g[kAuvDepthError] = in.depth_m - depth_setpoint_m;
  g[kAuvClearance] = in.clearance_m;
  g[kAuvTargetIndex] = in.target_index;
  g[kAuvTargetX] = in.target_x_m;
  g[kAuvTargetY] = in.target_y_m;
  g[kAuvRouteBearing] = in.route_bearing_rad;
  g[kAuvCosRouteBearing] = std::cos(in.route_bearing_rad);
  g[kAuvSinRouteBearing] = std::sin(in.route_bearing_rad);
  const std::uint32_t n = std::min(sonar_beams, kAuvMaxSonarBeams);
  double nearest = std::numeric_limits<double>::infinity();
  for (std::uint32_t i = 0; i < n; ++i) {
    g[kAuvSonarSignal0 + i] = sonar_m[i];
    nearest = std::min(nearest, sonar_m[i]);
  }
  g[kAuvNearestEcho] = nearest;
}

void AuvSignalsFromSample(const AuvSensorSample& s, double depth_setpoint_m, double* signals) noexcept {
  AuvSignalInputs in;
  in.x_m = s.x_m;
  in.y_m = s.y_m;
  in.depth_m = s.depth_m;
  in.yaw_rad = s.yaw_rad;
  in.surge_mps = s.surge_mps;
  in.sway_mps = s.sway_mps;
  in.yaw_rate_radps = s.yaw_rate_radps;
  in.target_distance_m = s.target_distance_m;
  in.target_bearing_rad = s.target_bearing_rad;
  in.route_bearing_rad = s.route_bearing_rad;
  in.clearance_m = s.clearance_m;
  in.target_index = s.target_index;
  in.target_x_m = s.target_x_m;
  in.target_y_m = s.target_y_m;
  in.episode_end = s.episode_end;
  const std::uint32_t n = std::min(s.sonar_beams, kAuvMaxSonarBeams);
  std::array<double, kAuvMaxSonarBeams> sonar{};
  for (std::uint32_t i = 0; i < n; ++i) sonar[i] = static_cast<double>(s.sonar_m[i]);
  AuvSignals(in, depth_setpoint_m, sonar.data(), n, signals);
}

}  // namespace pbppo::robot
