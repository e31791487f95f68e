#include "sim_hil/scenarios/auv_nav_task.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>

#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::sim {
namespace {

using robot::YamlFields;

constexpr double kPi = 3.14159265358979323846;
// Geodesic progress: grid spacing (the narrowest passage of the layouts leaves 1.6 m of free
// space: six nodes across) and how far ahead along the path its bearing looks.
constexpr double kGeodesicCellM = 0.25;
constexpr double kGeodesicLookaheadM = 2.0;
// The route signal: the path keeps off obstacles (2 m beyond l_safe at up to 4 extra per metre,
// as task.geodesic_margin 2:4) and points up to 3 m ahead along it, no further than a straight
// line keeps 1 m beyond l_safe (or the path's own clearance where that is less) so that it does
// not cut corners.
constexpr double kRouteMarginM = 2.0;
constexpr double kRouteMarginCost = 4.0;
constexpr double kRouteLookaheadM = 3.0;
constexpr double kRouteAimBeyondSafeM = 1.0;
// The sonar map (route_map: chart_and_sonar): a return within this distance of a charted
// surface is that surface; any other marks its point as an obstacle, one per grid cell.
constexpr double kChartedEchoM = 0.1;

}  // namespace

bool ParseAuvProgress(const std::string& name, AuvTaskParams::Progress* out) noexcept {
  if (name == "euclidean") {
    *out = AuvTaskParams::Progress::kEuclidean;
  } else if (name == "geodesic") {
    *out = AuvTaskParams::Progress::kGeodesic;
  } else {
    return false;
  }
  return true;
}

Result<SonarParams> ParseSonarParams(const YAML::Node& plant, const std::string& path) {
  YamlFields f(path);
  YAML::Node n;
  if (auto st = f.Map(plant, "sonar", "", &n); !st) return st.error();
  if (auto st = f.Keys(n, "sonar", {"beams", "fov_deg", "max_range_m", "beam_width_deg", "rays_per_beam"}); !st)
    return st.error();
  SonarParams s;
  long beams = 0;
  double fov_deg = 0.0;
  if (auto st = f.Integer(n, "beams", "sonar", 1, 256, &beams); !st) return st.error();
  if (auto st = f.Number(n, "fov_deg", "sonar", 0.0, 360.0, &fov_deg); !st) return st.error();
  if (auto st = f.Number(n, "max_range_m", "sonar", 0.1, 1000.0, &s.max_range_m); !st) return st.error();
  s.beams = static_cast<int>(beams);
  s.fov_rad = fov_deg * kPi / 180.0;
  // Optional: a thin ray per beam by default.
  if (n["beam_width_deg"]) {
    double width_deg = 0.0;
    if (auto st = f.Number(n, "beam_width_deg", "sonar", 0.0, 90.0, &width_deg); !st) return st.error();
    s.beam_width_rad = width_deg * kPi / 180.0;
  }
  if (n["rays_per_beam"]) {
    long rays = 0;
    if (auto st = f.Integer(n, "rays_per_beam", "sonar", 1, 64, &rays); !st) return st.error();
    s.rays_per_beam = static_cast<int>(rays);
  }
  return s;
}

