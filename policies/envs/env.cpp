#include "policies/envs/env.hpp"

#include <cstdlib>

#include "policies/envs/auv_nav.hpp"
#include "policies/envs/pendulum.hpp"

namespace pbppo::envs {

std::vector<std::string> EnvNames() {
  return {"pendulum", "auv-nav"};
}

std::string DefaultModelsDir() {
  if (const char* env = std::getenv("PBPPO_MODELS_DIR"); env != nullptr && env[0] != '\0') return env;
  return PBPPO_DEFAULT_MODELS_DIR;
}

Result<std::unique_ptr<Env>> MakeEnv(const EnvOptions& options) {
  const std::string& name = options.name;
  if (name == "auv-nav") {
    auto env = AuvNav::Make(options);
    if (!env) return std::move(env).error();
    return std::unique_ptr<Env>(std::move(env).value());
  }
  if (name == "pendulum") {
    auto none = [&](const char* flag, const std::string& what) {
      return MakeError(ErrorCode::kInvalidValue,
                       std::string(flag) + ": only auv-nav has " + what + ", not '" + name + "'");
    };
    if (!options.progress.empty()) return none("--progress", "a progress term to choose");
    if (!options.geodesic_margin.empty()) return none("--geodesic-margin", "one");
    if (!options.clearance_penalty.empty()) return none("--clearance-penalty", "one");
    if (options.extra_obstacles != 0) return none("--extra-obstacles", "obstacles");
    if (options.exploring_starts != 0) return none("--exploring-starts", "exploring starts");
    const std::string dir = options.models_dir.empty() ? DefaultModelsDir() : options.models_dir;
    auto layout = robot::LoadIoLayout(dir + "/pendulum/io_layout.yaml");
    if (!layout) return std::move(layout).error();
    auto env = Pendulum::Make(std::move(layout).value());
    if (!env) return std::move(env).error();
    return std::unique_ptr<Env>(std::move(env).value());
  }
  std::string known;
  for (const auto& n : EnvNames()) known += (known.empty() ? "" : ", ") + n;
  return MakeError(ErrorCode::kInvalidValue, "--env: '" + name + "' unknown (known: " + known + ")");
}

}  // namespace pbppo::envs
