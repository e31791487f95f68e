// The quadruped velocity-tracking task as data (models/quadruped/walk.yaml): simulation rates,
// the joint PD, command ranges, reward scales, termination, observation noise, domain
// randomisation and the block terrain. Set-up time only; errors name the file, the field and the
// value.
#pragma once

#include <array>
#include <string>

#include <yaml-cpp/yaml.h>

#include "runtime/core/result.hpp"

namespace pbppo::envs {

using Range = std::array<double, 2>;  // [low, high]

struct WalkRewardScales {
  double tracking_lin_vel = 0, tracking_ang_vel = 0, lin_vel_z = 0, ang_vel_xy = 0, orientation = 0, torques = 0,
         dof_acc = 0, action_rate = 0, collision = 0, feet_air_time = 0, dof_pos_limits = 0, base_height = 0,
         termination = 0;
};

struct QuadrupedWalkParams {
  // simulation
  double timestep_s = 0.005;
  int decimation = 4;
  double episode_s = 20.0;
  double init_base_height_m = 0.48;
  Range init_joint_scale{0.5, 1.5};
  double init_base_velocity = 0.5;
  // control: the joint PD, robot.yaml's motors.policy_gains (the controller's), not walk.yaml's
  double kp_nm_rad = 20.0, kd_nm_s_rad = 0.5;
  // commands
  double resample_s = 10.0;
  Range vx_mps{-1, 1}, vy_mps{-1, 1}, yaw_rate_radps{-1, 1}, heading_rad{-3.14159, 3.14159};
  double heading_share = 1.0;  // of the resamples: the yaw rate follows a heading (else drawn)
  double heading_gain = 0.5;
  double zero_planar_share = 0.0;  // of the resamples: vx = vy = 0 (standing or turning in place)
  // of the resamples: one axis only, as a joystick's single stick sends: vx alone, vy alone, or a
  // yaw rate alone (each a third), the others 0 and no heading
  double single_axis_share = 0.0;
  double zero_below_mps = 0.2;
  // rewards
  double tracking_sigma = 0.25;
  bool only_positive = true;
  double feet_air_time_target_s = 0.5;
  double soft_dof_pos_limit = 0.9;
  double contact_force_n = 1.0;
  // base_height's target: the base's height over the ground under it (m); base_height costs
  // (height - target)^2. Needed only when that term's scale is not 0.
  double base_height_target_m = 0.0;
  WalkRewardScales scales;
  // termination
  bool terminate_on_base_contact = true;
  double max_tilt_rad = 1.0;
  // noise
  double noise_level = 1.0;
  double noise_ang_vel_radps = 0.2, noise_gravity = 0.05, noise_dof_pos_rad = 0.01, noise_dof_vel_radps = 1.5;
  // randomisation
  Range friction{0.5, 1.25}, added_mass_kg{-1, 1}, gain_scale{0.9, 1.1}, latency_periods{0, 1};
  double push_interval_s = 15.0, push_velocity_mps = 1.0;
  // terrain
  double field_half_size_m = 10.0;
  int blocks = 300;
  Range block_size_m{0.3, 1.0}, block_height_m{0.05, 0.15};
  double clear_radius_m = 0.8;
  double near_m = 1.0;
  int pool = 16;

  double policy_dt_s() const noexcept { return timestep_s * decimation; }
  int episode_steps() const noexcept;
};

// Reads walk.yaml (every section but the control gains), parsed as `root`; errors name `path`.
Result<QuadrupedWalkParams> ParseQuadrupedWalkParams(const YAML::Node& root, const std::string& path);

// The command ranges of a --commands spec "VX_MAX:VY_MAX:YAW_RATE_MAX" (each range [-max, max]);
// an empty spec keeps walk.yaml's. Errors name the part of the spec.
Status ApplyCommandSpec(const std::string& spec, QuadrupedWalkParams& p);

// The command mix of a --command-shares spec "HEADING:ZERO_PLANAR[:SINGLE_AXIS]" (walk.yaml's
// heading_share, zero_planar_share and single_axis_share, each in [0, 1]; without the third part
// walk.yaml's single_axis_share is kept); an empty spec keeps walk.yaml's. Errors name the part.
Status ApplyCommandShares(const std::string& spec, QuadrupedWalkParams& p);

// The training's command period of a --command-resample spec "SECONDS" (walk.yaml's resample_s,
// in [0.02, 3600] as there); an empty spec keeps walk.yaml's. The paper's test keeps its own 10 s.
Status ApplyCommandResample(const std::string& spec, QuadrupedWalkParams& p);

// The reward scales of a --reward-scales spec "NAME=VALUE[,NAME=VALUE...]" (walk.yaml's
// rewards.scales names, e.g. tracking_ang_vel=1.0, and tracking_sigma, the tracking terms'
// width), the others kept; an empty spec keeps walk.yaml's. Errors name the term or the value.
Status ApplyRewardScales(const std::string& spec, QuadrupedWalkParams& p);

}  // namespace pbppo::envs
