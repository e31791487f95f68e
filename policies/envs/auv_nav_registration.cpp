// auv-nav as pbppo knows it: its flags, how they build it, and what pbppo eval adds to its
// episodes (--plot: the trajectories over the map; --trajectories: every step; --outcomes: one row
// per episode).
#include <array>
#include <fstream>
#include <vector>

#include "policies/envs/auv_nav.hpp"
#include "report/plots.hpp"
#include "sim_hil/scenarios/auv_sonar.hpp"

namespace pbppo::envs {
namespace {

struct EpisodeTrace {
  std::vector<std::array<double, 2>> xy;
  std::vector<sim::Circle> circles;  // this episode's obstacles (fixed and random)
  bool success = false, collided = false;
};

// Every episode's path over the layout: success green, failure red; the random obstacles of all
// episodes drawn light over the layout's.
Status PlotTrajectories(const std::string& png, const sim::AuvTaskConfig& cfg, const std::vector<EpisodeTrace>& traces,
                        const std::string& title) {
  const sim::World2d& world = cfg.layout.world;
  report::MapPlot m;
  m.title = title;
  m.arena = {world.arena.x_min_m, world.arena.x_max_m, world.arena.y_min_m, world.arena.y_max_m};
  for (const auto& b : world.boxes) m.boxes.push_back({b.x_min_m, b.x_max_m, b.y_min_m, b.y_max_m});
  for (const auto& c : world.circles) m.obstacles.push_back({c.x_m, c.y_m, c.radius_m});
  // The layout's obstacles come first in every episode's world; the rest are the episode's own.
  for (const auto& t : traces)
    for (std::size_t i = world.circles.size(); i < t.circles.size(); ++i)
      m.random_obstacles.push_back({t.circles[i].x_m, t.circles[i].y_m, t.circles[i].radius_m});
  for (const auto& t : cfg.layout.targets) m.targets.push_back({t[0], t[1]});
  for (const auto& t : traces) {
    m.paths.push_back({{}, t.success ? report::MapPlot::PathKind::kSuccess : report::MapPlot::PathKind::kFailure});
    for (const auto& p : t.xy) m.paths.back().xy.push_back({p[0], p[1]});
  }
  return report::PlotMap(m, png);
}

// Opens a CSV output and writes its header; an empty path writes nothing.
Status OpenCsv(std::ofstream& out, const std::string& path, const char* flag, const char* header) {
  if (path.empty()) return {};
  out.open(path);
  if (!out) return MakeError(ErrorCode::kIo, std::string(flag) + ": cannot write '" + path + "'");
  out << header << '\n';
  return {};
}

// One --outcomes row: how the episode ended, where, and what was nearest there ("wall", "layout" obstacle
// or "random" obstacle); the random obstacles (those beyond the layout's) as x:y:radius separated by spaces.
void WriteOutcome(std::ostream& out, int episode, const AuvNav& auv, double ret) {
  const auto& task = auv.task();
  const auto& st = task.stats();
  const auto& v = task.vehicle();
  const auto& world = task.world();
  const auto& fixed = auv.config().layout.world;  // arena and layout obstacles, without the random ones
  const char* outcome = st.success ? "success" : st.collided ? "collision" : "timeout";
  const double nearest = sim::Clearance(world, v.x_m, v.y_m);
  const double fixed_nearest = sim::Clearance(fixed, v.x_m, v.y_m);
  const double wall = sim::Clearance(sim::World2d{world.arena, {}, {}}, v.x_m, v.y_m);
  const char* what = nearest < fixed_nearest ? "random" : wall <= fixed_nearest ? "wall" : "layout";
  const std::size_t first_random = fixed.circles.size();
  out << episode << ',' << auv.config().layout.name << ',' << outcome << ',' << st.targets_reached << ',' << st.time_s
      << ',' << ret << ',' << v.x_m << ',' << v.y_m << ',' << v.yaw_rad << ',' << nearest << ',' << what << ',';
  for (std::size_t i = first_random; i < world.circles.size(); ++i) {
    const auto& c = world.circles[i];
    out << (i > first_random ? " " : "") << c.x_m << ':' << c.y_m << ':' << c.radius_m;
  }
  out << '\n';
}

class AuvEvalHooks final : public EpisodeHooks {
 public:
  static Result<std::unique_ptr<EpisodeHooks>> Make(const EvalRequest& r) {
    std::unique_ptr<AuvEvalHooks> h(new AuvEvalHooks());
    h->plot_ = FlagText(*r.env, "plot");
    if (!h->plot_.empty() && FlagText(*r.env, "layout") == "mixed")
      return MakeError(ErrorCode::kInvalidValue, "--plot needs one layout (easy, medium or hard), not 'mixed'");
    if (auto st = OpenCsv(h->trajectories_, FlagText(*r.env, "trajectories"), "--trajectories",
                          "episode,step,t_s,x_m,y_m,yaw_rad,v_cmd_mps,w_cmd_radps,target");
        !st)
      return st.error();
    if (auto st = OpenCsv(
            h->outcomes_, FlagText(*r.env, "outcomes"), "--outcomes",
            "episode,layout,outcome,targets,time_s,return,x_m,y_m,yaw_rad,clearance_m,nearest,random_obstacles");
        !st)
      return st.error();
    return std::unique_ptr<EpisodeHooks>(std::move(h));
  }

