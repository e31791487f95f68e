#include "runtime/loop/trajectory_source.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>
#include <sstream>

#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::loop {

Result<Trajectory> ParseTrajectory(const std::string& yaml_text, const std::string& origin,
                                   const robot::RobotModel& robot) {
  auto doc = robot::ParseYaml(yaml_text, origin);
  if (!doc) return std::move(doc).error();
  const YAML::Node root = *doc;
  const robot::YamlFields f(origin);
  constexpr double kInf = HUGE_VAL;
  if (auto st = f.Keys(root, "", {"duration_s", "joints"}); !st) return st.error();
  Trajectory t;
  if (auto st = f.Number(root, "duration_s", "", -kInf, kInf, &t.duration_s); !st) return st.error();
  if (!(t.duration_s > 0)) return f.Fail("duration_s", "is not positive");
  YAML::Node joints;
  if (auto st = f.List(root, "joints", "", true, &joints); !st) return st.error();
  if (joints.size() == 0) return f.Fail("joints", "is empty");
  if (!robot.body) return f.Fail("", "the robot has no description (the joints' limits)");
  std::set<std::string> seen;
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const YAML::Node j = joints[i];
    std::string where = "joints[" + std::to_string(i) + "]";
    if (auto st = f.Keys(j, where, {"joint", "amplitude_rad", "frequency_hz", "phase_rad"}); !st) return st.error();
    std::string name;
    if (auto st = f.Text(j, "joint", where, &name); !st) return st.error();
    where += " '" + name + "'";
    const auto it =
        std::find_if(robot.motors.begin(), robot.motors.end(), [&](const auto& m) { return m.joint == name; });
    if (it == robot.motors.end()) return f.Fail(where + ".joint", "is not an actuated joint of the robot");
    if (!seen.insert(name).second) return f.Fail(where + ".joint", "listed twice");
    JointSinusoid s;
    s.motor = static_cast<std::uint32_t>(it - robot.motors.begin());
    for (const Status& st : {f.Number(j, "amplitude_rad", where, 0.0, kInf, &s.amplitude_rad),
                             f.Number(j, "frequency_hz", where, -kInf, kInf, &s.frequency_hz),
                             f.OptionalNumber(j, "phase_rad", where, -kInf, kInf, &s.phase_rad)}) {
      if (!st) return st.error();
    }
    if (!(s.frequency_hz > 0) || s.frequency_hz > 10) return f.Fail(where + ".frequency_hz", "is outside (0, 10] Hz");
    // The whole sinusoid must stay inside the joint's limits.
    const robot::UrdfJoint& uj = robot.body->urdf.joints[static_cast<std::size_t>(robot.body->urdf.FindJoint(name))];
    const double centre = it->default_q_rad - s.amplitude_rad * std::sin(s.phase_rad);
    if (centre - s.amplitude_rad < uj.lower_rad || centre + s.amplitude_rad > uj.upper_rad) {
      std::ostringstream ss;
      ss << "sweeps [" << centre - s.amplitude_rad << ", " << centre + s.amplitude_rad
         << "] rad, outside the joint's limits [" << uj.lower_rad << ", " << uj.upper_rad << "]";
      return f.Fail(where + ".amplitude_rad", ss.str());
    }
    t.joints.push_back(s);
  }
  return t;
}

Result<Trajectory> RobotTrajectory(const robot::RobotModel& robot) {
  if (!robot.stand_trajectory)
    return MakeError(ErrorCode::kMismatch, robot.path + ": files: no file for 'stand_trajectory'");
  const robot::RobotDocument& doc = *robot.stand_trajectory;
  return ParseTrajectory(doc.text, std::filesystem::path(doc.path).filename().string(), robot);
}

TrajectorySource::TrajectorySource(const robot::RobotModel& robot, Trajectory trajectory)
    : trajectory_(std::move(trajectory)) {
  for (auto* v : {&q_des_, &dq_des_, &track_max_}) v->assign(robot.motors.size(), 0.0);
}

void TrajectorySource::Start(const robot::RobotModel&, const robot::RobotData& d, LoopData&) noexcept {
  start_tick_ = d.tick;
}

double TrajectorySource::rms_tracking_error_rad() const noexcept {
  return track_n_ == 0 ? 0.0 : std::sqrt(track_sq_ / static_cast<double>(track_n_ * q_des_.size()));
}

bool TrajectorySource::Compute(const robot::RobotModel& m, const robot::RobotData& d, LoopData&,
                               std::span<double> desired) noexcept {
  // Time since the run began, the first run tick one tick in.
  const double t = static_cast<double>(d.tick - start_tick_) * m.tick_period_s;
  const std::size_t n = m.motors.size();
  for (std::size_t k = 0; k < n; ++k) {
    q_des_[k] = m.motors[k].default_q_rad;
    dq_des_[k] = 0;
  }
  for (const JointSinusoid& s : trajectory_.joints) {
    const double w = 2 * std::numbers::pi * s.frequency_hz;
    q_des_[s.motor] += s.amplitude_rad * (std::sin(w * t + s.phase_rad) - std::sin(s.phase_rad));
    dq_des_[s.motor] = s.amplitude_rad * w * std::cos(w * t + s.phase_rad);
  }
  double sq = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const robot::MotorSpec& mo = m.motors[k];
    desired[mo.q] = q_des_[k];
    desired[mo.dq] = dq_des_[k];
    const double e = std::abs(d.fields[mo.q_field] - q_des_[k]);
    track_max_[k] = std::max(track_max_[k], e);
    sq += e * e;
  }
  track_sq_ += sq;
  ++track_n_;
  return t < trajectory_.duration_s;
}

}  // namespace pbppo::loop
