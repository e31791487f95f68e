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

PBPPO_DDS_TYPE(robot::AuvSensorSample, pbppo_idl::auv::SensorState);
PBPPO_DDS_TYPE(robot::AuvCommand, pbppo_idl::auv::Command);
PBPPO_DDS_TYPE(robot::AuvControllerStatus, pbppo_idl::auv::ControllerStatus);

}  // namespace pbppo::dds
