#include "runtime/transport/dds/auv_message_check.hpp"

#include <cmath>
#include <initializer_list>
#include <utility>

namespace pbppo::dds {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kAngleSlack = 1e-9;

bool AllFinite(std::initializer_list<double> v) noexcept {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

bool AngleOk(double a) noexcept {
  return std::abs(a) <= kPi + kAngleSlack;
}

std::string Describe(std::uint32_t flags, std::initializer_list<std::pair<std::uint32_t, const char*>> names) {
  std::string out;
  for (const auto& [bit, name] : names) {
    if ((flags & bit) == 0) continue;
    if (!out.empty()) out += ", ";
    out += name;
  }
  return out.empty() ? "none" : out;
}

}  // namespace

std::uint32_t CheckAuvSensorSample(const robot::AuvSensorSample& s) noexcept {
  std::uint32_t f = 0;
  if (s.sonar_beams > robot::kAuvMaxSonarBeams) f |= kSampleTooManyBeams;
  if (!AllFinite({s.x_m, s.y_m, s.depth_m, s.roll_rad, s.pitch_rad, s.yaw_rad, s.surge_mps, s.sway_mps, s.heave_mps,
                  s.roll_rate_radps, s.pitch_rate_radps, s.yaw_rate_radps, s.target_x_m, s.target_y_m,
                  s.target_distance_m, s.target_bearing_rad, s.route_bearing_rad, s.clearance_m}))
    f |= kSampleNonFinite;
  const std::uint32_t beams = s.sonar_beams < robot::kAuvMaxSonarBeams ? s.sonar_beams : robot::kAuvMaxSonarBeams;
  for (std::uint32_t i = 0; i < beams; ++i) {
    const float r = s.sonar_m[i];
    if (!std::isfinite(r))
      f |= kSampleNonFinite;
    else if (r < 0.0f)
      f |= kSampleSonarOutOfRange;
  }
  // NaN compares false, so only finite values reach the range checks below as failures.
  for (double a : {s.roll_rad, s.pitch_rad, s.yaw_rad, s.target_bearing_rad, s.route_bearing_rad})
    if (std::isfinite(a) && !AngleOk(a)) f |= kSampleAngleOutOfRange;
  for (double v : {s.surge_mps, s.sway_mps, s.heave_mps})
    if (std::abs(v) > kAuvMaxPlausibleSpeedMps) f |= kSampleSpeedOutOfRange;
  for (double w : {s.roll_rate_radps, s.pitch_rate_radps, s.yaw_rate_radps})
    if (std::abs(w) > kAuvMaxPlausibleRateRadps) f |= kSampleSpeedOutOfRange;
  if (s.target_index < 0 || s.target_distance_m < 0.0 || s.stamp_ns < 0) f |= kSampleTargetOutOfRange;
  return f;
}

std::uint32_t CheckAuvCommand(const robot::AuvCommand& c) noexcept {
  std::uint32_t f = 0;
  if (!AllFinite({c.surge_speed_mps, c.yaw_rate_radps})) f |= kCommandNonFinite;
  if (c.mode > 3) f |= kCommandModeOutOfRange;
  if (std::abs(c.surge_speed_mps) > kAuvMaxPlausibleSpeedMps || std::abs(c.yaw_rate_radps) > kAuvMaxPlausibleRateRadps)
    f |= kCommandSetpointOutOfRange;
  return f;
}

std::string DescribeAuvSampleFlags(std::uint32_t flags) {
  return Describe(flags, {{kSampleNonFinite, "non-finite field"},
                          {kSampleSonarOutOfRange, "negative sonar range"},
                          {kSampleAngleOutOfRange, "angle outside [-pi, pi]"},
                          {kSampleSpeedOutOfRange, "implausible velocity"},
                          {kSampleTargetOutOfRange, "negative target index, distance or stamp"},
                          {kSampleTooManyBeams, "more sonar beams than 32"}});
}

std::string DescribeAuvCommandFlags(std::uint32_t flags) {
  return Describe(flags, {{kCommandNonFinite, "non-finite setpoint"},
                          {kCommandModeOutOfRange, "mode above 3"},
                          {kCommandSetpointOutOfRange, "implausible setpoint"}});
}

}  // namespace pbppo::dds
