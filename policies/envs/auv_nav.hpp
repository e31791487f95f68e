// The AUV navigation task (sim_hil/scenarios/auv_nav_task: Simbody plant, sonar, the paper's
// reward) as a training environment. Actions are in policy units, [-1, 1] per element; the IO
// layout (models/auv/io_layout.yaml) maps them to [v, omega] commands, the same map the blob
// carries and the controller applies. One task instance (one Simbody System) per environment:
// Clone() builds a fresh instance from the shared configuration and the caller Reset()s it.
// Layout "mixed" draws a layout for every episode (easy 1/4, medium 1/4, hard 1/2): one policy for
// all three.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "policies/envs/registry.hpp"
#include "sim_hil/scenarios/auv_nav_task.hpp"

namespace pbppo::envs {

// auv-nav's flags (AuvNavEnv() declares them for pbppo).
struct AuvNavOptions {
  std::string models_dir;  // holding auv/; empty: DefaultModelsDir()
  // The robot the controller runs (models/auv/robot.yaml); null: loaded from models_dir. Its
  // layouts, IO layout, fields and signals make the task and its observation.
  std::shared_ptr<const robot::RobotModel> robot_model;
  std::string layout = "hard";    // --layout: easy, medium, hard or mixed (the robot's layouts)
  double exploring_starts = 0.0;  // --exploring-starts: see set_exploring_starts
  std::string progress;           // --progress: ProgressFor's spec; empty: auv.yaml's
  std::string geodesic_margin;    // --geodesic-margin: "D:C" replaces auv.yaml's; empty keeps it
  std::string clearance_penalty;  // --clearance-penalty: "D:W" replaces auv.yaml's; empty keeps it
  int extra_obstacles = 0;        // --extra-obstacles: random obstacles beyond each layout's, 0-16
};

class AuvNav final : public Env {
 public:
  // From the options (the layouts of models/<dir>/auv/robot.yaml, and the task's overrides), each
  // checked; errors name the flag and the value.
  static Result<std::unique_ptr<AuvNav>> Make(const AuvNavOptions& options);
  // One task per configuration; with several, each episode draws one uniformly.
  static Result<std::unique_ptr<AuvNav>> Make(std::vector<std::shared_ptr<const sim::AuvTaskConfig>> configs,
                                              const std::string& name);

  // The progress term a spec gives `layout`: "" keeps auv.yaml's (nullopt); "euclidean" or
  // "geodesic" holds for every layout; "LAYOUT=MODE,..." (e.g. "hard=geodesic") for the layouts
  // it names, the others keep auv.yaml's. The whole spec is checked whatever `layout` is ("" only
  // checks it); errors name the part of the spec that is wrong.
  static Result<std::optional<sim::AuvTaskParams::Progress>> ProgressFor(const std::string& spec,
                                                                         const std::string& layout);

  // "D:C" -> (distance_m, cost), each a number in [0, 100]; "" -> nullopt. Errors name the part.
  static Result<std::optional<std::pair<double, double>>> ParseGeodesicMargin(const std::string& spec);
  // "D:W" -> (distance_m, per_step), each a number in [0, 100]; "" -> nullopt. Errors name the part.
  static Result<std::optional<std::pair<double, double>>> ParseClearancePenalty(const std::string& spec);

  const std::string& name() const noexcept override { return name_; }
  std::span<const float> action_low() const noexcept override { return {low_.data(), 2}; }
  std::span<const float> action_high() const noexcept override { return {high_.data(), 2}; }
  std::uint32_t max_episode_steps() const noexcept override;
  const robot::IoLayout& layout() const noexcept override { return configs_[0]->io; }

  void Reset(Rng& rng, std::span<float> observation) override;
  StepResult Step(std::span<const float> action, std::span<float> observation) override;
  std::unique_ptr<Env> Clone() const override;
  EpisodeInfo episode_info() const noexcept override;

  // Training only: see sim::AuvNavTask::set_exploring_starts. Such episodes report no task success
  // (episode_info().available is false): success counts only episodes from the layout's start.
  void set_exploring_starts(double probability) noexcept;

  // The robot model the tasks were made from (null when made from configurations).
  const robot::RobotModel* robot_model() const noexcept { return robot_model_.get(); }
  // The task of the current episode and its configuration.
  const sim::AuvNavTask& task() const noexcept { return tasks_[current_]; }
  const sim::AuvTaskConfig& config() const noexcept { return *configs_[current_]; }

 private:
  // "A:B" -> (A, B), each a number in [0, 100]; `form` and `what` name the spec and its two parts in errors.
  static Result<std::optional<std::pair<double, double>>> ParseNumberPair(const std::string& spec,
                                                                          const std::string& form,
                                                                          const std::array<const char*, 2>& what);

  AuvNav(std::vector<std::shared_ptr<const sim::AuvTaskConfig>> configs, std::vector<sim::AuvNavTask> tasks,
         std::string name);

  std::shared_ptr<const robot::RobotModel> robot_model_;
  std::vector<std::shared_ptr<const sim::AuvTaskConfig>> configs_;
  std::vector<sim::AuvNavTask> tasks_;
  std::size_t current_ = 0;
  double exploring_starts_ = 0.0;
  std::string name_;
  std::array<float, 2> low_{-1.f, -1.f};
  std::array<float, 2> high_{1.f, 1.f};
};

// `auv-nav` for pbppo: its flags, and pbppo eval's --plot, --trajectories and --outcomes
// (auv_nav_registration.cpp).
EnvSpec AuvNavEnv();

}  // namespace pbppo::envs
