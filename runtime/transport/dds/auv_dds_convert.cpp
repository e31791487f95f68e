#include "runtime/transport/dds/auv_dds_convert.hpp"

#include <algorithm>

namespace pbppo::dds {

void ToDds(const robot::AuvSensorSample& in, pbppo_idl::auv::SensorState* out) noexcept {
  out->tick(in.tick);
  out->stamp_ns(in.stamp_ns);
  out->x_m(in.x_m);
  out->y_m(in.y_m);
  out->depth_m(in.depth_m);
  out->roll_rad(in.roll_rad);
  out->pitch_rad(in.pitch_rad);
  out->yaw_rad(in.yaw_rad);
  out->surge_mps(in.surge_mps);
  out->sway_mps(in.sway_mps);
  out->heave_mps(in.heave_mps);
  out->roll_rate_radps(in.roll_rate_radps);
  out->pitch_rate_radps(in.pitch_rate_radps);
  out->yaw_rate_radps(in.yaw_rate_radps);
  out->sonar_beams(in.sonar_beams);
  std::copy(in.sonar_m.begin(), in.sonar_m.end(), out->sonar_m().begin());
  out->target_index(in.target_index);
  out->target_x_m(in.target_x_m);
  out->target_y_m(in.target_y_m);
  out->target_distance_m(in.target_distance_m);
  out->target_bearing_rad(in.target_bearing_rad);
  out->route_bearing_rad(in.route_bearing_rad);
  out->clearance_m(in.clearance_m);
  out->mission_complete(in.mission_complete);
  out->episode_end(in.episode_end);
}

void FromDds(const pbppo_idl::auv::SensorState& in, robot::AuvSensorSample* out) noexcept {
  out->tick = in.tick();
  out->stamp_ns = in.stamp_ns();
  out->x_m = in.x_m();
  out->y_m = in.y_m();
  out->depth_m = in.depth_m();
  out->roll_rad = in.roll_rad();
  out->pitch_rad = in.pitch_rad();
  out->yaw_rad = in.yaw_rad();
  out->surge_mps = in.surge_mps();
  out->sway_mps = in.sway_mps();
  out->heave_mps = in.heave_mps();
  out->roll_rate_radps = in.roll_rate_radps();
  out->pitch_rate_radps = in.pitch_rate_radps();
  out->yaw_rate_radps = in.yaw_rate_radps();
  out->sonar_beams = in.sonar_beams();
  std::copy(in.sonar_m().begin(), in.sonar_m().end(), out->sonar_m.begin());
  out->target_index = in.target_index();
  out->target_x_m = in.target_x_m();
  out->target_y_m = in.target_y_m();
  out->target_distance_m = in.target_distance_m();
  out->target_bearing_rad = in.target_bearing_rad();
  out->route_bearing_rad = in.route_bearing_rad();
  out->clearance_m = in.clearance_m();
  out->mission_complete = in.mission_complete();
  out->episode_end = in.episode_end();
}

void ToDds(const robot::AuvCommand& in, pbppo_idl::auv::Command* out) noexcept {
  out->tick(in.tick);
  out->stamp_ns(in.stamp_ns);
  out->answers(in.answers);
  out->surge_speed_mps(in.surge_speed_mps);
  out->yaw_rate_radps(in.yaw_rate_radps);
  out->mode(in.mode);
}

void FromDds(const pbppo_idl::auv::Command& in, robot::AuvCommand* out) noexcept {
  out->tick = in.tick();
  out->stamp_ns = in.stamp_ns();
  out->answers = in.answers();
  out->surge_speed_mps = in.surge_speed_mps();
  out->yaw_rate_radps = in.yaw_rate_radps();
  out->mode = in.mode();
}

void ToDds(const robot::AuvControllerStatus& in, pbppo_idl::auv::ControllerStatus* out) noexcept {
  out->tick(in.tick);
  out->mode(in.mode);
  out->cause(in.cause);
  out->deadline_misses(in.deadline_misses);
  out->stale_samples(in.stale_samples);
  out->invalid_samples(in.invalid_samples);
  out->limited_commands(in.limited_commands);
  out->tick_median_us(in.tick_median_us);
  out->tick_max_us(in.tick_max_us);
}

void FromDds(const pbppo_idl::auv::ControllerStatus& in, robot::AuvControllerStatus* out) noexcept {
  out->tick = in.tick();
  out->mode = in.mode();
  out->cause = in.cause();
  out->deadline_misses = in.deadline_misses();
  out->stale_samples = in.stale_samples();
  out->invalid_samples = in.invalid_samples();
  out->limited_commands = in.limited_commands();
  out->tick_median_us = in.tick_median_us();
  out->tick_max_us = in.tick_max_us();
}

}  // namespace pbppo::dds
