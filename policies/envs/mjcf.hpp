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
//   - a floor plane, and optionally a pool of box geoms for block terrain ("block_<k>", parked
//     below the floor; the environment moves the blocks near the robot into them at run time:
//     MuJoCo 2.2's broad phase costs every static geom on every step, and a height field gives
//     many contacts per foot, both several times slower than a small pool);
//   - one torque motor per actuated joint (gear 1, limited to the URDF effort), in the robot's
//     joint order, so that ctrl[i] is the torque of actuated joint i;
//   - no self-collision: robot geoms touch only the ground (contype 1 / conaffinity 0 on the
//     robot, contype 0 / conaffinity 1 on the ground).
//
// Names: bodies and geoms keep the URDF link names (geom "<link>_<k>" for the k-th collision
// shape), hinges and motors the joint names, the floor geom "floor", the blocks "block_<k>".
#pragma once

#include <string>

#include "runtime/core/result.hpp"
#include "runtime/robot/urdf.hpp"

struct mjModel_;

namespace pbppo::envs {

struct MjcfOptions {
  double timestep_s = 0.005;
  double friction = 1.0;  // sliding friction of every geom (MuJoCo uses the larger of a pair)
  // Box geoms for block terrain (0: none).
  int block_geoms = 0;
  // Initial base height (m): the free joint's reference position.
  double base_height_m = 0.5;
};

// The MJCF text. Errors name the joint or link that MuJoCo cannot represent.
Result<std::string> GenerateMjcf(const robot::RobotDescription& robot, const MjcfOptions& options);

// Compiles MJCF text with MuJoCo (through its virtual file system: no file is written). The
// caller owns the model (mj_deleteModel). Errors carry MuJoCo's message.
Result<mjModel_*> CompileMjcf(const std::string& xml, const std::string& name);

}  // namespace pbppo::envs
