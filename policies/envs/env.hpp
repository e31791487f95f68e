// Training environments: one interface for every task the trainer learns (Pendulum now; the AUV
// navigation task on Simbody and MuJoCo tasks later). Float observations and actions, double
// rewards. Each environment carries the robot IO layout (models/<robot>/io_layout.yaml) it was
// built for, so blob names, layout hash and action map come from the same file the controller
// reads. The policy's action (before the layout's action map) is what Step() receives; the
// environment clips it to its bounds.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/random.hpp"
#include "runtime/core/result.hpp"
#include "runtime/robot/io_layout.hpp"

namespace pbppo::envs {

struct StepResult {
  double reward = 0.0;
  bool terminated = false;  // a true end of the task: no value beyond this state
  bool truncated = false;   // a time limit: the episode was cut, bootstrap from the final state
};

// What a task-style environment knows about its current (or just ended) episode.
struct EpisodeInfo {
  bool available = false;  // false: the environment has no notion of success
  bool success = false;    // the task was completed
  bool failure = false;    // it ended in a failure (e.g. a collision)
  int goals = 0;           // sub-goals reached (e.g. targets)
  double time_s = 0.0;     // simulated time of the episode
};

class Env {
 public:
  virtual ~Env() = default;

  virtual const std::string& name() const noexcept = 0;
  virtual std::uint32_t observation_size() const noexcept = 0;
  virtual std::uint32_t action_size() const noexcept = 0;
  // Bounds of the action Step() accepts; actions outside are clipped to them.
  virtual std::span<const float> action_low() const noexcept = 0;
  virtual std::span<const float> action_high() const noexcept = 0;
  // Episode length after which Step() reports truncated (0: none).
  virtual std::uint32_t max_episode_steps() const noexcept = 0;
  virtual const robot::IoLayout& layout() const noexcept = 0;

  // Starts an episode with a state drawn from `rng`; writes the first observation.
  virtual void Reset(Rng& rng, std::span<float> observation) = 0;
  // Applies one action and writes the next observation. After terminated or truncated the
  // caller must Reset() before the next Step().
  virtual StepResult Step(std::span<const float> action, std::span<float> observation) = 0;

  // An independent copy in the same configuration, for parallel workers. Environments whose
  // state cannot be copied (a Simbody system) return a fresh instance: Reset() it before use.
  virtual std::unique_ptr<Env> Clone() const = 0;

  virtual EpisodeInfo episode_info() const noexcept { return {}; }

  // Asymmetric actor-critic: an environment may give the value function a privileged observation
  // (state no device of the robot measures) beside the policy's. 0: the critic sees the policy's
  // observation. Otherwise CriticObservation writes the critic's observation of the state the last
  // Reset() or Step() left.
  virtual std::uint32_t critic_observation_size() const noexcept { return 0; }
  virtual void CriticObservation(std::span<float> out) const noexcept { (void)out; }
};

struct EnvOptions {
  // Folder holding models/<robot>/io_layout.yaml; empty: the source tree's models/ folder.
  std::string models_dir;
  // Obstacle layout of tasks that have several (auv-nav: easy, medium, hard).
  std::string layout = "hard";
  // auv-nav, training only: probability of an exploring start (sim::AuvNavTask::set_exploring_starts).
  double exploring_starts = 0.0;
  // auv-nav: the reward's progress term, "euclidean" or "geodesic" (sim::AuvTaskParams::progress);
  // empty: as models/auv/auv.yaml says.
  std::string progress;
  // auv-nav: "D:C" replaces auv.yaml's task.geodesic_margin (AuvNav::Make); empty keeps it.
  std::string geodesic_margin;
  // auv-nav: "D:W" replaces auv.yaml's task.clearance_penalty (AuvNav::Make); empty keeps it.
  std::string clearance_penalty;
  // auv-nav, training only: random obstacles per episode beyond each layout's count (AuvNav::Make).
  int extra_obstacles = 0;
  // quadruped-walk: "flat" or "mixed" (flat and block episodes 1:1), and the command ranges
  // "VX:VY:YAW" (maxima; empty: walk.yaml's).
  std::string terrain = "flat";
  std::string commands;
};

// The names MakeEnv() knows.
std::vector<std::string> EnvNames();

// Builds an environment by name; unknown names and bad layout files are errors that say so.
Result<std::unique_ptr<Env>> MakeEnv(const std::string& name, const EnvOptions& options = {});

// The default models folder (the source tree's, overridable with PBPPO_MODELS_DIR).
std::string DefaultModelsDir();

}  // namespace pbppo::envs
