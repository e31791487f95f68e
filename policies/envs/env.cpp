#include "policies/envs/env.hpp"

#include <cstdlib>

#include "policies/envs/auv_nav.hpp"
#include "policies/envs/mujoco_tasks.hpp"
#include "policies/envs/pendulum.hpp"
#include "policies/envs/quadruped_walk.hpp"

namespace pbppo::envs {

std::vector<std::string> EnvNames() {
  std::vector<std::string> names = {"pendulum", "auv-nav", "quadruped-walk"};
  for (auto& n : MujocoTaskNames()) names.push_back(std::move(n));
  return names;
}

std::string DefaultModelsDir() {
  if (const char* env = std::getenv("PBPPO_MODELS_DIR"); env != nullptr && env[0] != '\0') return env;
  return PBPPO_DEFAULT_MODELS_DIR;
}

Result<std::unique_ptr<Env>> MakeEnv(const EnvOptions& options) {
  const std::string& name = options.name;
  // An environment's flags given to another one are refused naming the flag.
  auto only = [&](const char* flag, const char* env, const std::string& what) {
    return MakeError(ErrorCode::kInvalidValue,
                     std::string(flag) + ": only " + env + " has " + what + ", not '" + name + "'");
  };
  if (name != "auv-nav") {
    if (!options.progress.empty()) return only("--progress", "auv-nav", "a progress term to choose");
    if (!options.geodesic_margin.empty()) return only("--geodesic-margin", "auv-nav", "one");
    if (!options.clearance_penalty.empty()) return only("--clearance-penalty", "auv-nav", "one");
    if (options.extra_obstacles != 0) return only("--extra-obstacles", "auv-nav", "obstacles");
    if (options.exploring_starts != 0) return only("--exploring-starts", "auv-nav", "exploring starts");
  }
  if (name != "quadruped-walk") {
    if (options.terrain != "flat") return only("--terrain", "quadruped-walk", "terrains to choose");
    if (!options.commands.empty()) return only("--commands", "quadruped-walk", "velocity commands");
    if (!options.command_shares.empty()) return only("--command-shares", "quadruped-walk", "velocity commands");
    if (!options.reward_scales.empty()) return only("--reward-scales", "quadruped-walk", "reward scales to set");
  }
  if (options.contact_forces != "computed") {
    if (name != "ant") return only("--contact-forces", "ant", "contact forces to leave out");
    if (options.contact_forces != "zero")
      return MakeError(ErrorCode::kInvalidValue,
                       "--contact-forces: '" + options.contact_forces + "' is not computed or zero");
  }
  const std::string dir = options.models_dir.empty() ? DefaultModelsDir() : options.models_dir;
  if (name == "pendulum") {
    auto layout = robot::LoadIoLayout(dir + "/pendulum/io_layout.yaml");
    if (!layout) return std::move(layout).error();
    auto env = Pendulum::Make(std::move(layout).value());
    if (!env) return std::move(env).error();
    return std::unique_ptr<Env>(std::move(env).value());
  }
  if (name == "auv-nav") {
    auto env = AuvNav::Make(options);
    if (!env) return std::move(env).error();
    return std::unique_ptr<Env>(std::move(env).value());
  }
  if (name == "quadruped-walk") {
    QuadrupedWalkOptions o;
    o.models_dir = dir;
    o.terrain = options.terrain;
    o.commands = options.commands;
    o.command_shares = options.command_shares;
    o.reward_scales = options.reward_scales;
    o.randomize = options.randomize;
    o.paper_test = options.paper_test;
    auto env = QuadrupedWalk::Make(o);
    if (!env) return std::move(env).error();
    return std::unique_ptr<Env>(std::move(env).value());
  }
  if (const MujocoTaskSpec* spec = FindMujocoTask(name)) {
    auto env = MujocoTask::Make(*spec, dir, options.contact_forces == "computed");
    if (!env) return std::move(env).error();
    return std::unique_ptr<Env>(std::move(env).value());
  }
  std::string known;
  for (const auto& n : EnvNames()) known += (known.empty() ? "" : ", ") + n;
  return MakeError(ErrorCode::kInvalidValue, "--env: '" + name + "' unknown (known: " + known + ")");
}

}  // namespace pbppo::envs
