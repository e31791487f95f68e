// The quadruped as a Simbody plant: the URDF (runtime/robot/urdf.hpp) becomes a multibody tree
// whose 12 revolute joints are pins driven by joint torques, under gravity, with the URDF's joint
// damping as a viscous damper. Two mounts:
//
//   stand   the base welded to the world at the stand height, level; no contact;
//   ground  the base free (six degrees of freedom) over a floor at z = 0 and the blocks of a
//           terrain (sim_hil/scenarios/quadruped_terrain.hpp). Every collision shape of the URDF
//           touches the terrain: spheres (the feet) and the end caps of cylinders (thighs,
//           shanks) as spheres, boxes (the base) by their corners. Contact is compliant: a
//           Hunt-Crossley normal force (k d^1.5 (1 + 1.5 c d')) and regularised Coulomb friction
//           (mu fn, linear below a transition speed of 0.1 m/s), the settings measured to work
//           at 1 kHz with fixed-step RK2 at 0.25 ms (/work/shared/PHYSICS.md facts, recorded in
//           docs/quadruped_hil.md).
//
// Time advances in 1 kHz ticks, each made of fixed-step RK2 substeps. Torques are inputs held
// constant over a tick (the motor emulators compute them once per tick from the latest command,
// like a driver's current loop sampled at the simulation rate).
//
// Simbody headers appear only in quadruped_plant.cpp, compiled without NDEBUG (Debian's library
// is built without it) and as C++17 (Simbody 3.7's comparison operators are ambiguous under
// C++20's rewritten candidates), so this header stays C++17. One plant per thread: a Simbody
// System must not be shared.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/urdf.hpp"
#include "sim_hil/scenarios/quadruped_terrain.hpp"

namespace pbppo::sim {

enum class Mount : std::uint8_t { kStand, kGround };

struct ContactParams {
  double stiffness = 1.2e6;     // N / m^1.5: a 13 kg robot on four feet sinks about 1 mm
  double dissipation = 1.0;     // s/m (Hunt-Crossley c)
  double friction = 1.0;        // Coulomb coefficient
  double transition_mps = 0.1;  // below this sliding speed friction grows linearly
};

struct QuadrupedPlantOptions {
  double tick_s = 1e-3;  // one Step()
  int substeps = 4;      // fixed RK2 steps per tick
  double gravity_m_s2 = 9.81;
  Mount mount = Mount::kStand;
  ContactParams contact;              // ground
  std::vector<TerrainBlock> terrain;  // ground: blocks on the floor
};

// The free base (ground mount): world frame z up.
struct BaseState {
  double position_m[3] = {0, 0, 0};
  double quat_wxyz[4] = {1, 0, 0, 0};   // base to world
  double velocity_mps[3] = {0, 0, 0};   // world frame
  double angular_radps[3] = {0, 0, 0};  // base frame
};

class QuadrupedPlant {
 public:
  static Result<std::unique_ptr<QuadrupedPlant>> Make(const robot::RobotDescription& robot,
                                                      const QuadrupedPlantOptions& options = {});
  ~QuadrupedPlant();
  QuadrupedPlant(const QuadrupedPlant&) = delete;
  QuadrupedPlant& operator=(const QuadrupedPlant&) = delete;

  Mount mount() const noexcept;
  std::size_t joint_count() const noexcept;
  // Set-up: puts the joints at q (rad) with velocity dq (rad/s) and restarts time at 0. Ground:
  // the base at `base_xyz` (m; z is the base height above the floor) with yaw `base_yaw_rad`,
  // at rest.
  Status Reset(const std::vector<double>& q_rad, const std::vector<double>& dq_rad_s,
               const double base_xyz[3] = nullptr, double base_yaw_rad = 0);
  // Torques (Nm, actuated-joint order) applied from now until the next call.
  void SetJointTorques(const double* tau_nm, std::size_t count) noexcept;
  // Ground: adds a velocity (world frame, m/s) to the base, as a push would. Not real-time
  // (re-initialises the integrator: about 0.1 ms).
  void Push(double dvx, double dvy, double dvz);
  // Advances one tick. Returns false if the state became non-finite (the plant then holds).
  bool Step() noexcept;

  std::uint64_t tick() const noexcept;
  double time_s() const noexcept;
  double q_rad(std::size_t joint) const noexcept;
  double dq_rad_s(std::size_t joint) const noexcept;
  double tau_nm(std::size_t joint) const noexcept;  // the torque being applied
  // What a base IMU measures: orientation (base to world), angular velocity (base frame) and
  // specific force (m/s^2, base frame; over the last tick). On the stand the base is level.
  void BaseImu(double quat_wxyz[4], double gyro_rad_s[3], double accel_m_s2[3]) const noexcept;
  const BaseState& base() const noexcept;
  // Ground: the terrain height under (x, y); the base's height above it.
  double TerrainHeightAt(double x, double y) const noexcept;
  // Ground, this tick: feet in contact (bit i: foot i, URDF sphere order), and whether any
  // shape other than a foot touched the terrain (base, thighs, shanks).
  std::uint32_t foot_contacts() const noexcept;
  bool body_contact() const noexcept;
  std::size_t foot_count() const noexcept;

 private:
  QuadrupedPlant();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pbppo::sim
