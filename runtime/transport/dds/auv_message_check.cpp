#include "runtime/transport/dds/auv_message_check.hpp"

#include <cmath>
#include <initializer_list>
#include <utility>

namespace pbppo::dds {
namespace {

bool AllFinite(std::initializer_list<double> v) noexcept {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
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
  return s.sonar_beams > robot::kAuvMaxSonarBeams ? kSampleTooManyBeams : 0u;
}

std::uint32_t CheckAuvCommand(const robot::AuvCommand& c) noexcept {
  std::uint32_t f = 0;
  if (!AllFinite({c.surge_speed_mps, c.yaw_rate_radps})) f |= kCommandNonFinite;
  if (c.mode > 3) f |= kCommandModeOutOfRange;
  if (std::abs(c.surge_speed_mps) > kAuvMaxPlausibleSpeedMps || std::abs(c.yaw_rate_radps) > kAuvMaxPlausibleRateRadps)
    f |= kCommandSetpointOutOfRange;
  return f;
}

std::string DescribeAuvCommandFlags(std::uint32_t flags) {
  return Describe(flags, {{kCommandNonFinite, "non-finite setpoint"},
                          {kCommandModeOutOfRange, "mode above 3"},
                          {kCommandSetpointOutOfRange, "implausible setpoint"}});
}

}  // namespace pbppo::dds
