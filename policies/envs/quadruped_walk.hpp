// The quadruped velocity-tracking task (Pb-PPO paper's legged_gym ANYmal-C task, on our robot) in
// MuJoCo 2.2.2: the robot (models/quadruped: URDF, joint order, default pose, CAN map), the task
// (walk.yaml) and the policy's IO layout (io_layout.yaml). docs/quadruped_walk.md lists every
// value beside legged_gym's.
//
//   physics     MJCF generated from the URDF (policies/envs/mjcf.hpp), 200 Hz; the joint PD runs
//               every physics step, the policy every `decimation` steps (50 Hz)
//   action      policy units; the IO layout's action map gives the joint targets
//               (default + 0.25 a, clamped to the URDF limits), exactly as the controller does
//   observation the controller's: the environment writes the robot model's fields as the robot's
//               devices report them (each motor's MIT reply: q, dq, tau through the reply codec
//               with the CAN map's ranges; the base IMU's sample through the IMU codec: the
//               quantised orientation, gyro and specific force; the operator's velocity command),
//               and the controller's robot::SignalProgram (the IO layout's signals: gyro, gravity
//               from the normalised orientation, command, q, dq, last action) and
//               robot::ObservationBuilder make the observation from them. Training noise
//               (walk.yaml noise, uniform) is added to the signals between the two, so that with
//               noise off the observation is the one the controller builds from the same replies
//   critic      the same without noise, plus privileged state: base linear velocity, base height
//               over the ground, foot contacts, friction, added mass, actuation latency
//   commands    vx, vy, heading (-> yaw rate) resampled every resample_s
//   reward      legged_gym's flat-terrain terms
//   randomised  friction, added base mass, PD gains, actuation latency, pushes
//   terrain     flat, or mixed: each episode flat or on random blocks, 1:1 (the blocks near the
//               robot are moved into a small pool of box geoms every policy step)
//
// One compiled template model is shared read-only by every copy of the environment; each copy owns
// a model copy (friction, base mass and the terrain are randomised per episode, and MuJoCo reads
// them from the model) and its mjData. Deterministic for a seed: every random draw comes from the
// environment's own generator, seeded at Reset.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "policies/envs/quadruped_walk_config.hpp"
#include "policies/envs/registry.hpp"
#include "runtime/robot/observation_builder.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/robot/urdf.hpp"
#include "sim_hil/scenarios/quadruped_terrain.hpp"

struct mjModel_;
struct mjData_;

namespace pbppo::envs {

// The paper's test resamples commands at 10 s (legged_gym's period).
inline constexpr double kWalkEvalResampleS = 10.0;

struct QuadrupedWalkOptions {
  std::string models_dir;  // holding <robot>/; empty: DefaultModelsDir()
  // The legged robot: a folder of models_dir (quadruped, go2) or a robot.yaml path.
  std::string robot = "quadruped";
  // The robot the controller runs (robot::LoadRobotModel of models/<robot>/robot.yaml); null:
  // loaded from models_dir. Its fields, signals and IO layout make the observation.
  std::shared_ptr<const robot::RobotModel> robot_model;
  std::string terrain = "flat";  // flat | mixed
  std::string commands;          // "VX:VY:YAW" maxima; empty: walk.yaml's ranges
  std::string command_shares;    // "HEADING:ZERO_PLANAR[:SINGLE_AXIS]" shares; empty: walk.yaml's
  std::string command_resample;  // "SECONDS" between the training's commands; empty: walk.yaml's
  std::string reward_scales;     // "NAME=VALUE,..." reward scales replacing walk.yaml's; empty: none
  bool noise = true;             // observation noise
  bool randomize = true;         // friction, mass, gains, latency, pushes (false: the nominal robot)
  double blocks_fraction = 0.5;  // mixed: the fraction of episodes on blocks
  // The paper's test: commands every kWalkEvalResampleS, every one following a heading, none
  // zeroed by walk.yaml's zero_planar_share, whatever the training used.
  bool paper_test = false;
};

// What happened in the last policy step, for evaluation and tests.
struct WalkTelemetry {
  double time_s = 0;
  std::array<double, 3> command{};   // vx, vy (m/s), yaw rate (rad/s), base frame
  std::array<double, 3> measured{};  // the same, measured (true base velocity)
  std::array<double, 3> position{};  // base, world frame
  double yaw_rad = 0;
  bool on_blocks = false;
  bool fell = false;                // the episode ended by base contact or tilt
  bool base_contact = false;        // ... by base contact (else by tilt)
  std::uint32_t command_index = 0;  // incremented at each resample
  // Steps at which MuJoCo found more contacts or constraint rows than the model has room for
  // (mjcf.cpp's <size>) and dropped some, since the environment was made: 0 in a sound run.
  std::uint32_t physics_overflows = 0;
};

class QuadrupedWalk final : public Env {
 public:
  static Result<std::unique_ptr<QuadrupedWalk>> Make(const QuadrupedWalkOptions& options);
  ~QuadrupedWalk() override;
  QuadrupedWalk(const QuadrupedWalk&) = delete;
  QuadrupedWalk& operator=(const QuadrupedWalk&) = delete;

