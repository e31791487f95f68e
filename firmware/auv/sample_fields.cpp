#include "firmware/auv/sample_fields.hpp"

namespace pbppo::auv {

Result<SampleFields> SampleFields::Create(const robot::RobotModel& m) {
  SampleFields t;
  Status st;
  auto index = [&](const char* name, std::uint32_t* out) {
    const int k = m.FieldIndex(name);
    if (k < 0 && st)
      st = MakeError(ErrorCode::kMismatch,
                     m.path + ": the AUV's sample has member '" + std::string(name) + "', the robot has no such field");
    *out = k < 0 ? 0 : static_cast<std::uint32_t>(k);
  };
  Map& f = t.f_;
  const std::pair<const char*, std::uint32_t*> named[] = {
      {"tick", &f.tick},
      {"x_m", &f.x},
      {"y_m", &f.y},
      {"depth_m", &f.depth},
      {"roll_rad", &f.roll},
      {"pitch_rad", &f.pitch},
      {"yaw_rad", &f.yaw},
      {"surge_mps", &f.surge},
      {"sway_mps", &f.sway},
      {"heave_mps", &f.heave},
      {"roll_rate_radps", &f.roll_rate},
      {"pitch_rate_radps", &f.pitch_rate},
      {"yaw_rate_radps", &f.yaw_rate},
      {"target_x_m", &f.target_x},
      {"target_y_m", &f.target_y},
      {"target_distance_m", &f.target_distance},
      {"target_bearing_rad", &f.target_bearing},
      {"route_bearing_rad", &f.route_bearing},
      {"clearance_m", &f.clearance},
      {"target_index", &f.target_index},
      {"mission_complete", &f.mission_complete},
      {"episode_end", &f.episode_end},
      {"sonar_beams", &f.sonar_beams},
  };
  for (const auto& [name, out] : named) index(name, out);
  if (!st) return st.error();
  for (; t.beams_ < robot::kAuvMaxSonarBeams; ++t.beams_) {
    const int k = m.FieldIndex(robot::ExpandIndex("sonar_{i}_m", t.beams_));
    if (k < 0) break;
    t.sonar_[t.beams_] = static_cast<std::uint32_t>(k);
  }
  t.stream_ = m.fields[f.x].stream;
  return t;
}

void SampleFields::Write(const robot::AuvSensorSample& s, std::span<double> fields) const noexcept {
  double* x = fields.data();
  x[f_.tick] = static_cast<double>(s.tick);
  x[f_.x] = s.x_m;
  x[f_.y] = s.y_m;
  x[f_.depth] = s.depth_m;
  x[f_.roll] = s.roll_rad;
  x[f_.pitch] = s.pitch_rad;
  x[f_.yaw] = s.yaw_rad;
  x[f_.surge] = s.surge_mps;
  x[f_.sway] = s.sway_mps;
  x[f_.heave] = s.heave_mps;
  x[f_.roll_rate] = s.roll_rate_radps;
  x[f_.pitch_rate] = s.pitch_rate_radps;
  x[f_.yaw_rate] = s.yaw_rate_radps;
  x[f_.target_x] = s.target_x_m;
  x[f_.target_y] = s.target_y_m;
  x[f_.target_distance] = s.target_distance_m;
  x[f_.target_bearing] = s.target_bearing_rad;
  x[f_.route_bearing] = s.route_bearing_rad;
  x[f_.clearance] = s.clearance_m;
  x[f_.target_index] = s.target_index;
  x[f_.mission_complete] = s.mission_complete ? 1.0 : 0.0;
  x[f_.episode_end] = s.episode_end ? 1.0 : 0.0;
  x[f_.sonar_beams] = s.sonar_beams;
  for (std::uint32_t i = 0; i < beams_; ++i) x[sonar_[i]] = static_cast<double>(s.sonar_m[i]);
}

}  // namespace pbppo::auv
