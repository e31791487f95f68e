#include "runtime/transport/dds/auv_dds_convert.hpp"

#include <algorithm>

namespace pbppo::dds {

// Each message's scalar fields, named alike in the struct and the IDL.
// clang-format off
#define PBPPO_AUV_SAMPLE_FIELDS(X)                                                                          \
  X(tick) X(stamp_ns) X(x_m) X(y_m) X(depth_m) X(roll_rad) X(pitch_rad) X(yaw_rad) X(surge_mps) X(sway_mps) \
  X(heave_mps) X(roll_rate_radps) X(pitch_rate_radps) X(yaw_rate_radps) X(sonar_beams) X(target_index)      \
  X(target_x_m) X(target_y_m) X(target_distance_m) X(target_bearing_rad) X(route_bearing_rad) X(clearance_m) \
  X(mission_complete) X(episode_end)
#define PBPPO_AUV_COMMAND_FIELDS(X) X(tick) X(stamp_ns) X(answers) X(surge_speed_mps) X(yaw_rate_radps) X(mode)
#define PBPPO_AUV_STATUS_FIELDS(X)                                                                   \
  X(tick) X(mode) X(cause) X(deadline_misses) X(stale_samples) X(invalid_samples) X(limited_commands) \
  X(tick_median_us) X(tick_max_us)
// clang-format on

void DdsType<robot::AuvSensorSample>::ToWire(const robot::AuvSensorSample& in, Wire* out) noexcept {
  PBPPO_AUV_SAMPLE_FIELDS(PBPPO_DDS_TO_WIRE_FIELD)
  std::copy(in.sonar_m.begin(), in.sonar_m.end(), out->sonar_m().begin());
}

void DdsType<robot::AuvSensorSample>::FromWire(const Wire& in, robot::AuvSensorSample* out) noexcept {
  PBPPO_AUV_SAMPLE_FIELDS(PBPPO_DDS_FROM_WIRE_FIELD)
  std::copy(in.sonar_m().begin(), in.sonar_m().end(), out->sonar_m.begin());
}

PBPPO_DDS_FIELD_CONVERSIONS(robot::AuvCommand, PBPPO_AUV_COMMAND_FIELDS)
PBPPO_DDS_FIELD_CONVERSIONS(robot::AuvControllerStatus, PBPPO_AUV_STATUS_FIELDS)

#undef PBPPO_AUV_STATUS_FIELDS
#undef PBPPO_AUV_COMMAND_FIELDS
#undef PBPPO_AUV_SAMPLE_FIELDS

}  // namespace pbppo::dds
