// How the quadruped operator's message structs (runtime/robot/quadruped_messages.hpp) travel over
// DDS: the types fastddsgen generates from models/quadruped/idl/*.idl, and the conversions both
// ways. Internal to pbppo_dds.
#pragma once

#include "QuadrupedStatusPubSubTypes.h"
#include "VelocityCommandPubSubTypes.h"
#include "runtime/robot/quadruped_messages.hpp"
#include "runtime/transport/dds/dds_endpoint_impl.hpp"

namespace pbppo::dds {

PBPPO_DDS_TYPE(robot::VelocityCommand, pbppo_idl::quadruped::VelocityCommand);
PBPPO_DDS_TYPE(robot::QuadrupedStatus, pbppo_idl::quadruped::QuadrupedStatus);

}  // namespace pbppo::dds
