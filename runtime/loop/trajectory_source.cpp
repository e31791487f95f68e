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
    if (auto st =
            f.Keys(j, where, {"joint", "amplitude_rad", "speed_rad_s", "amplitude_rad_s", "frequency_hz", "phase_rad"});
        !st)
      return st.error();
    std::string name;
    if (auto st = f.Text(j, "joint", where, &name); !st) return st.error();
    where += " '" + name + "'";
    const auto it =
        std::find_if(robot.motors.begin(), robot.motors.end(), [&](const auto& m) { return m.joint == name; });
    if (it == robot.motors.end()) return f.Fail(where + ".joint", "is not an actuated joint of the robot");
    if (!seen.insert(name).second) return f.Fail(where + ".joint", "listed twice");
    JointSinusoid s;
    s.motor = static_cast<std::uint32_t>(it - robot.motors.begin());
    s.velocity = it->velocity_commanded();
    // A position for a velocity-commanded joint, or a speed for a position-commanded one.
    for (const char* key : {"amplitude_rad", "speed_rad_s", "amplitude_rad_s"}) {
      if (!j[key] || (std::string(key) == "amplitude_rad") == !s.velocity) continue;
      if (s.velocity)
        return f.Fail(where + "." + key, "joint '" + name + "' is velocity-commanded" +
                                             (it->continuous ? " (continuous)" : "") +
                                             ": it takes no position target (give speed_rad_s, amplitude_rad_s)");
      return f.Fail(
          where + "." + key,
          "joint '" + name + "' is position-commanded: give amplitude_rad (a sinusoid around its default pose)");
    }
    const bool sweeps = !s.velocity || j["amplitude_rad_s"];
    for (const Status& st :
         {s.velocity ? f.OptionalNumber(j, "speed_rad_s", where, -kInf, kInf, &s.speed_rad_s) : Status(),
          s.velocity ? f.OptionalNumber(j, "amplitude_rad_s", where, 0.0, kInf, &s.amplitude_rad_s)
                     : f.Number(j, "amplitude_rad", where, 0.0, kInf, &s.amplitude_rad),
          sweeps ? f.Number(j, "frequency_hz", where, -kInf, kInf, &s.frequency_hz) : Status(),
          f.OptionalNumber(j, "phase_rad", where, -kInf, kInf, &s.phase_rad)}) {
      if (!st) return st.error();
    }
    if (sweeps && (!(s.frequency_hz > 0) || s.frequency_hz > 10))
      return f.Fail(where + ".frequency_hz", "is outside (0, 10] Hz");
    if (s.velocity) {
      // The whole speed sweep must stay inside the joint's velocity limit (its dq_des_ command's).
      const robot::CommandSpec& c = robot.commands[it->dq];
      const double centre = s.speed_rad_s - s.amplitude_rad_s * std::sin(s.phase_rad);
      if (centre - s.amplitude_rad_s < c.min || centre + s.amplitude_rad_s > c.max) {
        std::ostringstream ss;
        ss << "sweeps [" << centre - s.amplitude_rad_s << ", " << centre + s.amplitude_rad_s
           << "] rad/s, outside the joint's velocity limits [" << c.min << ", " << c.max << "]";
        return f.Fail(where + (j["amplitude_rad_s"] ? ".amplitude_rad_s" : ".speed_rad_s"), ss.str());
      }
      t.joints.push_back(s);
      continue;
    }
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
  for (const robot::MotorSpec& mo : robot.motors) speed_motors_ += mo.velocity_commanded() ? 1u : 0u;
}

void TrajectorySource::Start(const robot::RobotModel&, const robot::RobotData& d, LoopData&) noexcept {
  start_tick_ = d.tick;
}

double TrajectorySource::rms_tracking_error_rad() const noexcept {
  const std::size_t n = q_des_.size() - speed_motors_;
  return track_n_ == 0 || n == 0 ? 0.0 : std::sqrt(track_sq_ / static_cast<double>(track_n_ * n));
}

double TrajectorySource::rms_speed_error_rad_s() const noexcept {
  return track_n_ == 0 || speed_motors_ == 0 ? 0.0
                                             : std::sqrt(speed_sq_ / static_cast<double>(track_n_ * speed_motors_));
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
    if (s.velocity) {
      dq_des_[s.motor] = s.speed_rad_s + s.amplitude_rad_s * (std::sin(w * t + s.phase_rad) - std::sin(s.phase_rad));
      continue;
    }
    q_des_[s.motor] += s.amplitude_rad * (std::sin(w * t + s.phase_rad) - std::sin(s.phase_rad));
    dq_des_[s.motor] = s.amplitude_rad * w * std::cos(w * t + s.phase_rad);
  }
  double sq = 0, speed_sq = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const robot::MotorSpec& mo = m.motors[k];
    desired[mo.dq] = dq_des_[k];
    if (mo.velocity_commanded()) {  // a speed: no position target
      const double e = std::abs(d.fields[mo.dq_field] - dq_des_[k]);
      track_max_[k] = std::max(track_max_[k], e);
      speed_sq += e * e;
      continue;
    }
    desired[mo.q] = q_des_[k];
    const double e = std::abs(d.fields[mo.q_field] - q_des_[k]);
    track_max_[k] = std::max(track_max_[k], e);
    sq += e * e;
  }
  track_sq_ += sq;
  speed_sq_ += speed_sq;
  ++track_n_;
  return t < trajectory_.duration_s;
}

void TrajectorySource::SaveState(StateWriter& o) const noexcept {
  o.Put(start_tick_);
  o.Put(track_n_);
  o.Put(track_sq_);
  o.Put(speed_sq_);
  o.PutSpan<double>(track_max_);
}

bool TrajectorySource::LoadState(StateReader& in) {
  return in.Get(start_tick_, "trajectory.start_tick") && in.Get(track_n_, "trajectory.ticks") &&
         in.Get(track_sq_, "trajectory.track_sq") && in.Get(speed_sq_, "trajectory.speed_sq") &&
         in.GetSpan<double>(track_max_, "trajectory.track_max");
}

}  // namespace pbppo::loop