  const std::string& name() const noexcept override;
  // The terrain, the observation noise and the randomisation the robot trains with.
  std::string provenance() const override;
  std::span<const float> action_low() const noexcept override;
  std::span<const float> action_high() const noexcept override;
  std::uint32_t max_episode_steps() const noexcept override;
  const robot::IoLayout& layout() const noexcept override;
  std::uint32_t critic_observation_size() const noexcept override;
  void CriticObservation(std::span<float> out) const noexcept override;

  void Reset(Rng& rng, std::span<float> observation) override;
  StepResult Step(std::span<const float> action, std::span<float> observation) override;
  std::unique_ptr<Env> Clone() const override;
  EpisodeInfo episode_info() const noexcept override;

  const WalkTelemetry& telemetry() const noexcept { return tel_; }
  // From now on the command is `vx, vy, yaw rate` (base frame) instead of the task's draws and
  // heading controller: Reset and Step then observe it (a scripted operator, as in the HIL's
  // schedules). Call before Reset for the first observation, before each Step for the next.
  void HoldCommand(const std::array<double, 3>& command) noexcept;
  const QuadrupedWalkParams& params() const noexcept;
  const QuadrupedWalkOptions& options() const noexcept;
  const robot::RobotDescription& robot() const noexcept;
  // The robot model the observation is computed over, and its fields as the devices last
  // reported them (after the last Reset or Step): what the controller's transports would write.
  const robot::RobotModel& robot_model() const noexcept;
  std::span<const double> fields() const noexcept { return fields_; }
  // For tests: this copy's MuJoCo model and data (the state its devices report).
  const mjModel_* mujoco_model() const noexcept { return m_; }
  const mjData_* mujoco_data() const noexcept { return d_; }
  // Benchmarks: `steps` MuJoCo steps of a copy of the current state with only the joint PD
  // holding the default pose (no policy, observation or reward); the physics steps per second of
  // this thread's CPU time.
  double BarePhysicsRate(int steps) const;
  struct Shared;

 private:
  explicit QuadrupedWalk(std::shared_ptr<const Shared> shared);
  void BuildTerrain(bool blocks) noexcept;
  void UpdateBlockPool() noexcept;
  double GroundHeight(double x, double y) const noexcept;
  void ResampleCommand() noexcept;
  void ApplyTargets(const double* target_rad, int substeps) noexcept;
  void Contacts() noexcept;
  void WriteFields() noexcept;
  void Observe(std::span<float> observation, bool first) noexcept;
  double Reward() noexcept;

  std::shared_ptr<const Shared> shared_;
  mjModel_* m_ = nullptr;
  mjData_* d_ = nullptr;
  Rng rng_;
  robot::ObservationBuilder builder_, clean_builder_;
  std::vector<double> fields_;                   // the robot model's fields, as the devices report them
  std::vector<double> signals_, clean_signals_;  // the layout's signals, with and without noise
  std::vector<float> observed_action_;           // last_action_<joint>: the action in policy units, as float
  std::vector<float> clean_obs_;
  // Per joint (robot order).
  std::vector<double> kp_, kd_, target_, prev_target_, action_, last_action_, last_dq_, torque_, air_time_;
  std::array<bool, 4> foot_contact_{}, last_foot_contact_{};
  int collisions_ = 0;
  bool base_contact_ = false;
  double friction_ = 1, added_mass_ = 0;
  int latency_substeps_ = 0;
  std::array<double, 4> command_{};    // vx, vy, yaw rate, heading
  std::array<double, 3> error_sum_{};  // sum over the episode's steps of |command - measured|
  int step_ = 0;
  bool on_blocks_ = false, fell_ = false, done_ = true, held_ = false, heading_mode_ = true;
  std::vector<sim::TerrainBlock> blocks_;  // this episode's blocks
  std::vector<int> block_slot_;            // per block: its pool geom, or -1
  std::vector<int> slot_block_;            // per pool geom: its block, or -1
  WalkTelemetry tel_;
};

// `quadruped-walk` for pbppo: its flags, and its pbppo eval (the paper's test, --schedule)
// (quadruped_walk_registration.cpp).
EnvSpec QuadrupedWalkEnv();

}  // namespace pbppo::envs