  void Started(int episode, const Env& env) override {
    const auto& auv = static_cast<const AuvNav&>(env);
    trace_ = EpisodeTrace{};
    trace_.circles = auv.task().world().circles;
    Record(episode, 0, auv);
  }
  void Stepped(int episode, long step, const Env& env) override {
    Record(episode, step, static_cast<const AuvNav&>(env));
  }
  void Ended(int episode, const Env& env, double episode_return) override {
    const auto& auv = static_cast<const AuvNav&>(env);
    const EpisodeInfo info = auv.episode_info();
    trace_.success = info.available && info.success;
    trace_.collided = info.available && info.failure;
    if (outcomes_.is_open()) WriteOutcome(outcomes_, episode, auv, episode_return);
    if (!plot_.empty()) traces_.push_back(std::move(trace_));
  }
  std::string Finish(const Env& env, const EvalTotals& t, nlohmann::json& json, std::string& text) override {
    if (plot_.empty()) return {};
    char title[200];
    std::snprintf(title, sizeof title, "%s, %d episodes from seed %llu: %d successes, %d collisions, %d timeouts",
                  env.name().c_str(), t.episodes, static_cast<unsigned long long>(t.seed), t.successes, t.failures,
                  t.timeouts);
    const auto st = PlotTrajectories(plot_, static_cast<const AuvNav&>(env).config(), traces_, title);
    json["plot"] = st ? plot_ : "";
    if (!st) return "--plot: " + st.error().message;
    text += "plot " + plot_ + "\n";
    return {};
  }

 private:
  AuvEvalHooks() = default;
  void Record(int episode, long step, const AuvNav& auv) {
    const auto& v = auv.task().vehicle();
    if (!plot_.empty()) trace_.xy.push_back({v.x_m, v.y_m});
    if (trajectories_.is_open())
      trajectories_ << episode << ',' << step << ',' << v.time_s << ',' << v.x_m << ',' << v.y_m << ',' << v.yaw_rad
                    << ',' << auv.task().commanded_speed_mps() << ',' << auv.task().commanded_yaw_rate_radps() << ','
                    << auv.task().target_index() << '\n';
  }

  std::string plot_;
  std::ofstream trajectories_, outcomes_;
  EpisodeTrace trace_;
  std::vector<EpisodeTrace> traces_;
};

}  // namespace

EnvSpec AuvNavEnv() {
  EnvSpec s;
  s.name = "auv-nav";
  s.description = "the AUV's navigation task, docs/auv_task.md";
  using K = EnvFlag::Kind;
  s.flags = {
      Flag("layout", EnvFlag::kBoth, K::kText, "hard", "has obstacle layouts",
           "obstacle layout: easy, medium, hard, mixed (one drawn per episode)",
           OneOf({"easy", "medium", "hard", "mixed"}), true),
      Flag("exploring-starts", EnvFlag::kTrain, K::kReal, "0", "has exploring starts",
           "probability that a training episode starts anywhere in the arena with a random current target (success "
           "is counted only from the layout's start)",
           InRange(0, 1)),
      Flag("progress", EnvFlag::kTrain, K::kText, "", "has a progress term to choose",
           "the reward's progress term: euclidean (the paper: straight-line distance and bearing to the target) or "
           "geodesic (shortest path around obstacles), for every layout or per layout as LAYOUT=MODE,... (e.g. "
           "hard=geodesic; the others keep it); default: models/auv/auv.yaml's task.progress",
           ParsedBy([](const std::string& v) { return AuvNav::ProgressFor(v, ""); })),
      Flag("geodesic-margin", EnvFlag::kTrain, K::kText, "", "has one",
           "DISTANCE_M:COST, the geodesic path pays up to COST extra per metre within DISTANCE_M beyond l_safe of "
           "obstacles (keeps the progress term off the collision boundary); default: auv.yaml's "
           "task.geodesic_margin (none)",
           ParsedBy(AuvNav::ParseGeodesicMargin)),
      Flag("clearance-penalty", EnvFlag::kTrain, K::kText, "", "has one",
           "DISTANCE_M:PER_STEP, each step within DISTANCE_M beyond l_safe of an obstacle costs up to PER_STEP "
           "(linear, the full cost at l_safe); default: auv.yaml's task.clearance_penalty (none)",
           ParsedBy(AuvNav::ParseClearancePenalty)),
      Flag("extra-obstacles", EnvFlag::kTrain, K::kInteger, "0", "has obstacles",
           "each training episode draws N more random obstacles than its layout file says (0-16), so that the "
           "policy has to steer by its sonar rather than learn a route",
           InRange(0, 16)),
      Flag("plot", EnvFlag::kEval, K::kText, "", "draw plots", "write the trajectories over the map to this PNG"),
      Flag("trajectories", EnvFlag::kEval, K::kText, "", "write trajectories",
           "write every episode's trajectory to this CSV"),
      Flag("outcomes", EnvFlag::kEval, K::kText, "", "writes outcomes",
           "write one row per episode to this CSV (outcome, targets, time, return, end pose, clearance, the "
           "nearest obstacle and the random obstacles)"),
  };
  s.make = [](const EnvOptions& o) -> Result<std::unique_ptr<Env>> {
    AuvNavOptions a;
    a.models_dir = ModelsDir(o);
    a.layout = FlagText(o, "layout");
    a.exploring_starts = FlagReal(o, "exploring-starts");
    a.progress = FlagText(o, "progress");
    a.geodesic_margin = FlagText(o, "geodesic-margin");
    a.clearance_penalty = FlagText(o, "clearance-penalty");
    a.extra_obstacles = static_cast<int>(FlagInteger(o, "extra-obstacles"));
    return AsEnv(AuvNav::Make(a));
  };
  s.evaluation.hooks = [](const EvalRequest& r, Env&) { return AuvEvalHooks::Make(r); };
  return s;
}

}  // namespace pbppo::envs
