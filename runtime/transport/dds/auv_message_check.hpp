// Checks of the AUV's messages as they arrive from DDS: pure functions returning flag bits (0:
// fine). A sensor sample that cannot be represented (more sonar beams than
// robot::kAuvMaxSonarBeams) is rejected outright; every other judgement of a sample is the
// controller's one sample check against the robot model's bounds (runtime/loop CheckSample). The
// vehicle checks the commands it receives for plausibility and counts the flagged ones (its
// plant takes no implausible set-point). No DDS or OS header.
#pragma once

#include <cstdint>
#include <string>

#include "runtime/robot/auv_messages.hpp"

namespace pbppo::dds {

enum AuvSampleFlag : std::uint32_t {
  kSampleTooManyBeams = 1u << 5,  // sonar_beams > kAuvMaxSonarBeams (rejected, not delivered)
};

enum AuvCommandFlag : std::uint32_t {
  kCommandNonFinite = 1u << 0,           // NaN or infinite setpoint
  kCommandModeOutOfRange = 1u << 1,      // mode above 3 (e-stop)
  kCommandSetpointOutOfRange = 1u << 2,  // |v| or |omega| above the plausible bounds below
};

inline constexpr double kAuvMaxPlausibleSpeedMps = 20.0;
inline constexpr double kAuvMaxPlausibleRateRadps = 20.0;

std::uint32_t CheckAuvSensorSample(const robot::AuvSensorSample& s) noexcept;
std::uint32_t CheckAuvCommand(const robot::AuvCommand& c) noexcept;

// "non-finite setpoint, mode out of range" for logs and error messages (set-up and tools only).
std::string DescribeAuvCommandFlags(std::uint32_t flags);

}  // namespace pbppo::dds
