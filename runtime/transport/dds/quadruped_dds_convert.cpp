#include "runtime/transport/dds/quadruped_dds_convert.hpp"

namespace pbppo::dds {

// Each message's fields, named alike in the struct and the IDL.
// clang-format off
#define PBPPO_VELOCITY_COMMAND_FIELDS(X) X(seq) X(stamp_ns) X(vx_mps) X(vy_mps) X(yaw_rate_radps)
#define PBPPO_QUADRUPED_STATUS_FIELDS(X)                                                                \
  X(tick) X(phase) X(mode) X(cause) X(commands_received) X(command_vx_mps) X(command_vy_mps)             \
  X(command_yaw_rate_radps) X(deadline_misses) X(stale_samples) X(tick_median_us) X(tick_max_us)
// clang-format on
#define PBPPO_TO_WIRE(f) out->f(in.f);
#define PBPPO_FROM_WIRE(f) out->f = in.f();

void DdsType<robot::VelocityCommand>::ToWire(const robot::VelocityCommand& in, Wire* out) noexcept {
  PBPPO_VELOCITY_COMMAND_FIELDS(PBPPO_TO_WIRE)
}

void DdsType<robot::VelocityCommand>::FromWire(const Wire& in, robot::VelocityCommand* out) noexcept {
  PBPPO_VELOCITY_COMMAND_FIELDS(PBPPO_FROM_WIRE)
}

void DdsType<robot::QuadrupedStatus>::ToWire(const robot::QuadrupedStatus& in, Wire* out) noexcept {
  PBPPO_QUADRUPED_STATUS_FIELDS(PBPPO_TO_WIRE)
}

void DdsType<robot::QuadrupedStatus>::FromWire(const Wire& in, robot::QuadrupedStatus* out) noexcept {
  PBPPO_QUADRUPED_STATUS_FIELDS(PBPPO_FROM_WIRE)
}

#undef PBPPO_FROM_WIRE
#undef PBPPO_TO_WIRE
#undef PBPPO_QUADRUPED_STATUS_FIELDS
#undef PBPPO_VELOCITY_COMMAND_FIELDS

}  // namespace pbppo::dds
