// The robot's CAN map, as data (models/<robot>/can_map.yaml): buses, the identifiers of every
// motor and IMU, and each actuator's MIT-protocol ranges. The id -> codec table of the CAN
// transport (runtime/transport/can/can_table.hpp) is built from it at set-up. Set-up time only.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/mit_range.hpp"

namespace pbppo::robot {

inline constexpr std::uint32_t kCanMaxStandardId = 0x7FF;

struct CanBus {
  std::string name;       // "front"
  std::string interface;  // "can0" on the robot
  bool fd = false;        // the interface runs CAN FD (classic frames still pass)
};

struct CanActuator {
  std::string name;
  MitRange range;
};

struct CanMotor {
  std::string joint;           // "LF_HAA"
  std::uint32_t bus = 0;       // index into CanMap::buses
  std::uint32_t id = 0;        // command frame identifier = motor id byte of the reply (1..255)
  std::uint32_t reply_id = 0;  // identifier of the reply frame
  std::uint32_t actuator = 0;  // index into CanMap::actuators
};

enum class ImuFormat : std::uint8_t { kClassic, kFd };

struct CanImu {
  std::string name;
  std::uint32_t bus = 0;
  ImuFormat format = ImuFormat::kClassic;
  std::uint32_t id = 0;  // classic: id, id+1, id+2; fd: id
};

struct CanMap {
  std::string robot;
  std::vector<CanBus> buses;
  std::vector<CanActuator> actuators;
  std::vector<CanMotor> motors;
  std::vector<CanImu> imus;

  const MitRange& range_of(const CanMotor& m) const { return actuators[m.actuator].range; }
};

// Parses and validates a CAN map. Errors name the file, the element and the field: unknown
// fields, buses or actuators, duplicate names or identifiers on a bus, min >= max, identifiers
// outside the standard 11-bit range, an FD IMU on a classic bus.
Result<CanMap> LoadCanMap(const std::string& path);
Result<CanMap> ParseCanMap(const std::string& yaml_text, const std::string& origin);

const char* ToString(ImuFormat format) noexcept;

}  // namespace pbppo::robot