Result<AuvTaskParams> ParseAuvTaskParams(const YAML::Node& plant, const std::string& path, double depth_m) {
  YamlFields f(path);
  YAML::Node n;
  if (auto st = f.Map(plant, "task", "", &n); !st) return st.error();
  if (auto st = f.Keys(n, "task",
                       {"safe_distance_m", "target_radius_m", "episode_time_s", "weights", "collision_penalty",
                        "goal_reward", "step_penalty", "distance_gain", "bearing_gain", "progress", "geodesic_margin",
                        "clearance_penalty", "route_map"});
      !st)
    return st.error();
  AuvTaskParams t;
  if (!(depth_m >= 0.0 && depth_m <= 1e4))
    return f.Fail("task", "the mission depth " + YamlFields::Num(depth_m) + " m is outside [0, 10000]");
  t.depth_m = depth_m;
  if (auto st = f.Number(n, "safe_distance_m", "task", 0.0, 100.0, &t.safe_distance_m); !st) return st.error();
  if (auto st = f.Number(n, "target_radius_m", "task", 0.01, 100.0, &t.target_radius_m); !st) return st.error();
  if (auto st = f.Number(n, "episode_time_s", "task", 1e-3, 1e6, &t.episode_time_s); !st) return st.error();
  for (auto [k, out] : {std::pair<const char*, double*>{"collision_penalty", &t.collision_penalty},
                        {"goal_reward", &t.goal_reward},
                        {"step_penalty", &t.step_penalty},
                        {"distance_gain", &t.distance_gain},
                        {"bearing_gain", &t.bearing_gain}}) {
    if (auto st = f.Number(n, k, "task", 0.0, 1e6, out); !st) return st.error();
  }
  if (n["progress"]) {  // optional: the paper's euclidean by default
    std::string progress;
    if (auto st = f.Text(n, "progress", "task", &progress); !st) return st.error();
    if (!ParseAuvProgress(progress, &t.progress))
      return f.Fail("task.progress", "'" + progress + "' is not euclidean or geodesic");
  }
  if (n["route_map"]) {  // optional: the chart by default
    std::string map;
    if (auto st = f.Text(n, "route_map", "task", &map); !st) return st.error();
    if (map == "chart")
      t.route_map = AuvTaskParams::RouteMap::kChart;
    else if (map == "chart_and_sonar")
      t.route_map = AuvTaskParams::RouteMap::kChartAndSonar;
    else
      return f.Fail("task.route_map", "'" + map + "' is not chart or chart_and_sonar");
  }
  // Optional {distance_m, <second>} maps, each number in [0, 100]; absent: off (both stay 0).
  auto optional_pair = [&](const char* key, const char* second, double* distance_m, double* value) -> Status {
    if (!n[key]) return {};
    YAML::Node m;
    const std::string where = std::string("task.") + key;
    if (auto st = f.Map(n, key, "task", &m); !st) return st;
    if (auto st = f.Keys(m, where, {"distance_m", second}); !st) return st;
    if (auto st = f.Number(m, "distance_m", where, 0.0, 100.0, distance_m); !st) return st;
    return f.Number(m, second, where, 0.0, 100.0, value);
  };
  if (auto st = optional_pair("geodesic_margin", "cost", &t.geodesic_margin_m, &t.geodesic_margin_cost); !st)
    return st.error();
  if (auto st = optional_pair("clearance_penalty", "per_step", &t.clearance_penalty_m, &t.clearance_penalty_per_step);
      !st)
    return st.error();
  YAML::Node w;
  if (auto st = f.Map(n, "weights", "task", &w); !st) return st.error();
  if (auto st = f.Keys(w, "task.weights", {"collision", "goal", "progress"}); !st) return st.error();
  if (auto st = f.Number(w, "collision", "task.weights", 0.0, 1e6, &t.weight_collision); !st) return st.error();
  if (auto st = f.Number(w, "goal", "task.weights", 0.0, 1e6, &t.weight_goal); !st) return st.error();
  if (auto st = f.Number(w, "progress", "task.weights", 0.0, 1e6, &t.weight_progress); !st) return st.error();
  return t;
}

