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

  // An independent copy in the same configuration (state included), for parallel workers.
  virtual std::unique_ptr<Env> Clone() const = 0;
};

struct EnvOptions {
  // Folder holding models/<robot>/io_layout.yaml; empty: the source tree's models/ folder.
  std::string models_dir;
};

// The names MakeEnv() knows.
std::vector<std::string> EnvNames();

// Builds an environment by name; unknown names and bad layout files are errors that say so.
Result<std::unique_ptr<Env>> MakeEnv(const std::string& name, const EnvOptions& options = {});

// The default models folder (the source tree's, overridable with PBPPO_MODELS_DIR).
std::string DefaultModelsDir();

}  // namespace pbppo::envs
