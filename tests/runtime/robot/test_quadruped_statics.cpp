// The quadruped can carry itself: at the default pose, a stance leg holding up half the robot's
// weight (a trot has two legs on the ground) needs at most half of each joint's effort limit,
// computed from the description alone (URDF kinematics, masses and limits). The other half is
// left for dynamics: accelerating the body, pushes, uneven ground.
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <string>

#include "runtime/robot/urdf.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo::robot;

namespace {

using Mat3 = std::array<std::array<double, 3>, 3>;

Mat3 Mul(const Mat3& a, const Mat3& b) {
  Mat3 c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) c[i][j] += a[i][k] * b[k][j];
  return c;
}

Vec3d Apply(const Mat3& a, const Vec3d& v) {
  Vec3d r{};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) r[i] += a[i][k] * v[k];
  return r;
}

Mat3 Rpy(const Vec3d& rpy) {
  const double cr = std::cos(rpy[0]), sr = std::sin(rpy[0]), cp = std::cos(rpy[1]), sp = std::sin(rpy[1]),
               cy = std::cos(rpy[2]), sy = std::sin(rpy[2]);
  return {{{cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr},
           {sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr},
           {-sp, cp * sr, cp * cr}}};
}

// Rotation by angle q about unit axis a (Rodrigues).
Mat3 AxisAngle(const Vec3d& a, double q) {
  const double c = std::cos(q), s = std::sin(q), t = 1 - c;
  return {{{t * a[0] * a[0] + c, t * a[0] * a[1] - s * a[2], t * a[0] * a[2] + s * a[1]},
           {t * a[0] * a[1] + s * a[2], t * a[1] * a[1] + c, t * a[1] * a[2] - s * a[0]},
           {t * a[0] * a[2] - s * a[1], t * a[1] * a[2] + s * a[0], t * a[2] * a[2] + c}}};
}

Vec3d Cross(const Vec3d& a, const Vec3d& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

struct Frame {
  Mat3 R{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  Vec3d p{0, 0, 0};
};

}  // namespace

TEST_CASE("quadruped: a stance leg carrying half the weight at the default pose needs <= half of each effort limit") {
  auto d = LoadRobotDescription(pbppo::test::SourcePath("models/quadruped/quadruped.yaml"));
  REQUIRE_MESSAGE(d.ok(), d.error().message);
  const UrdfModel& u = d->urdf;
  const double g = 9.81, weight = u.TotalMassKg() * g;
  // World frames of every link with the base level at the origin and the joints at the default pose.
  std::vector<Frame> link(u.links.size());
  std::vector<double> q(u.joints.size(), 0.0);
  for (std::size_t i = 0; i < d->joint_count(); ++i) q[d->joint[i]] = d->default_q_rad[i];
  for (std::size_t j = 0; j < u.joints.size(); ++j) {  // topological order
    const UrdfJoint& J = u.joints[j];
    const Frame& P = link[J.parent];
    Frame& C = link[J.child];
    const Mat3 R_joint = Mul(P.R, Rpy(J.origin.rpy));
    const Vec3d o = Apply(P.R, J.origin.xyz);
    C.p = {P.p[0] + o[0], P.p[1] + o[1], P.p[2] + o[2]};
    C.R = J.type == UrdfJointType::kRevolute ? Mul(R_joint, AxisAngle(J.axis, q[j])) : R_joint;
  }
  // The links below each actuated joint (its subtree), and the foot of each leg.
  auto below = [&](std::uint32_t joint_index, std::uint32_t l) {
    for (std::uint32_t c = l;;) {
      if (c == u.joints[joint_index].child) return true;
      bool moved = false;
      for (const auto& J : u.joints)
        if (J.child == c) {
          c = J.parent;
          moved = true;
          break;
        }
      if (!moved) return false;
    }
  };
  int legs = 0;
  for (std::size_t f = 0; f < u.links.size(); ++f) {
    if (u.links[f].sphere_radius_m <= 0) continue;  // feet carry the collision spheres
    ++legs;
    const Vec3d contact = {link[f].p[0], link[f].p[1], link[f].p[2] - u.links[f].sphere_radius_m};
    const Vec3d ground_force = {0, 0, weight / 2};
    for (std::size_t i = 0; i < d->joint_count(); ++i) {
      const std::uint32_t j = d->joint[i];
      if (!below(j, static_cast<std::uint32_t>(f))) continue;
      const UrdfJoint& J = u.joints[j];
      const Frame& C = link[J.child];
      const Vec3d axis = Apply(C.R, J.axis);
      // Torque the joint must supply = -(moment of the external forces on its subtree about its axis).
      auto moment = [&](const Vec3d& at, const Vec3d& force) {
        const Vec3d r = {at[0] - C.p[0], at[1] - C.p[1], at[2] - C.p[2]};
        const Vec3d m = Cross(r, force);
        return m[0] * axis[0] + m[1] * axis[1] + m[2] * axis[2];
      };
      double external = moment(contact, ground_force);
      for (std::size_t l = 0; l < u.links.size(); ++l) {
        if (!u.links[l].has_inertial || !below(j, static_cast<std::uint32_t>(l))) continue;
        const Vec3d com = Apply(link[l].R, u.links[l].inertial.origin.xyz);
        external += moment({link[l].p[0] + com[0], link[l].p[1] + com[1], link[l].p[2] + com[2]},
                           {0, 0, -u.links[l].inertial.mass_kg * g});
      }
      const double tau = std::fabs(external);
      INFO(J.name << ": " << tau << " Nm of " << J.effort_nm << " Nm");
      CHECK(tau <= 0.5 * J.effort_nm);
      CHECK(tau < 1e3);
    }
  }
  CHECK(legs == 4);
}