Result<AuvTaskConfig> MakeAuvTaskConfig(const robot::RobotModel& model, const std::string& layout) {
  auto plant = model.Document("plant");
  if (!plant) return std::move(plant).error();
  const robot::RobotDocument& doc = **plant;
  auto depth = model.Parameter("depth_m");
  if (!depth) return std::move(depth).error();
  auto layout_doc = model.Document("layouts." + layout);
  if (!layout_doc) {
    std::string known;
    for (const auto& n : model.DocumentGroup("layouts")) known += (known.empty() ? "" : ", ") + n;
    return MakeError(ErrorCode::kInvalidValue, "layout '" + layout + "' unknown (" + model.path + ": " + known + ")");
  }
  if (!model.io) return MakeError(ErrorCode::kMismatch, model.path + ": files: no io_layout");
  AuvTaskConfig c;
  auto p = ParseAuvParams(doc.yaml, doc.path, model.policy_period_s);
  if (!p) return std::move(p).error();
  c.plant = *p;
  auto sonar = ParseSonarParams(doc.yaml, doc.path);
  if (!sonar) return std::move(sonar).error();
  c.sonar = *sonar;
  auto task = ParseAuvTaskParams(doc.yaml, doc.path, *depth);
  if (!task) return std::move(task).error();
  c.task = *task;
  auto l = ParseAuvLayout((*layout_doc)->yaml, (*layout_doc)->path);
  if (!l) return std::move(l).error();
  c.layout = std::move(*l);
  c.io = *model.io;
  auto signals = robot::SignalProgram::Create(model, robot::SignalNames(model));
  if (!signals) return std::move(signals).error();
  c.signals = std::move(*signals);
  AuvFieldIndex& f = c.fields;
  f.count = static_cast<std::uint32_t>(model.fields.size());
  Status st;
  auto index = [&](const std::string& name, std::uint32_t* out) {
    const int k = model.FieldIndex(name);
    if (k < 0 && st)
      st = MakeError(ErrorCode::kMismatch,
                     model.path + ": the AUV task measures '" + name + "', the robot has no such field");
    *out = k < 0 ? 0 : static_cast<std::uint32_t>(k);
  };
  const std::pair<const char*, std::uint32_t*> named[] = {{"tick", &f.tick},
                                                          {"x_m", &f.x},
                                                          {"y_m", &f.y},
                                                          {"depth_m", &f.depth},
                                                          {"roll_rad", &f.roll},
                                                          {"pitch_rad", &f.pitch},
                                                          {"yaw_rad", &f.yaw},
                                                          {"surge_mps", &f.surge},
                                                          {"sway_mps", &f.sway},
                                                          {"heave_mps", &f.heave},
                                                          {"roll_rate_radps", &f.roll_rate},
                                                          {"pitch_rate_radps", &f.pitch_rate},
                                                          {"yaw_rate_radps", &f.yaw_rate},
                                                          {"target_distance_m", &f.target_distance},
                                                          {"target_bearing_rad", &f.target_bearing},
                                                          {"route_bearing_rad", &f.route_bearing},
                                                          {"clearance_m", &f.clearance},
                                                          {"target_index", &f.target_index},
                                                          {"target_x_m", &f.target_x},
                                                          {"target_y_m", &f.target_y},
                                                          {"mission_complete", &f.mission_complete},
                                                          {"episode_end", &f.episode_end},
                                                          {"sonar_beams", &f.sonar_beams}};
  for (const auto& [name, out] : named) index(name, out);
  f.sonar.assign(static_cast<std::size_t>(c.sonar.beams), 0);
  for (std::size_t i = 0; i < f.sonar.size(); ++i)
    index(robot::ExpandIndex("sonar_{i}_m", static_cast<std::uint32_t>(i)), &f.sonar[i]);
  if (!st) return st.error();
  return c;
}

