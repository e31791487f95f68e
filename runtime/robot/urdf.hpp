// A URDF loader for the subset our robots use (set-up time only): links with inertials and
// sphere/box/cylinder collision shapes, revolute and fixed joints with origin, axis, limits and dynamics.
// Our own small XML reader (elements, attributes, comments; no DTD), so runtime/robot needs no
// XML library. Errors name the file, the element and the field:
//
//   quadruped.urdf: joint 'LF_KFE'.limit.effort: '-1' is not a positive number
//
// The robot description (models/<robot>/<robot>.yaml) adds what URDF has no element for: the
// actuated joint order, the default pose, the stand mount and the stand-test gains.
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

enum class UrdfJointType : std::uint8_t { kRevolute, kFixed };

struct UrdfJoint {
  std::string name;
  UrdfJointType type = UrdfJointType::kFixed;
  std::uint32_t parent = 0, child = 0;  // link indices
  UrdfPose origin;                      // child frame in the parent frame at q = 0
  Vec3d axis{1, 0, 0};                  // unit vector in the joint (child) frame
  double lower_rad = 0, upper_rad = 0;  // revolute: position limits
  double effort_nm = 0;                 // revolute: actuator torque limit
  double velocity_rad_s = 0;            // revolute: actuator velocity limit
  double damping_nm_s_rad = 0;          // viscous joint damping
  double friction_nm = 0;
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

// models/<robot>/<robot>.yaml: the URDF plus the data URDF cannot hold.
struct RobotDescription {
  UrdfModel urdf;
  std::string urdf_path;
  std::vector<std::string> joint_names;  // actuated joints in runtime order
  std::vector<std::uint32_t> joint;      // index into urdf.joints, per actuated joint
  std::vector<double> default_q_rad;     // per actuated joint
  double stand_base_height_m = 0;
  double kp_nm_rad = 0, kd_nm_s_rad = 0, damping_kd_nm_s_rad = 0;

  std::size_t joint_count() const noexcept { return joint.size(); }
  const UrdfJoint& joint_at(std::size_t i) const { return urdf.joints[joint[i]]; }
};

Result<RobotDescription> LoadRobotDescription(const std::string& yaml_path);
Result<RobotDescription> ParseRobotDescription(const std::string& yaml_text, const std::string& origin, UrdfModel urdf,
                                               const std::string& urdf_path);

}  // namespace pbppo::robot
