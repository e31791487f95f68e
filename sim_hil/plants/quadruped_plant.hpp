// The quadruped on a stand as a Simbody plant: the URDF (runtime/robot/urdf.hpp) becomes a
// multibody tree whose base is welded to the world at the stand height (no contact), the 12
// revolute joints are pins driven by joint torques, gravity acts, and the URDF's joint damping
// is a viscous damper. Time advances in 1 kHz ticks, each made of fixed-step RK2 substeps
// (0.25 ms; /work/shared/PHYSICS.md). Torques are inputs held constant over a tick (the motor
// emulators compute them once per tick from the latest command, like a driver's current loop
// sampled at the simulation rate).
//
// Simbody headers appear only in quadruped_plant.cpp, compiled without NDEBUG (Debian's library
// is built without it) and as C++17 (Simbody 3.7's comparison operators are ambiguous under
// C++20's rewritten candidates), so this header stays C++17. One plant per thread: a Simbody System must not be shared.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/urdf.hpp"

namespace pbppo::sim {

struct QuadrupedPlantOptions {
  double tick_s = 1e-3;  // one Step()
  int substeps = 4;      // fixed RK2 steps per tick
  double gravity_m_s2 = 9.81;
};

class QuadrupedStandPlant {
 public:
  static Result<std::unique_ptr<QuadrupedStandPlant>> Make(const robot::RobotDescription& robot,
                                                           const QuadrupedPlantOptions& options = {});
  ~QuadrupedStandPlant();
  QuadrupedStandPlant(const QuadrupedStandPlant&) = delete;
  QuadrupedStandPlant& operator=(const QuadrupedStandPlant&) = delete;

  std::size_t joint_count() const noexcept;
  // Set-up: puts the joints at q (rad) with velocity dq (rad/s) and restarts time at 0.
  Status Reset(const std::vector<double>& q_rad, const std::vector<double>& dq_rad_s);
  // Torques (Nm, actuated-joint order) applied from now until the next call.
  void SetJointTorques(const double* tau_nm, std::size_t count) noexcept;
  // Advances one tick. Returns false if the state became non-finite (the plant then holds).
  bool Step() noexcept;

  std::uint64_t tick() const noexcept;
  double time_s() const noexcept;
  double q_rad(std::size_t joint) const noexcept;
  double dq_rad_s(std::size_t joint) const noexcept;
  double tau_nm(std::size_t joint) const noexcept;  // the torque being applied
  // The base is welded level: what a base IMU measures (specific force, m/s^2, base frame).
  void BaseImu(double quat_wxyz[4], double gyro_rad_s[3], double accel_m_s2[3]) const noexcept;

 private:
  QuadrupedStandPlant();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pbppo::sim
