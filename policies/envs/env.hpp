// Training environments: one interface for every task the trainer learns (pendulum, auv-nav,
// quadruped-walk, the MuJoCo locomotion tasks; registry.hpp lists them and their flags). Float
// observations and actions, double rewards. Each environment carries the robot IO layout
// (models/<robot>/io_layout.yaml) it was built for, so blob names, layout hash and action map come
// from the same file the controller reads; the robots with a controller (auv-nav, quadruped-walk)
// compute their observation from the robot model's fields through the controller's own signal and
// observation code. The policy's action (before the layout's action map) is what Step() receives;
// the environment clips it to its bounds.
//
// Asymmetric actor-critic: an environment may give the critic a privileged observation (state the
// robot cannot measure: true base velocity, height, friction) beside the actor's deployable one:
// critic_observation_size() > 0, and CriticObservation() after every Reset() and Step(). The
// trainer's value network takes it (with its own normaliser under --normalize-obs); the blob
// carries only the actor, which sees only Reset()'s and Step()'s `observation`. Size 0 (the
// default, pendulum and auv-nav): the critic sees the actor's observation.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <map>
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
  // Velocity-tracking tasks: the episode's mean absolute error of vx, vy (m/s) and the yaw rate
  // (rad/s) against the command; NaN where the task has none.
  std::array<double, 3> tracking_error{kNoValue, kNoValue, kNoValue};
  static constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();
};

class Env {
 public:
  virtual ~Env() = default;

  virtual const std::string& name() const noexcept = 0;
  // The policy's input and output widths: the IO layout's, the one statement of them.
  std::uint32_t observation_size() const noexcept { return layout().observation_size(); }
  std::uint32_t action_size() const noexcept { return layout().action_size(); }
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

  // What the blob's provenance records of the environment (at most 256 bytes): its name, and for
  // environments with noise and randomisation, their settings.
  virtual std::string provenance() const { return name(); }

  // Asymmetric actor-critic (see the top): the size of the critic's privileged observation, 0 when
  // the critic sees the actor's observation; CriticObservation writes it (critic_observation_size()
  // elements) for the state the last Reset() or Step() left, before any next Reset() (so after a
  // truncated step it describes the episode's final state).
  virtual std::uint32_t critic_observation_size() const noexcept { return 0; }
  virtual void CriticObservation(std::span<float> out) const noexcept { (void)out; }
};

// What an environment is built for: pbppo train, or pbppo eval (quadruped-walk: the nominal robot
// unless --randomize, the paper's test's commands).
enum class EnvPurpose : std::uint8_t { kTrain, kEval };

// What an environment is built from: --env, --models and the environment's own flags, as pbppo
// train or pbppo eval got them; MakeEnv() checks them against the environment's registration
// (registry.hpp; errors name the flag and the value).
struct EnvOptions {
  std::string name = "pendulum";  // --env: one of EnvNames()
  // --models: folder holding models/<robot>/...; empty: DefaultModelsDir().
  std::string models_dir;
  EnvPurpose purpose = EnvPurpose::kTrain;
  // The environment's flags by name without the dashes ("layout" -> "hard", "extra-obstacles" ->
  // "2"); a switch given holds "true". Flags not given take the environment's defaults.
  std::map<std::string, std::string> flags;
};

// The names MakeEnv() knows.
std::vector<std::string> EnvNames();

// Builds the environment `options.name` and checks every flag it was given: an unknown name, a
// bad value, a flag the environment does not have and a bad layout file are errors that name the
// flag and the value ("--extra-obstacles: only auv-nav has obstacles, not 'pendulum'").
Result<std::unique_ptr<Env>> MakeEnv(const EnvOptions& options);

// The default models folder (the source tree's, overridable with PBPPO_MODELS_DIR).
std::string DefaultModelsDir();

}  // namespace pbppo::envs
