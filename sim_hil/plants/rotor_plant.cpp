#include "sim_hil/plants/rotor_plant.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace pbppo::sim {
namespace {

using Mat3 = std::array<robot::Vec3d, 3>;

// R = Rz(yaw) Ry(pitch) Rx(roll) (URDF's fixed-axis rpy).
Mat3 Rotation(const robot::Vec3d& rpy) {
  const double cr = std::cos(rpy[0]), sr = std::sin(rpy[0]), cp = std::cos(rpy[1]), sp = std::sin(rpy[1]),
               cy = std::cos(rpy[2]), sy = std::sin(rpy[2]);
  return {{{cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr},
           {sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr},
           {-sp, cp * sr, cp * cr}}};
}

// The moment of inertia of a link about the line through the joint frame's origin along `axis`
// (both in the link's frame).
double MomentAbout(const robot::UrdfInertial& in, const robot::Vec3d& axis) {
  const Mat3 R = Rotation(in.origin.rpy);
  robot::Vec3d a{};  // the axis in the inertia's frame: R^T axis
  for (std::size_t i = 0; i < 3; ++i) a[i] = R[0][i] * axis[0] + R[1][i] * axis[1] + R[2][i] * axis[2];
  const double I[3][3] = {{in.ixx, in.ixy, in.ixz}, {in.ixy, in.iyy, in.iyz}, {in.ixz, in.iyz, in.izz}};
  double about_com = 0;
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t k = 0; k < 3; ++k) about_com += a[i] * I[i][k] * a[k];
  const robot::Vec3d& c = in.origin.xyz;
  const double along = c[0] * axis[0] + c[1] * axis[1] + c[2] * axis[2];
  return about_com + in.mass_kg * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2] - along * along);
}

}  // namespace

Result<RotorPlant> RotorPlant::Make(const robot::RobotDescription& robot, double tick_s, std::uint32_t substeps) {
  if (!(tick_s > 0) || substeps == 0)
    return MakeError(ErrorCode::kInvalidValue,
                     "rotor plant: tick " + std::to_string(tick_s) + " s, " + std::to_string(substeps) + " substeps");
  const std::string urdf = std::filesystem::path(robot.urdf_path).filename().string();
  RotorPlant p;
  p.h_ = tick_s / substeps;
  p.substeps_ = substeps;
  for (std::size_t j = 0; j < robot.joint_count(); ++j) {
    const robot::UrdfJoint& uj = robot.joint_at(j);
    const robot::UrdfLink& child = robot.urdf.links[uj.child];
    const std::string where = urdf + ": joint '" + uj.name + "': child link '" + child.name + "'";
    if (!child.has_inertial) return MakeError(ErrorCode::kInvalidValue, where + " has no <inertial>");
    const double inertia = MomentAbout(child.inertial, uj.axis);
    if (!(inertia > 0))
      return MakeError(ErrorCode::kInvalidValue,
                       where + ": its moment of inertia about the joint axis is not positive");
    p.inertia_.push_back(inertia);
    p.damping_.push_back(uj.damping_nm_s_rad);
    p.friction_.push_back(uj.friction_nm);
    p.lower_.push_back(uj.lower_rad);  // continuous: -inf
    p.upper_.push_back(uj.upper_rad);
  }
  p.q_.assign(robot.joint_count(), 0.0);
  p.dq_.assign(robot.joint_count(), 0.0);
  for (std::size_t j = 0; j < p.q_.size(); ++j) p.q_[j] = std::clamp(0.0, p.lower_[j], p.upper_[j]);
  return p;
}

void RotorPlant::Reset(const std::vector<double>& q_rad, const std::vector<double>& dq_rad_s) {
  for (std::size_t j = 0; j < q_.size() && j < q_rad.size() && j < dq_rad_s.size(); ++j) {
    q_[j] = std::clamp(q_rad[j], lower_[j], upper_[j]);
    dq_[j] = dq_rad_s[j];
  }
}

void RotorPlant::Step(const double* tau_nm) noexcept {
  for (std::uint32_t s = 0; s < substeps_; ++s) {
    for (std::size_t j = 0; j < q_.size(); ++j) {
      double& dq = dq_[j];
      const double drive = tau_nm[j] - damping_[j] * dq, f = friction_[j];
      if (dq != 0 || std::abs(drive) > f) {  // else friction holds it
        const double sign = dq != 0 ? (dq > 0 ? 1.0 : -1.0) : (drive > 0 ? 1.0 : -1.0);
        const double next = dq + (drive - f * sign) / inertia_[j] * h_;
        dq = dq != 0 && next * dq < 0 ? 0.0 : next;  // friction stops a joint, never reverses it
      }
      q_[j] += dq * h_;
      if (q_[j] < lower_[j]) {
        q_[j] = lower_[j];
        dq = std::max(dq, 0.0);
      } else if (q_[j] > upper_[j]) {
        q_[j] = upper_[j];
        dq = std::min(dq, 0.0);
      }
    }
  }
}

}  // namespace pbppo::sim
