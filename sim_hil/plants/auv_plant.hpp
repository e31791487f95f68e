// A small torpedo-shaped AUV as a Simbody free body: gravity and buoyancy (restoring moments),
// linear + quadratic damping, approximated added mass, and three thrusters (a differential
// horizontal pair and one vertical) behind a low-level speed/depth controller that tracks a
// commanded surge speed v and yaw rate w. The trainer's environment and the HIL simulator use
// this one model. Simbody stays behind the pimpl: including this header needs no Simbody
// headers (and hence no -UNDEBUG). One instance per thread; instances share nothing.
//
// Frames: world x, y horizontal, z up (depth = -z); body x forward, y to port, z up. Yaw is
// counter-clockwise about world z, so heading 0 points along +x.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "runtime/core/result.hpp"
#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::sim {

enum class AuvIntegrator { kRk2, kSemiExplicitEuler };

struct PidGains {
  double kp = 0.0;
  double ki = 0.0;
  double kd = 0.0;
  double integral_limit = 0.0;  // |integral of the error| is clamped to this (anti-windup)
};

struct AuvParams {
  // Hull (rigid body, origin at the centre of gravity).
  double mass_kg = 50.0;
  double length_m = 1.6;
  double diameter_m = 0.23;
  std::array<double, 3> inertia_kgm2{0.33, 10.8, 10.8};  // Ixx, Iyy, Izz about the CG
  double buoyancy_n = 492.0;
  double cb_above_cg_m = 0.02;
  double gravity_mps2 = 9.81;
  // Added mass as positive magnitudes (-X_udot, -Y_vdot, -Z_wdot) and (-K_pdot, -M_qdot, -N_rdot).
  std::array<double, 3> added_mass_kg{4.0, 45.0, 45.0};
  std::array<double, 3> added_inertia_kgm2{0.05, 7.0, 7.0};
  // Damping per body DOF (u, v, w, p, q, r): force = -(linear + quadratic * |x|) * x.
  std::array<double, 6> damping_linear{10, 100, 100, 2, 8, 8};
  std::array<double, 6> damping_quadratic{15, 300, 300, 2, 8, 8};
  // Thrusters: a horizontal pair at y = +-lateral_offset, one vertical thruster at the CG.
  double thruster_lateral_offset_m = 0.3;
  double thrust_forward_max_n = 40.0;
  double thrust_reverse_max_n = 25.0;
  double heave_thrust_max_n = 30.0;
  // Low-level controller (runs every physics step, zero-order hold on thrust).
  PidGains surge{150.0, 150.0, 0.0, 1.0};
  PidGains yaw_rate{80.0, 40.0, 0.0, 1.0};
  PidGains depth{150.0, 10.0, 150.0, 1.0};
  double surge_speed_min_mps = -0.5;
  double surge_speed_max_mps = 1.5;
  double yaw_rate_max_radps = 0.6;
  // Integration.
  double physics_step_s = 0.02;
  double control_period_s = 0.1;
  AuvIntegrator integrator = AuvIntegrator::kRk2;

  // Physics steps per control period (control_period_s is a whole multiple of physics_step_s).
  int substeps() const noexcept;
};

// Validates every field; errors name the field and the value.
Status ValidateAuvParams(const AuvParams& p);
// Reads the hull, added_mass, damping, thrusters, controller and simulation sections of the
// plant file (models/auv/auv.yaml, read with robot.yaml: sim::MakeAuvTaskConfig); `path` names it
// in errors. The control period is the robot's (robot.yaml timing.policy_period_s).
Result<AuvParams> ParseAuvParams(const YAML::Node& plant, const std::string& path, double control_period_s);

struct AuvPose {
  double x_m = 0.0;
  double y_m = 0.0;
  double z_m = 0.0;  // up; depth = -z
  double yaw_rad = 0.0;
  double roll_rad = 0.0;
  double pitch_rad = 0.0;
};

struct AuvState {
  double time_s = 0.0;
  double x_m = 0.0, y_m = 0.0, z_m = 0.0;                 // CG position in the world
  double roll_rad = 0.0, pitch_rad = 0.0, yaw_rad = 0.0;  // Z-Y-X (yaw, pitch, roll)
  double u_mps = 0.0, v_mps = 0.0, w_mps = 0.0;           // body linear velocity
  double p_radps = 0.0, q_radps = 0.0, r_radps = 0.0;     // body angular velocity
  // Thrusts applied over the last physics step: starboard, port, vertical.
  std::array<double, 3> thrust_n{0.0, 0.0, 0.0};
};

class AuvPlant {
 public:
  static Result<AuvPlant> Create(const AuvParams& params);

  AuvPlant(AuvPlant&&) noexcept;
  AuvPlant& operator=(AuvPlant&&) noexcept;
  ~AuvPlant();

  // At rest at `pose`, time 0, controller integrators cleared, depth set-point = pose depth.
  void Reset(const AuvPose& pose);
  // Commanded surge speed and yaw rate, clamped to the controller's limits (non-finite -> 0).
  void SetCommand(double v_mps, double w_radps) noexcept;
  void SetDepthSetpoint(double z_m) noexcept;
  // Advances by whole physics steps: round(dt_s / physics_step_s), at least one.
  void Advance(double dt_s) noexcept;
  void AdvanceSteps(int steps) noexcept;
  // Advances one control period.
  void AdvanceControlPeriod() noexcept { AdvanceSteps(params().substeps()); }

  const AuvState& State() const noexcept;
  const AuvParams& params() const noexcept;
  std::uint64_t physics_steps() const noexcept;

 private:
  struct Impl;
  explicit AuvPlant(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace pbppo::sim
