// The standard MuJoCo locomotion tasks the paper's table is measured on (hopper, walker2d,
// half-cheetah, ant), as their v3 versions define them: observations, rewards (forward progress,
// healthy reward, control and contact costs), termination, frame skip and 1,000-step episodes.
// The bodies are our own MJCF files (models/<task>/<task>.xml), written from the tasks' published
// dimensions; docs/mujoco_tasks.md lists every value and compares the environments with the
// standard tasks' known behaviour.
//
// One compiled mjModel is shared (read-only) by all copies of a task; each environment owns its
// mjData. Deterministic: the only randomness is the reset noise, drawn from the Rng given to
// Reset().
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "policies/envs/registry.hpp"

struct mjModel_;
struct mjData_;

namespace pbppo::envs {

enum class MujocoTaskKind { kHopper, kWalker2d, kHalfCheetah, kAnt };

// What distinguishes the tasks (the v3 defaults).
struct MujocoTaskSpec {
  MujocoTaskKind kind;
  const char* name;     // the --env name
  const char* folder;   // models/<folder>/<folder>.xml and io_layout.yaml
  int frame_skip;       // physics steps per environment step
  double ctrl_cost;     // ctrl_cost_weight x sum(action^2)
  double contact_cost;  // contact_cost_weight x sum(clip(contact force, -1, 1)^2) (ant)
  double healthy_reward;
  bool terminates;  // ends the episode when unhealthy
  double reset_noise;
  bool normal_velocity_noise;  // velocities reset with noise x N(0, 1), else U(-noise, noise)
  double velocity_clip;        // observed velocities clipped to +-this (0: not clipped)
};

// The spec of `name` (hopper, walker2d, half-cheetah, ant), nullptr if unknown.
const MujocoTaskSpec* FindMujocoTask(const std::string& name) noexcept;
// The --env names of the tasks.
std::vector<std::string> MujocoTaskNames();
// The tasks' registrations: pbppo eval's --through-ends for each, and ant's --contact-forces.
std::vector<EnvSpec> MujocoTaskEnvs();

class MujocoTask final : public Env {
 public:
  static constexpr std::uint32_t kEpisodeSteps = 1000;

  // Loads models/<folder>/<folder>.xml and io_layout.yaml from `models_dir` and checks that they
  // fit the task (observation and action counts, the action map's [-1, 1] bounds, the bodies and
  // joints the task reads). Errors name the file and what is wrong.
  // contact_forces false (ant): the external contact forces are left at zero, observed as 0 and
  // costing nothing, as the paper's software ran (mujoco-py on MuJoCo 2.x never computed them).
  static Result<std::unique_ptr<MujocoTask>> Make(const MujocoTaskSpec& spec, const std::string& models_dir,
                                                  bool contact_forces = true);

  ~MujocoTask() override;
  MujocoTask(const MujocoTask&) = delete;
  MujocoTask& operator=(const MujocoTask&) = delete;

  const std::string& name() const noexcept override { return name_; }
  std::span<const float> action_low() const noexcept override { return low_; }
  std::span<const float> action_high() const noexcept override { return high_; }
  std::uint32_t max_episode_steps() const noexcept override { return kEpisodeSteps; }
  const robot::IoLayout& layout() const noexcept override;
  // The name, and "contact forces zero" when they are left out.
  std::string provenance() const override;

  void Reset(Rng& rng, std::span<float> observation) override;
  StepResult Step(std::span<const float> action, std::span<float> observation) override;
  std::unique_ptr<Env> Clone() const override;

  // For tests and the benchmark: the model and data, the task's spec, the forward position the
  // progress reward measures, whether the current state is healthy, and the environment step (s).
  const mjModel_* model() const noexcept;
  mjData_* data() noexcept { return d_; }
  const MujocoTaskSpec& spec() const noexcept;
  double forward_position() const noexcept;
  bool healthy() const noexcept;
  double dt() const noexcept;
  // Writes the observation of the current state.
  void Observe(std::span<float> observation) const noexcept;

  struct Shared;
  explicit MujocoTask(std::shared_ptr<const Shared> shared);

 private:
  std::shared_ptr<const Shared> shared_;
  std::string name_;
  mjData_* d_ = nullptr;
  std::vector<float> low_, high_;
  std::uint32_t elapsed_ = 0;
};

}  // namespace pbppo::envs