Result<AuvNavTask> AuvNavTask::Create(const AuvTaskConfig& config) {
  auto plant = AuvPlant::Create(config.plant);
  if (!plant) return std::move(plant).error();
  if (config.sonar.beams < 1) return MakeError(ErrorCode::kInvalidValue, "sonar.beams must be >= 1");
  if (config.layout.targets.empty())
    return MakeError(ErrorCode::kInvalidValue, "layout '" + config.layout.name + "': no targets");
  AuvNavTask t(config, std::move(*plant));
  const std::string where = "io layout '" + config.io.robot + "'";
  if (config.io.robot != "auv")
    return MakeError(ErrorCode::kMismatch, where + ": robot is '" + config.io.robot + "', expected 'auv'");
  auto builder = robot::ObservationBuilder::Create(config.io, config.signals.names());
  if (!builder) return std::move(builder).error();
  t.observe_ = std::move(*builder);
  if (config.io.actions.size() != 2)
    return MakeError(ErrorCode::kMismatch, where + ": " + std::to_string(config.io.actions.size()) +
                                               " actions, the AUV task takes 2 (surge_speed, yaw_rate)");
  t.action_of_ = {-1, -1};
  for (std::size_t i = 0; i < 2; ++i) {
    const auto& a = config.io.actions[i];
    const int slot = a.command == "surge_speed" ? 0 : a.command == "yaw_rate" ? 1 : -1;
    if (slot < 0)
      return MakeError(ErrorCode::kMismatch, where + ": actions[" + std::to_string(i) + "] '" + a.name +
                                                 "': command '" + a.command + "' is not one of surge_speed, yaw_rate");
    if (t.action_of_[static_cast<std::size_t>(slot)] >= 0)
      return MakeError(ErrorCode::kMismatch,
                       where + ": actions[" + std::to_string(i) + "]: command '" + a.command + "' appears twice");
    t.action_of_[static_cast<std::size_t>(slot)] = static_cast<int>(i);
  }
  t.act_ = robot::ActionMapper::Create(config.io);
  t.io_hash_ = config.io.Hash();
  t.obs_size_ = config.io.observation_size();
  t.last_obs_.assign(t.obs_size_, 0.0f);
  t.fields_.assign(config.fields.count, 0.0);
  t.signals_.assign(config.signals.size(), 0.0);
  t.last_action_.assign(config.io.actions.size(), 0.0f);
  t.sonar_.assign(static_cast<std::size_t>(config.sonar.beams), 0.0);
  t.chart_.emplace(config.layout.world.arena, kGeodesicCellM);
  t.chart_->SetObstacles(config.layout.world);
  t.route_.emplace(config.layout.world.arena, kGeodesicCellM);
  t.route_->CopyObstacles(*t.chart_);
  if (config.task.route_map == AuvTaskParams::RouteMap::kChartAndSonar) {
    t.rays_.assign(static_cast<std::size_t>(config.sonar.beams * SonarRaysPerBeam(config.sonar)), 0.0);
    t.mapped_.assign(static_cast<std::size_t>(t.chart_->nx()) * static_cast<std::size_t>(t.chart_->ny()), 0);
  }
  t.max_steps_ = std::lround(std::ceil(config.task.episode_time_s / config.plant.control_period_s - 1e-9));
  t.world_ = config.layout.world;
  t.world_.circles.reserve(config.layout.world.circles.size() +
                           static_cast<std::size_t>(config.layout.random_obstacles.count[1]));
  return t;
}

AuvNavTask::AuvNavTask(const AuvTaskConfig& config, AuvPlant plant) : config_(config), plant_(std::move(plant)) {}

void AuvNavTask::PlaceRandomObstacles(Rng& rng) {
  const AuvRandomObstacles& r = config_.layout.random_obstacles;
  const AuvStartRegion& s = config_.layout.start;
  const Arena& a = world_.arena;
  const auto span = static_cast<std::uint64_t>(r.count[1] - r.count[0] + 1);
  const int count = r.count[0] + static_cast<int>(rng.Below(span));
  constexpr int kAttempts = 64;
  for (int k = 0; k < count; ++k) {
    for (int attempt = 0; attempt < kAttempts; ++attempt) {
      const double radius = rng.Uniform(r.radius_m[0], r.radius_m[1]);
      const double keep = radius + r.clearance_m;
      if (a.x_max_m - a.x_min_m <= 2 * keep || a.y_max_m - a.y_min_m <= 2 * keep) break;
      const double x = rng.Uniform(a.x_min_m + keep, a.x_max_m - keep);
      const double y = rng.Uniform(a.y_min_m + keep, a.y_max_m - keep);
      // Away from walls and obstacles (passages stay at least clearance_m wide) ...
      bool ok = Clearance(world_, x, y) >= keep;
      // ... from every target ...
      for (const auto& t : config_.layout.targets) ok = ok && std::hypot(x - t[0], y - t[1]) >= keep;
      // ... and from the start region (distance to a rectangle).
      const double dx = std::max({s.x_m[0] - x, 0.0, x - s.x_m[1]});
      const double dy = std::max({s.y_m[0] - y, 0.0, y - s.y_m[1]});
      ok = ok && std::hypot(dx, dy) >= keep;
      if (ok) {
        world_.circles.push_back(Circle{x, y, radius});
        ++stats_.random_obstacles;
        break;
      }
    }
  }
}

