// How the AUV's message structs (runtime/robot/auv_messages.hpp) travel over DDS: the types
// fastddsgen generates from models/auv/idl/*.idl, and the conversions both ways (every field,
// sonar ranges past sonar_beams included: the array is fixed at 32). Internal to pbppo_dds.
#pragma once

#include "AuvCommandPubSubTypes.h"
#include "AuvControllerStatusPubSubTypes.h"
#include "AuvSensorStatePubSubTypes.h"
#include "runtime/robot/auv_messages.hpp"
#include "runtime/transport/dds/dds_endpoint_impl.hpp"

namespace pbppo::dds {

template <>
struct DdsType<robot::AuvSensorSample> {
  using Wire = pbppo_idl::auv::SensorState;
  using PubSubType = pbppo_idl::auv::SensorStatePubSubType;
  static void ToWire(const robot::AuvSensorSample& in, Wire* out) noexcept;
  static void FromWire(const Wire& in, robot::AuvSensorSample* out) noexcept;
};

template <>
struct DdsType<robot::AuvCommand> {
  using Wire = pbppo_idl::auv::Command;
  using PubSubType = pbppo_idl::auv::CommandPubSubType;
  static void ToWire(const robot::AuvCommand& in, Wire* out) noexcept;
  static void FromWire(const Wire& in, robot::AuvCommand* out) noexcept;
};

template <>
struct DdsType<robot::AuvControllerStatus> {
  using Wire = pbppo_idl::auv::ControllerStatus;
  using PubSubType = pbppo_idl::auv::ControllerStatusPubSubType;
  static void ToWire(const robot::AuvControllerStatus& in, Wire* out) noexcept;
  static void FromWire(const Wire& in, robot::AuvControllerStatus* out) noexcept;
};

}  // namespace pbppo::dds
