// Any robot's actuated joints as free rotors: the robot on a stand, its base held still and level,
// its wheels in the air. Each actuated joint turns its child link about the joint axis, with the
// link's inertia about that axis (its URDF <inertial>, moved to the joint by the parallel-axis
// theorem), the URDF's viscous damping and Coulomb friction (<dynamics>); a revolute joint stops
// dead at its limits, a continuous one turns without end. Gravity, the coupling between joints,
// the links below the child and contacts are not modelled: a plant for testing controllers and
// transports on any robot that is data only, not for judging a gait.
//
// Semi-implicit Euler in `substeps` steps per tick; deterministic, no allocation in Step.
#pragma once

#include <cstdint>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/urdf.hpp"

namespace pbppo::sim {

class RotorPlant {
 public:
  // Errors name the URDF, the joint and its child link (a child without an inertial, a zero
  // moment about the axis).
  static Result<RotorPlant> Make(const robot::RobotDescription& robot, double tick_s, std::uint32_t substeps = 4);

  // One tick with the joints' torques (per actuated joint, Nm).
  void Step(const double* tau_nm) noexcept;
  // Puts the joints at q with velocity dq (per actuated joint; a revolute joint inside its limits).
  void Reset(const std::vector<double>& q_rad, const std::vector<double>& dq_rad_s);

  std::size_t joint_count() const noexcept { return q_.size(); }
  const double* q_rad() const noexcept { return q_.data(); }
  const double* dq_rad_s() const noexcept { return dq_.data(); }
  double inertia_kg_m2(std::size_t j) const noexcept { return inertia_[j]; }

 private:
  std::vector<double> q_, dq_, inertia_, damping_, friction_, lower_, upper_;
  double h_ = 0;
  std::uint32_t substeps_ = 1;
};

}  // namespace pbppo::sim
