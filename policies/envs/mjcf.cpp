#include "policies/envs/mjcf.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <sstream>
#include <vector>

namespace pbppo::envs {
namespace {

std::string Num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.9g", v);
  return b;
}

std::string Vec(const robot::Vec3d& v) {
  return Num(v[0]) + " " + Num(v[1]) + " " + Num(v[2]);
}

// Unit quaternion (w x y z) of R = Rz(yaw) Ry(pitch) Rx(roll).
std::string QuatOfRpy(const robot::Vec3d& rpy) {
  const double cr = std::cos(rpy[0] / 2), sr = std::sin(rpy[0] / 2);
  const double cp = std::cos(rpy[1] / 2), sp = std::sin(rpy[1] / 2);
  const double cy = std::cos(rpy[2] / 2), sy = std::sin(rpy[2] / 2);
  const double w = cr * cp * cy + sr * sp * sy;
  const double x = sr * cp * cy - cr * sp * sy;
  const double y = cr * sp * cy + sr * cp * sy;
  const double z = cr * cp * sy - sr * sp * cy;
  return Num(w) + " " + Num(x) + " " + Num(y) + " " + Num(z);
}

// R = Rz(yaw) Ry(pitch) Rx(roll), row-major.
std::array<std::array<double, 3>, 3> Rotation(const robot::Vec3d& rpy) {
  const double cr = std::cos(rpy[0]), sr = std::sin(rpy[0]), cp = std::cos(rpy[1]), sp = std::sin(rpy[1]),
               cy = std::cos(rpy[2]), sy = std::sin(rpy[2]);
  return {{{cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr},
           {sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr},
           {-sp, cp * sr, cp * cr}}};
}

std::string Pose(const robot::UrdfPose& p) {
  return "pos=\"" + Vec(p.xyz) + "\" quat=\"" + QuatOfRpy(p.rpy) + "\"";
}

class Writer {
 public:
  Writer(const robot::RobotDescription& robot, const MjcfOptions& o) : r_(robot), o_(o) {}

  Result<std::string> Run() {
    const robot::UrdfModel& u = r_.urdf;
    // Revolute joints that are not actuated would be free hinges: refuse them.
    for (const auto& j : u.joints)
      if (j.type == robot::UrdfJointType::kRevolute &&
          std::find(r_.joint.begin(), r_.joint.end(), static_cast<std::uint32_t>(&j - u.joints.data())) ==
              r_.joint.end())
        return MakeError(ErrorCode::kMismatch, "mjcf: revolute joint '" + j.name + "' is not actuated");
    s_ << "<mujoco model=\"" << u.name << "\">\n"
       << "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
       << "  <option timestep=\"" << Num(o_.timestep_s)
       << "\" integrator=\"Euler\"/>\n"
       // Room for 50 contacts and 200 constraint rows: a walking or falling robot, on blocks too,
       // was measured at up to 10 contacts and 41 rows. MuJoCo sizes each mjData's stack from these
       // (about 5 njmax^2 numbers): 1000 and 250 made it 41 MB per environment, zeroed at creation
       // and at every reset.
       << "  <size njmax=\"200\" nconmax=\"50\"/>\n"
       << "  <default><geom condim=\"3\" friction=\"" << Num(o_.friction) << " 0.005 0.0001\"/></default>\n";
    s_ << "  <worldbody>\n"
       << "    <geom name=\"floor\" type=\"plane\" size=\"0 0 1\" contype=\"0\" conaffinity=\"1\"/>\n";
    for (int k = 0; k < o_.block_geoms; ++k)
      s_ << "    <geom name=\"block_" << k
         << "\" type=\"box\" size=\"0.1 0.1 0.1\" pos=\"0 0 -10\" contype=\"0\" conaffinity=\"0\"/>\n";
    s_ << "    <body name=\"" << u.links[u.root].name << "\" pos=\"0 0 " << Num(o_.base_height_m) << "\">\n"
       << "      <freejoint name=\"root\"/>\n";
    if (auto st = Body(u.root, "      "); !st) return st.error();
    s_ << "    </body>\n  </worldbody>\n  <actuator>\n";
    for (std::size_t i = 0; i < r_.joint_count(); ++i) {
      const robot::UrdfJoint& j = r_.joint_at(i);
      s_ << "    <motor name=\"" << j.name << "\" joint=\"" << j.name
         << "\" gear=\"1\" ctrllimited=\"true\" ctrlrange=\"" << Num(-j.effort_nm) << " " << Num(j.effort_nm)
         << "\"/>\n";
    }
    s_ << "  </actuator>\n</mujoco>\n";
    return s_.str();
  }

