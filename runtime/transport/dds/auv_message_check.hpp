// Plausibility checks of the AUV's messages as they arrive from DDS: pure functions returning
// flag bits (0: plausible). The transport delivers flagged messages to the controller (or the
// simulator) together with their flags and counts them, so the safety supervisor decides what a
// bad sample means; only a sample that cannot be represented (more sonar beams than
// robot::kAuvMaxSonarBeams) is rejected outright. No DDS or OS header.
#pragma once

#include <cstdint>
#include <string>

#include "runtime/robot/auv_messages.hpp"

namespace pbppo::dds {

enum AuvSampleFlag : std::uint32_t {
  kSampleNonFinite = 1u << 0,         // a NaN or infinite number in any field
  kSampleSonarOutOfRange = 1u << 1,   // a valid beam's range is negative
  kSampleAngleOutOfRange = 1u << 2,   // roll, pitch, yaw, target or route bearing outside [-pi, pi]
  kSampleSpeedOutOfRange = 1u << 3,   // a body velocity above kAuvMaxPlausibleSpeed*
  kSampleTargetOutOfRange = 1u << 4,  // negative target index or distance, negative stamp
  kSampleTooManyBeams = 1u << 5,      // sonar_beams > kAuvMaxSonarBeams (rejected, not delivered)
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

// "non-finite, sonar out of range" for logs and error messages (set-up and tools only).
std::string DescribeAuvSampleFlags(std::uint32_t flags);
std::string DescribeAuvCommandFlags(std::uint32_t flags);

}  // namespace pbppo::dds
