#include "runtime/transport/dds/quadruped_dds_convert.hpp"

namespace pbppo::dds {

// Each message's fields, named alike in the struct and the IDL.
// clang-format off
#define PBPPO_VELOCITY_COMMAND_FIELDS(X) X(seq) X(stamp_ns) X(vx_mps) X(vy_mps) X(yaw_rate_radps)
#define PBPPO_QUADRUPED_STATUS_FIELDS(X)                                                                \
  X(tick) X(phase) X(mode) X(cause) X(commands_received) X(command_vx_mps) X(command_vy_mps)             \
  X(command_yaw_rate_radps) X(deadline_misses) X(stale_samples) X(tick_median_us) X(tick_max_us)
// clang-format on

PBPPO_DDS_FIELD_CONVERSIONS(robot::VelocityCommand, PBPPO_VELOCITY_COMMAND_FIELDS)
PBPPO_DDS_FIELD_CONVERSIONS(robot::QuadrupedStatus, PBPPO_QUADRUPED_STATUS_FIELDS)

#undef PBPPO_QUADRUPED_STATUS_FIELDS
#undef PBPPO_VELOCITY_COMMAND_FIELDS

}  // namespace pbppo::dds
