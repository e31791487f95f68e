// The MuJoCo model of a legged robot, generated from its description (the URDF and
// models/<robot>/<robot>.yaml, read by runtime/robot/urdf.hpp), so that training, the HIL plant
// and the controller share one description. MuJoCo 2.2.2 can import the URDF itself, but with the
// base welded to the world and without floor or actuators; the generated MJCF adds what training
// needs:
//
//   - the base on a free joint, every revolute joint a hinge with the URDF's range, damping and
//     friction loss, every fixed joint a body without a joint (MuJoCo welds it);
//   - the URDF's inertials (mass, centre of mass, full inertia) and collision shapes (spheres,
//     boxes, and cylinders as capsules, which collide faster and more smoothly);
//   - a floor plane, and optionally a height field over the middle of the floor for rough terrain
//     (its heights are filled at run time in the model's hfield_data);
//   - one torque motor per actuated joint (gear 1, limited to the URDF effort), in the robot's
//     joint order, so that ctrl[i] is the torque of actuated joint i;
//   - no self-collision: robot geoms touch only the ground (contype 1 / conaffinity 0 on the
//     robot, contype 0 / conaffinity 1 on the ground).
//
// Names: bodies and geoms keep the URDF link names (geom "<link>_<k>" for the k-th collision
// shape), hinges and motors the joint names, the floor geom "floor", the height field "terrain".
#pragma once

#include <string>

#include "runtime/core/result.hpp"
#include "runtime/robot/urdf.hpp"

struct mjModel_;

namespace pbppo::envs {

struct MjcfOptions {
  double timestep_s = 0.005;
  double friction = 1.0;  // sliding friction of every geom (MuJoCo uses the larger of a pair)
  // Height field centred on the origin: half sizes (m), cells per side, the height of a data
  // value of 1 (m). cells 0: no height field.
  double hfield_half_size_m = 10.0;
  int hfield_cells = 0;
  double hfield_max_height_m = 0.2;
  // The floor plane lies this far below the height field's base (0 without a height field), so
  // that it only carries the robot once it walks off the field.
  double floor_below_hfield_m = 0.05;
  // Initial base height (m): the free joint's reference position.
  double base_height_m = 0.5;
};

// The MJCF text. Errors name the joint or link that MuJoCo cannot represent.
Result<std::string> GenerateMjcf(const robot::RobotDescription& robot, const MjcfOptions& options);

// Compiles MJCF text with MuJoCo (through its virtual file system: no file is written). The
// caller owns the model (mj_deleteModel). Errors carry MuJoCo's message.
Result<mjModel_*> CompileMjcf(const std::string& xml, const std::string& name);

}  // namespace pbppo::envs