void AuvNavTask::ExploringStart(Rng& rng, AuvPose& pose) {
  const auto n = static_cast<std::uint64_t>(config_.layout.targets.size());
  const int target = static_cast<int>(rng.Below(n));
  const auto& t = config_.layout.targets[static_cast<std::size_t>(target)];
  const Arena& a = world_.arena;
  const double keep = config_.task.safe_distance_m + 1.0;
  for (int attempt = 0; attempt < 256; ++attempt) {
    const double x = rng.Uniform(a.x_min_m, a.x_max_m), y = rng.Uniform(a.y_min_m, a.y_max_m);
    const double yaw = rng.Uniform(-std::numbers::pi, std::numbers::pi);
    if (Clearance(world_, x, y) < keep || std::hypot(x - t[0], y - t[1]) < config_.task.target_radius_m + 3.0) continue;
    pose.x_m = x;
    pose.y_m = y;
    pose.yaw_rad = yaw;
    target_ = target;
    stats_.exploring_start = true;
    return;
  }
  // No free spot found (a crowded layout): the ordinary start drawn above stands.
}

void AuvNavTask::MapReturns() {
  const AuvState& s = plant_.State();
  const SonarParams& p = config_.sonar;
  const Arena& a = config_.layout.world.arena;
  const int rays = SonarRaysPerBeam(p), nx = chart_->nx(), ny = chart_->ny();
  // Beyond l_safe + margin a point changes neither a node's weight nor whether it is free.
  const double reach = config_.task.safe_distance_m + kRouteMarginM + kGeodesicCellM;
  bool changed = false;
  for (int i = 0; i < p.beams; ++i) {
    for (int k = 0; k < rays; ++k) {
      const double r = rays_[static_cast<std::size_t>(i * rays + k)];
      if (!(r < p.max_range_m)) continue;  // no echo
      const double angle = s.yaw_rad + SonarRayAngle(p, i, k);
      const double hx = s.x_m + r * std::cos(angle), hy = s.y_m + r * std::sin(angle);
      if (Clearance(config_.layout.world, hx, hy) < kChartedEchoM) continue;  // the chart has it
      const int ci = std::clamp(static_cast<int>(std::lround((hx - a.x_min_m) / kGeodesicCellM)), 0, nx - 1);
      const int cj = std::clamp(static_cast<int>(std::lround((hy - a.y_min_m) / kGeodesicCellM)), 0, ny - 1);
      std::uint8_t& seen =
          mapped_[static_cast<std::size_t>(cj) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(ci)];
      if (seen) continue;
      seen = 1;
      ++stats_.mapped_returns;
      changed = route_->AddPoint(hx, hy, reach) || changed;
    }
  }
  if (changed) route_target_ = -1;
}

void AuvNavTask::Measure() {
  const AuvState& s = plant_.State();
  const bool map_sonar = config_.task.route_map == AuvTaskParams::RouteMap::kChartAndSonar;
  SonarScan(world_, config_.sonar, s.x_m, s.y_m, s.yaw_rad, sonar_.data(), map_sonar ? rays_.data() : nullptr);
  if (map_sonar) MapReturns();
  const auto current =
      static_cast<std::size_t>(std::min<int>(target_, static_cast<int>(config_.layout.targets.size()) - 1));
  const auto& t = config_.layout.targets[current];
  l_at_ = std::hypot(t[0] - s.x_m, t[1] - s.y_m);
  phi_at_ = WrapAngle(std::atan2(t[1] - s.y_m, t[0] - s.x_m) - s.yaw_rad);
  clearance_ = Clearance(world_, s.x_m, s.y_m);
  progress_l_ = l_at_;
  progress_phi_ = phi_at_;
  if (route_target_ != static_cast<int>(current)) {
    route_->Solve(config_.task.safe_distance_m, t[0], t[1], kRouteMarginM, kRouteMarginCost);
    route_target_ = static_cast<int>(current);
  }
  const double route_angle =
      route_->PathAngle(s.x_m, s.y_m, kRouteLookaheadM, config_.task.safe_distance_m + kRouteAimBeyondSafeM);
  route_phi_ = std::isfinite(route_angle) ? WrapAngle(route_angle - s.yaw_rad) : phi_at_;
  if (config_.task.progress == AuvTaskParams::Progress::kGeodesic) {
    if (!geodesic_) geodesic_.emplace(world_.arena, kGeodesicCellM);
    if (geodesic_target_ != target_) {
      geodesic_->Compute(world_, config_.task.safe_distance_m, t[0], t[1], config_.task.geodesic_margin_m,
                         config_.task.geodesic_margin_cost);
      geodesic_target_ = target_;
    }
    // Outside the free space (only at a collision) or walled off: the straight line stands.
    const double g = geodesic_->Distance(s.x_m, s.y_m);
    const double a = geodesic_->PathAngle(s.x_m, s.y_m, kGeodesicLookaheadM);
    if (std::isfinite(g) && std::isfinite(a)) {
      progress_l_ = g;
      progress_phi_ = WrapAngle(a - s.yaw_rad);
    }
  }
}

