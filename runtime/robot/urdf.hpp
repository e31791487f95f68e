// A URDF loader for the subset our robots use (set-up time only): links with inertials and
// sphere/box/cylinder collision shapes, revolute, continuous and fixed joints with origin, axis,
// limits and dynamics. A continuous joint (a wheel) has no position limits: its lower and upper are
// ignored, as the URDF specification says, and kept as -inf and +inf; its <limit> (effort and
// velocity) is optional in URDF, but an actuated joint needs one (the description checks).
// Our own small XML reader (elements, attributes, comments; no DTD), so runtime/robot needs no
// XML library. Errors name the file, the element and the field:
//
//   quadruped.urdf: joint 'LF_KFE'.limit.effort: '-1' is not a positive number
//
// The robot description (models/<robot>/<robot>.yaml) adds what URDF has no element for: the
// actuated joint order, how each is commanded (position, or velocity: velocity_control), the
// default pose of the position-commanded ones, the stand mount and the stand-test gains.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"

namespace pbppo::robot {

using Vec3d = std::array<double, 3>;

struct UrdfPose {
  Vec3d xyz{0, 0, 0};
  Vec3d rpy{0, 0, 0};  // fixed-axis roll (x), pitch (y), yaw (z): R = Rz(yaw) Ry(pitch) Rx(roll)
};

struct UrdfInertial {
  UrdfPose origin;  // centre of mass and the frame the inertia is expressed in
  double mass_kg = 0;
  double ixx = 0, ixy = 0, ixz = 0, iyy = 0, iyz = 0, izz = 0;  // kg m^2, about the centre of mass
};

enum class UrdfShape : std::uint8_t { kSphere, kBox, kCylinder };

// One collision shape of a link, in the link frame. A cylinder's axis is the z axis of its origin.
struct UrdfCollision {
  UrdfShape shape = UrdfShape::kSphere;
  UrdfPose origin;
  Vec3d size{0, 0, 0};  // sphere: radius; box: x, y, z lengths; cylinder: radius, length
};

struct UrdfLink {
  std::string name;
  bool has_inertial = false;
  UrdfInertial inertial;
  double sphere_radius_m = 0;  // the first collision sphere (feet); 0: none
  std::vector<UrdfCollision> collisions;
};

enum class UrdfJointType : std::uint8_t { kRevolute, kContinuous, kFixed };

const char* ToString(UrdfJointType type) noexcept;

struct UrdfJoint {
  std::string name;
  UrdfJointType type = UrdfJointType::kFixed;
  std::uint32_t parent = 0, child = 0;  // link indices
  UrdfPose origin;                      // child frame in the parent frame at q = 0
  Vec3d axis{1, 0, 0};                  // unit vector in the joint (child) frame
  double lower_rad = 0, upper_rad = 0;  // revolute: position limits; continuous: -inf, +inf
  double effort_nm = 0;                 // actuator torque limit (continuous without <limit>: 0, none)
  double velocity_rad_s = 0;            // actuator velocity limit (continuous without <limit>: 0, none)
  double damping_nm_s_rad = 0;          // viscous joint damping
  double friction_nm = 0;

  bool moves() const noexcept { return type != UrdfJointType::kFixed; }
  bool continuous() const noexcept { return type == UrdfJointType::kContinuous; }
};

struct UrdfModel {
  std::string name;
  std::vector<UrdfLink> links;
  std::vector<UrdfJoint>
      joints;              // topological order: a joint's parent link is the root or the child of an earlier joint
  std::uint32_t root = 0;  // the one link that is no joint's child

  int FindLink(const std::string& name) const noexcept;
  int FindJoint(const std::string& name) const noexcept;
  double TotalMassKg() const noexcept;
};

Result<UrdfModel> ParseUrdf(const std::string& xml_text, const std::string& origin);
Result<UrdfModel> LoadUrdf(const std::string& path);

// How an actuated joint is commanded. Position: the MIT command's p_des and kp track a target (the
// default pose, a trajectory, a policy's action). Velocity (a wheel): kp is 0, dq_des is the
// commanded speed, kd the joint's velocity gain; such a joint has no position target at all.
// Every continuous joint is velocity-commanded.
enum class JointControl : std::uint8_t { kPosition, kVelocity };

// models/<robot>/<robot>.yaml: the URDF plus the data URDF cannot hold.
struct RobotDescription {
  UrdfModel urdf;
  std::string urdf_path;
  std::vector<std::string> joint_names;      // actuated joints in runtime order
  std::vector<std::uint32_t> joint;          // index into urdf.joints, per actuated joint
  std::vector<double> default_q_rad;         // per actuated joint (a velocity-commanded one: 0, unused)
  std::vector<double> sit_q_rad;             // the same for sit_pose (a sit-down ends in it); empty: none
  std::vector<JointControl> control;         // per actuated joint
  std::vector<double> velocity_kd_nm_s_rad;  // per actuated joint: a velocity-commanded one's kd (else 0)
  double stand_base_height_m = 0;
  double kp_nm_rad = 0, kd_nm_s_rad = 0, damping_kd_nm_s_rad = 0;

  std::size_t joint_count() const noexcept { return joint.size(); }
  bool velocity_commanded(std::size_t i) const { return control[i] == JointControl::kVelocity; }
  const UrdfJoint& joint_at(std::size_t i) const { return urdf.joints[joint[i]]; }
};

Result<RobotDescription> LoadRobotDescription(const std::string& yaml_path);
Result<RobotDescription> ParseRobotDescription(const std::string& yaml_text, const std::string& origin, UrdfModel urdf,
                                               const std::string& urdf_path);

}  // namespace pbppo::robot
