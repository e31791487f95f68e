#include "policies/envs/auv_nav.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <tuple>

namespace pbppo::envs {
namespace {

// The layouts under models/<dir>/auv/layouts/ (mixed draws from them).
bool IsLayoutName(const std::string& name) {
  return name == "easy" || name == "medium" || name == "hard";
}

}  // namespace

Result<std::optional<sim::AuvTaskParams::Progress>> AuvNav::ProgressFor(const std::string& spec,
                                                                        const std::string& layout) {
  auto bad = [&](const std::string& why) { return MakeError(ErrorCode::kInvalidValue, "'" + spec + "': " + why); };
  std::optional<sim::AuvTaskParams::Progress> result;
  if (spec.empty()) return result;
  if (spec.find('=') == std::string::npos) {
    sim::AuvTaskParams::Progress mode{};
    if (!sim::ParseAuvProgress(spec, &mode)) return bad("unknown (euclidean, geodesic, or LAYOUT=MODE,...)");
    return std::optional{mode};
  }
  std::vector<std::string> seen;
  std::size_t start = 0;
  while (start <= spec.size()) {
    const std::size_t end = std::min(spec.find(',', start), spec.size());
    const std::string part = spec.substr(start, end - start);
    const std::size_t eq = part.find('=');
    if (eq == std::string::npos) return bad("'" + part + "' is not LAYOUT=MODE");
    const std::string name = part.substr(0, eq), mode_name = part.substr(eq + 1);
    if (!IsLayoutName(name)) return bad("layout '" + name + "' unknown (easy, medium, hard)");
    if (std::find(seen.begin(), seen.end(), name) != seen.end()) return bad("layout '" + name + "' given twice");
    seen.push_back(name);
    sim::AuvTaskParams::Progress mode{};
    if (!sim::ParseAuvProgress(mode_name, &mode))
      return bad("'" + mode_name + "' for " + name + " is not euclidean or geodesic");
    if (name == layout) result = mode;
    start = end + 1;
  }
  return result;
}

Result<std::optional<std::pair<double, double>>> AuvNav::ParseGeodesicMargin(const std::string& spec) {
  return ParseNumberPair(spec, "DISTANCE_M:COST (e.g. 2:4)", {"distance", "cost"});
}

Result<std::optional<std::pair<double, double>>> AuvNav::ParseClearancePenalty(const std::string& spec) {
  return ParseNumberPair(spec, "DISTANCE_M:PER_STEP (e.g. 1.5:1)", {"distance", "per-step cost"});
}

Result<std::optional<std::pair<double, double>>> AuvNav::ParseNumberPair(const std::string& spec,
                                                                         const std::string& form,
                                                                         const std::array<const char*, 2>& what) {
  std::optional<std::pair<double, double>> result;
  if (spec.empty()) return result;
  const std::size_t colon = spec.find(':');
  if (colon == std::string::npos) return MakeError(ErrorCode::kInvalidValue, "'" + spec + "' is not " + form);
  double v[2] = {0, 0};
  const std::string parts[2] = {spec.substr(0, colon), spec.substr(colon + 1)};
  for (std::size_t k = 0; k < 2; ++k) {
    char* end = nullptr;
    v[k] = std::strtod(parts[k].c_str(), &end);
    if (parts[k].empty() || end != parts[k].c_str() + parts[k].size() || !(v[k] >= 0 && v[k] <= 100))
      return MakeError(ErrorCode::kInvalidValue,
                       "'" + spec + "': " + what[k] + " '" + parts[k] + "' is not a number in [0, 100]");
  }
  result = std::pair{v[0], v[1]};
  return result;
}

Result<std::unique_ptr<AuvNav>> AuvNav::Make(const AuvNavOptions& o) {
  auto bad = [](const char* flag, const std::string& why) {
    return MakeError(ErrorCode::kInvalidValue, std::string(flag) + ": " + why);
  };
  if (auto check = ProgressFor(o.progress, ""); !check) return bad("--progress", check.error().message);
  auto margin = ParseGeodesicMargin(o.geodesic_margin);
  if (!margin) return bad("--geodesic-margin", margin.error().message);
  auto clearance = ParseClearancePenalty(o.clearance_penalty);
  if (!clearance) return bad("--clearance-penalty", clearance.error().message);
  if (o.extra_obstacles < 0 || o.extra_obstacles > 16)
    return bad("--extra-obstacles", std::to_string(o.extra_obstacles) + " is not in [0, 16]");
  if (!(o.exploring_starts >= 0 && o.exploring_starts <= 1)) {
    char v[32];
    std::snprintf(v, sizeof v, "%g", o.exploring_starts);
    return bad("--exploring-starts", std::string(v) + " is not in [0, 1]");
  }
  const std::string& layout_name = o.layout;
  std::vector<std::string> names;
  if (layout_name == "mixed") {
    // Hard twice: it needs the most experience (a serpentine of three corridors).
    names = {"easy", "medium", "hard", "hard"};
  } else if (IsLayoutName(layout_name)) {
    names = {layout_name};
  } else {
    return bad("--layout", "'" + layout_name + "' unknown (easy, medium, hard, mixed)");
  }
  // The robot is read once; every layout's configuration comes from that one model.
  std::shared_ptr<const robot::RobotModel> model = o.robot_model;
  if (!model) {
    auto loaded = robot::LoadRobotModel((o.models_dir.empty() ? DefaultModelsDir() : o.models_dir) + "/auv/robot.yaml");
    if (!loaded) return std::move(loaded).error();
    model = std::make_shared<const robot::RobotModel>(std::move(loaded).value());
  }
  std::vector<std::shared_ptr<const sim::AuvTaskConfig>> configs;
  for (const auto& n : names) {
    auto cfg = sim::MakeAuvTaskConfig(*model, n);
    if (!cfg) return std::move(cfg).error();
    if (const auto mode = ProgressFor(o.progress, n).value()) cfg->task.progress = *mode;
    if (*margin) std::tie(cfg->task.geodesic_margin_m, cfg->task.geodesic_margin_cost) = **margin;
    if (*clearance) std::tie(cfg->task.clearance_penalty_m, cfg->task.clearance_penalty_per_step) = **clearance;
    for (int& count : cfg->layout.random_obstacles.count) count += o.extra_obstacles;
    configs.push_back(std::make_shared<const sim::AuvTaskConfig>(std::move(cfg).value()));
  }
  auto env = Make(std::move(configs), "auv-nav:" + layout_name);
  if (env) {
    (*env)->robot_model_ = std::move(model);
    (*env)->set_exploring_starts(o.exploring_starts);
  }
  return env;
}

Result<std::unique_ptr<AuvNav>> AuvNav::Make(std::vector<std::shared_ptr<const sim::AuvTaskConfig>> configs,
                                             const std::string& name) {
  if (configs.empty()) return MakeError(ErrorCode::kInvalidValue, "auv-nav: no layout");
  std::vector<sim::AuvNavTask> tasks;
  for (const auto& config : configs) {
    if (config->io.Hash() != configs[0]->io.Hash())
      return MakeError(ErrorCode::kMismatch, "auv-nav: layouts '" + configs[0]->layout.name + "' and '" +
                                                 config->layout.name + "' come with different io layouts");
    auto task = sim::AuvNavTask::Create(*config);
    if (!task) return std::move(task).error();
    tasks.push_back(std::move(task).value());
  }
  // The policy acts in [-1, 1]; the layout's map must cover exactly the command range there,
  // otherwise part of the action box would be dead (clipped) or part of the commands unreachable.
  for (const auto& a : configs[0]->io.actions) {
    const double lo = a.offset - std::fabs(a.scale), hi = a.offset + std::fabs(a.scale);
    if (a.scale == 0.0 || std::fabs(lo - a.low) > 1e-6 * (1 + std::fabs(a.low)) ||
        std::fabs(hi - a.high) > 1e-6 * (1 + std::fabs(a.high))) {
      return MakeError(ErrorCode::kMismatch, "auv-nav: io layout action '" + a.name +
                                                 "': scale and offset must map [-1, 1] onto [low, high] = [" +
                                                 std::to_string(a.low) + ", " + std::to_string(a.high) + "]");
    }
  }
  return std::unique_ptr<AuvNav>(new AuvNav(std::move(configs), std::move(tasks), name));
}

AuvNav::AuvNav(std::vector<std::shared_ptr<const sim::AuvTaskConfig>> configs, std::vector<sim::AuvNavTask> tasks,
               std::string name)
    : configs_(std::move(configs)), tasks_(std::move(tasks)), name_(std::move(name)) {}

std::uint32_t AuvNav::max_episode_steps() const noexcept {
  return static_cast<std::uint32_t>(tasks_[0].max_episode_steps());
}

void AuvNav::set_exploring_starts(double probability) noexcept {
  exploring_starts_ = probability;
  for (auto& t : tasks_) t.set_exploring_starts(probability);
}

void AuvNav::Reset(Rng& rng, std::span<float> observation) {
  current_ = tasks_.size() > 1 ? static_cast<std::size_t>(rng.Below(tasks_.size())) : 0;
  tasks_[current_].Reset(rng.Next(), observation.data());
}

StepResult AuvNav::Step(std::span<const float> action, std::span<float> observation) {
  float a[2];
  for (std::size_t i = 0; i < 2; ++i)
    a[i] = std::isfinite(action[i]) ? std::clamp(action[i], low_[i], high_[i]) : action[i];
  const sim::AuvStepResult r = tasks_[current_].Step(a, observation.data());
  StepResult s;
  s.reward = r.reward;
  s.terminated = r.terminated;
  s.truncated = r.truncated;
  return s;
}

std::unique_ptr<Env> AuvNav::Clone() const {
  // Create() succeeded for the same configurations when this instance was made.
  std::vector<sim::AuvNavTask> tasks;
  for (const auto& c : configs_) tasks.push_back(std::move(sim::AuvNavTask::Create(*c)).value());
  auto env = std::unique_ptr<AuvNav>(new AuvNav(configs_, std::move(tasks), name_));
  env->robot_model_ = robot_model_;
  env->set_exploring_starts(exploring_starts_);
  return env;
}

EpisodeInfo AuvNav::episode_info() const noexcept {
  const sim::AuvEpisodeStats& s = tasks_[current_].stats();
  EpisodeInfo e;
  e.available = !s.exploring_start;
  e.success = s.success;
  e.failure = s.collided;
  e.goals = s.targets_reached;
  e.time_s = s.time_s;
  return e;
}

}  // namespace pbppo::envs