void AuvNavTask::WriteObservation(bool first, float* obs) {
  // The controller's path: the task's sensor sample (what the HIL publishes) as the robot model's
  // fields, the robot's signals (runtime/robot/signals.hpp), the IO layout (robot::ObservationBuilder).
  FillSensorFields(fields_);
  config_.signals.Compute(fields_, last_action_, signals_.data());
  observe_.Build(signals_.data(), first, last_obs_.data());
  std::copy(last_obs_.begin(), last_obs_.end(), obs);
}

void AuvNavTask::Reset(std::uint64_t seed, float* obs) {
  Rng rng(seed);
  if (stats_.mapped_returns > 0) {  // the last episode's sonar map: back to the chart
    std::fill(mapped_.begin(), mapped_.end(), std::uint8_t{0});
    route_->CopyObstacles(*chart_);
    route_target_ = -1;
  }
  stats_ = AuvEpisodeStats{};
  world_.circles.resize(config_.layout.world.circles.size());
  PlaceRandomObstacles(rng);
  geodesic_target_ = -1;  // the world changed
  // Start pose: uniform in the start region, redrawn while closer than l_safe + 0.5 m to anything.
  const AuvStartRegion& s = config_.layout.start;
  AuvPose pose;
  pose.z_m = -config_.task.depth_m;
  for (int attempt = 0; attempt < 64; ++attempt) {
    pose.x_m = rng.Uniform(s.x_m[0], s.x_m[1]);
    pose.y_m = rng.Uniform(s.y_m[0], s.y_m[1]);
    pose.yaw_rad = rng.Uniform(s.yaw_rad[0], s.yaw_rad[1]);
    if (Clearance(world_, pose.x_m, pose.y_m) >= config_.task.safe_distance_m + 0.5) break;
  }
  target_ = 0;
  if (exploring_starts_ > 0.0 && rng.Uniform(0.0, 1.0) < exploring_starts_) ExploringStart(rng, pose);
  physics_steps_ += plant_.physics_steps();
  plant_.Reset(pose);
  plant_.SetCommand(0.0, 0.0);
  stats_.first_target = target_;
  stats_.targets_reached = target_;
  v_cmd_ = w_cmd_ = 0.0;
  done_ = terminated_ = truncated_ = false;
  Measure();
  stats_.min_clearance_m = clearance_;
  WriteObservation(true, obs);
}

AuvStepResult AuvNavTask::Step(const float* action, float* obs) {
  if (done_) return StepCommand(0.0, 0.0, obs);
  // Action -> command through the IO layout: clamp(a * scale + offset, low, high).
  double cmd[2];
  stats_.nonfinite_actions += std::popcount(act_.Map(action, cmd));
  // The previous action as the controller's policy source sees it: (command - offset) / scale.
  for (std::size_t k = 0; k < last_action_.size() && k < 2; ++k) {
    const robot::ActionElement& a = config_.io.actions[k];
    last_action_[k] = static_cast<float>((cmd[k] - a.offset) / a.scale);
  }
  return StepCommand(cmd[static_cast<std::size_t>(action_of_[0])], cmd[static_cast<std::size_t>(action_of_[1])], obs);
}