 private:
  // The contents of the body of `link` (its joint is written by the caller).
  Status Body(std::uint32_t link, const std::string& in) {
    const robot::UrdfLink& l = r_.urdf.links[link];
    if (!l.has_inertial || !(l.inertial.mass_kg > 0))
      return MakeError(ErrorCode::kInvalidValue, "mjcf: link '" + l.name + "' has no mass (a MuJoCo body needs one)");
    // MuJoCo takes a full inertia only without an orientation: express it in the body frame,
    // I_body = R I R^T with R the inertial frame's orientation.
    const robot::UrdfInertial& I = l.inertial;
    const auto R = Rotation(I.origin.rpy);
    const double J[3][3] = {{I.ixx, I.ixy, I.ixz}, {I.ixy, I.iyy, I.iyz}, {I.ixz, I.iyz, I.izz}};
    double B[3][3] = {};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        for (int c = 0; c < 3; ++c)
          for (int e = 0; e < 3; ++e)
            B[a][b] += R[static_cast<std::size_t>(a)][static_cast<std::size_t>(c)] * J[c][e] *
                       R[static_cast<std::size_t>(b)][static_cast<std::size_t>(e)];
    s_ << in << "<inertial pos=\"" << Vec(I.origin.xyz) << "\" mass=\"" << Num(I.mass_kg) << "\" fullinertia=\""
       << Num(B[0][0]) << " " << Num(B[1][1]) << " " << Num(B[2][2]) << " " << Num(B[0][1]) << " " << Num(B[0][2])
       << " " << Num(B[1][2]) << "\"/>\n";
    for (std::size_t k = 0; k < l.collisions.size(); ++k) {
      const robot::UrdfCollision& c = l.collisions[k];
      s_ << in << "<geom name=\"" << l.name << "_" << k << "\" " << Pose(c.origin)
         << " contype=\"1\" conaffinity=\"0\" ";
      switch (c.shape) {
        case robot::UrdfShape::kSphere: s_ << "type=\"sphere\" size=\"" << Num(c.size[0]) << "\""; break;
        case robot::UrdfShape::kBox:
          s_ << "type=\"box\" size=\"" << Num(c.size[0] / 2) << " " << Num(c.size[1] / 2) << " " << Num(c.size[2] / 2)
             << "\"";
          break;
        case robot::UrdfShape::kCylinder:
          s_ << "type=\"capsule\" size=\"" << Num(c.size[0]) << " " << Num(c.size[1] / 2) << "\"";
          break;
      }
      s_ << "/>\n";
    }
    for (const robot::UrdfJoint& j : r_.urdf.joints) {
      if (j.parent != link) continue;
      s_ << in << "<body name=\"" << r_.urdf.links[j.child].name << "\" " << Pose(j.origin) << ">\n";
      if (j.type == robot::UrdfJointType::kRevolute) {
        s_ << in << "  <joint name=\"" << j.name << "\" type=\"hinge\" axis=\"" << Vec(j.axis)
           << "\" limited=\"true\" range=\"" << Num(j.lower_rad) << " " << Num(j.upper_rad) << "\" damping=\""
           << Num(j.damping_nm_s_rad) << "\" frictionloss=\"" << Num(j.friction_nm) << "\"/>\n";
      }
      if (auto st = Body(j.child, in + "  "); !st) return st;
      s_ << in << "</body>\n";
    }
    return {};
  }

  const robot::RobotDescription& r_;
  const MjcfOptions& o_;
  std::ostringstream s_;
};

}  // namespace

Result<std::string> GenerateMjcf(const robot::RobotDescription& robot, const MjcfOptions& options) {
  if (!(options.timestep_s > 0 && options.timestep_s <= 0.05))
    return MakeError(ErrorCode::kInvalidValue, "mjcf: timestep " + Num(options.timestep_s) + " s is not in (0, 0.05]");
  if (options.block_geoms < 0 || options.block_geoms > 256)
    return MakeError(ErrorCode::kInvalidValue,
                     "mjcf: block_geoms " + std::to_string(options.block_geoms) + " is not in [0, 256]");
  return Writer(robot, options).Run();
}

Result<mjModel*> CompileMjcf(const std::string& xml, const std::string& name) {
  // mjVFS holds 2000 file names of 1000 bytes: too large for the stack.
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const std::string file = name + ".xml";
  if (mj_makeEmptyFileVFS(vfs.get(), file.c_str(), static_cast<int>(xml.size())) != 0)
    return MakeError(ErrorCode::kIo, "mjcf: cannot make the in-memory file '" + file + "'");
  const int index = mj_findFileVFS(vfs.get(), file.c_str());
  std::memcpy(vfs->filedata[index], xml.data(), xml.size());
  char error[1000] = "";
  mjModel* m = mj_loadXML(file.c_str(), vfs.get(), error, sizeof error);
  mj_deleteVFS(vfs.get());
  if (m == nullptr)
    return MakeError(ErrorCode::kFormat, "mjcf: MuJoCo refused the generated model: " + std::string(error));
  return m;
}

}  // namespace pbppo::envs
