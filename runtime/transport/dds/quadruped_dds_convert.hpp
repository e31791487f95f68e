// How the quadruped operator's message structs (runtime/robot/quadruped_messages.hpp) travel over
// DDS: the types fastddsgen generates from models/quadruped/idl/*.idl, and the conversions both
// ways. Internal to pbppo_dds.
#pragma once

#include "QuadrupedStatusPubSubTypes.h"
#include "VelocityCommandPubSubTypes.h"
#include "runtime/robot/quadruped_messages.hpp"
#include "runtime/transport/dds/dds_endpoint_impl.hpp"

namespace pbppo::dds {

template <>
struct DdsType<robot::VelocityCommand> {
  using Wire = pbppo_idl::quadruped::VelocityCommand;
  using PubSubType = pbppo_idl::quadruped::VelocityCommandPubSubType;
  static void ToWire(const robot::VelocityCommand& in, Wire* out) noexcept;
  static void FromWire(const Wire& in, robot::VelocityCommand* out) noexcept;
};

template <>
struct DdsType<robot::QuadrupedStatus> {
  using Wire = pbppo_idl::quadruped::QuadrupedStatus;
  using PubSubType = pbppo_idl::quadruped::QuadrupedStatusPubSubType;
  static void ToWire(const robot::QuadrupedStatus& in, Wire* out) noexcept;
  static void FromWire(const Wire& in, robot::QuadrupedStatus* out) noexcept;
};

}  // namespace pbppo::dds