AuvStepResult AuvNavTask::StepCommand(double surge_speed_mps, double yaw_rate_radps, float* obs) {
  AuvStepResult r;
  if (done_) {
    r.terminated = terminated_;
    r.truncated = truncated_;
    std::copy(last_obs_.begin(), last_obs_.end(), obs);
    return r;
  }
  for (double* c : {&surge_speed_mps, &yaw_rate_radps}) {
    if (!std::isfinite(*c)) {
      *c = 0.0;
      ++stats_.nonfinite_actions;
    }
  }
  v_cmd_ = surge_speed_mps;
  w_cmd_ = yaw_rate_radps;
  plant_.SetCommand(v_cmd_, w_cmd_);

  const double l_prev = progress_l_, phi_prev = progress_phi_;
  plant_.AdvanceControlPeriod();
  ++stats_.steps;
  Measure();
  const AuvTaskParams& p = config_.task;
  r.r_progress = -p.step_penalty + p.distance_gain * (l_prev - progress_l_) +
                 p.bearing_gain * (std::abs(phi_prev) - std::abs(progress_phi_));
  stats_.min_clearance_m = std::min(stats_.min_clearance_m, clearance_);
  if (p.clearance_penalty_m > 0.0 && p.clearance_penalty_per_step > 0.0)
    r.r_clearance = -p.clearance_penalty_per_step *
                    std::clamp(1.0 - (clearance_ - p.safe_distance_m) / p.clearance_penalty_m, 0.0, 1.0);
  if (clearance_ < p.safe_distance_m) {
    r.r_collision = -p.collision_penalty;
    r.events.collision = true;
    stats_.collided = true;
    r.terminated = true;
  }
  if (l_at_ < p.target_radius_m) {
    r.r_goal = p.goal_reward;
    r.events.target_reached = target_;
    ++target_;
    stats_.targets_reached = target_;
    if (target_ == static_cast<int>(config_.layout.targets.size())) {
      r.events.all_targets = true;
      stats_.success = true;
      r.terminated = true;
    } else {
      Measure();  // l_AT and phi now refer to the next target
    }
  }
  if (!r.terminated && stats_.steps >= max_steps_) {
    r.truncated = true;
    stats_.truncated = true;
  }
  r.reward =
      p.weight_collision * r.r_collision + p.weight_goal * r.r_goal + p.weight_progress * r.r_progress + r.r_clearance;
  stats_.episode_return += r.reward;
  stats_.time_s = plant_.State().time_s;
  done_ = r.terminated || r.truncated;
  terminated_ = r.terminated;
  truncated_ = r.truncated;
  WriteObservation(false, obs);
  return r;
}

void AuvNavTask::FillSensorFields(std::span<double> f) const {
  const AuvState& s = plant_.State();
  const AuvFieldIndex& i = config_.fields;
  f[i.tick] = static_cast<double>(stats_.steps);
  f[i.x] = s.x_m;
  f[i.y] = s.y_m;
  f[i.depth] = -s.z_m;
  f[i.roll] = s.roll_rad;
  f[i.pitch] = s.pitch_rad;
  f[i.yaw] = WrapAngle(s.yaw_rad);
  f[i.surge] = s.u_mps;
  f[i.sway] = s.v_mps;
  f[i.heave] = s.w_mps;
  f[i.roll_rate] = s.p_radps;
  f[i.pitch_rate] = s.q_radps;
  f[i.yaw_rate] = s.r_radps;
  f[i.sonar_beams] = static_cast<double>(sonar_.size());
  for (std::size_t k = 0; k < i.sonar.size(); ++k) f[i.sonar[k]] = static_cast<float>(sonar_[k]);
  const int last = static_cast<int>(config_.layout.targets.size()) - 1;
  const auto& t = config_.layout.targets[static_cast<std::size_t>(std::min(target_, last))];
  f[i.target_index] = target_;
  f[i.target_x] = t[0];
  f[i.target_y] = t[1];
  f[i.target_distance] = l_at_;
  f[i.target_bearing] = phi_at_;
  f[i.route_bearing] = route_phi_;
  f[i.clearance] = clearance_;
  f[i.mission_complete] = stats_.success ? 1.0 : 0.0;
  f[i.episode_end] = done_ ? 1.0 : 0.0;
}

long StepRandomly(AuvNavTask& task, Rng& rng, long steps, float* obs, std::uint64_t* next_seed) {
  long episodes = 0;
  float action[2];
  for (long k = 0; k < steps; ++k) {
    action[0] = static_cast<float>(rng.Uniform(-1.0, 1.0));
    action[1] = static_cast<float>(rng.Uniform(-1.0, 1.0));
    const AuvStepResult r = task.Step(action, obs);
    if (r.terminated || r.truncated) {
      task.Reset((*next_seed)++, obs);
      ++episodes;
    }
  }
  return episodes;
}

}  // namespace pbppo::sim
