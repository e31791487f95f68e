#include "policies/envs/env.hpp"

#include <cstdlib>

#include "policies/envs/auv_nav.hpp"
#include "policies/envs/pendulum.hpp"
#include "policies/envs/quadruped_walk.hpp"

namespace pbppo::envs {

std::vector<std::string> EnvNames() {
  return {"pendulum", "auv-nav", "quadruped-walk"};
}

std::string DefaultModelsDir() {
  if (const char* env = std::getenv("PBPPO_MODELS_DIR"); env != nullptr && env[0] != '\0') return env;
  return PBPPO_DEFAULT_MODELS_DIR;
}

Result<std::unique_ptr<Env>> MakeEnv(const std::string& name, const EnvOptions& options) {
  const std::string dir = options.models_dir.empty() ? DefaultModelsDir() : options.models_dir;
  if (name == "pendulum") {
    if (!options.progress.empty())
      return MakeError(ErrorCode::kInvalidValue,
                       "progress: only auv-nav has a progress term to choose, not 'pendulum'");
    if (!options.geodesic_margin.empty())
      return MakeError(ErrorCode::kInvalidValue, "geodesic margin: only auv-nav has one, not 'pendulum'");
    if (!options.clearance_penalty.empty())
      return MakeError(ErrorCode::kInvalidValue, "clearance penalty: only auv-nav has one, not 'pendulum'");
    if (options.extra_obstacles != 0)
      return MakeError(ErrorCode::kInvalidValue, "extra obstacles: only auv-nav has obstacles, not 'pendulum'");
    auto layout = robot::LoadIoLayout(dir + "/pendulum/io_layout.yaml");
    if (!layout) return std::move(layout).error();
    auto env = Pendulum::Make(std::move(layout).value());
    if (!env) return std::move(env).error();
    return std::unique_ptr<Env>(std::move(env).value());
  }
  if (name == "auv-nav") {
    auto env = AuvNav::Make(dir, options.layout, options.progress, options.geodesic_margin, options.clearance_penalty,
                            options.extra_obstacles);
    if (!env) return std::move(env).error();
    (*env)->set_exploring_starts(options.exploring_starts);
    return std::unique_ptr<Env>(std::move(env).value());
  }
  if (name == "quadruped-walk") {
    if (!options.progress.empty() || !options.geodesic_margin.empty() || !options.clearance_penalty.empty() ||
        options.extra_obstacles != 0)
      return MakeError(ErrorCode::kInvalidValue,
                       "--progress, --geodesic-margin, --clearance-penalty and --extra-obstacles are auv-nav's, not "
                       "quadruped-walk's");
    QuadrupedWalkOptions o;
    o.models_dir = dir;
    o.terrain = options.terrain;
    o.commands = options.commands;
    auto env = QuadrupedWalk::Make(o);
    if (!env) return std::move(env).error();
    return std::unique_ptr<Env>(std::move(env).value());
  }
  std::string known;
  for (const auto& n : EnvNames()) known += (known.empty() ? "" : ", ") + n;
  return MakeError(ErrorCode::kInvalidValue, "env: '" + name + "' unknown (known: " + known + ")");
}

}  // namespace pbppo::envs
