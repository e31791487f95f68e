// Conversions between the AUV's plain message structs (runtime/robot/auv_messages.hpp) and the
// types fastddsgen generates from models/auv/idl/*.idl. Internal to pbppo_dds and its tests.
#pragma once

#include "AuvCommandPubSubTypes.h"
#include "AuvControllerStatusPubSubTypes.h"
#include "AuvSensorStatePubSubTypes.h"
#include "runtime/robot/auv_messages.hpp"

namespace pbppo::dds {

// Every field, including sonar ranges past sonar_beams (the array is fixed at 32).
void ToDds(const robot::AuvSensorSample& in, pbppo_idl::auv::SensorState* out) noexcept;
void FromDds(const pbppo_idl::auv::SensorState& in, robot::AuvSensorSample* out) noexcept;
void ToDds(const robot::AuvCommand& in, pbppo_idl::auv::Command* out) noexcept;
void FromDds(const pbppo_idl::auv::Command& in, robot::AuvCommand* out) noexcept;
void ToDds(const robot::AuvControllerStatus& in, pbppo_idl::auv::ControllerStatus* out) noexcept;
void FromDds(const pbppo_idl::auv::ControllerStatus& in, robot::AuvControllerStatus* out) noexcept;

}  // namespace pbppo::dds
