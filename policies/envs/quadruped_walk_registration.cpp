// quadruped-walk as pbppo knows it: its flags, how they build it, and its pbppo eval: the paper's
// test (policies/envs/walk_eval.hpp: tracking errors per axis, falls, a plot of commanded against
// measured velocities), or one robot on a velocity schedule (--schedule, the HIL's).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "policies/envs/quadruped_walk.hpp"
#include "policies/envs/walk_eval.hpp"
#include "report/plots.hpp"
#include "runtime/loop/schedule.hpp"
#include "runtime/robot/robot_model.hpp"

namespace pbppo::envs {
namespace {

// Commanded (dashed) against measured (solid) vx, vy and yaw rate of the traced robots over time.
Status Plot(const std::string& png, const WalkEvalResult& r, const std::string& title) {
  report::TimeSeriesPlot p;
  p.title = title;
  const char* labels[3] = {"vx [m/s]", "vy [m/s]", "yaw rate [rad/s]"};
  for (int axis = 0; axis < 3; ++axis) {
    report::TimeSeriesPlot::Panel panel;
    panel.ylabel = labels[axis];
    for (std::size_t k = 0; k < r.traces.size(); ++k) {
      report::TimeSeriesPlot::Series command, measured;
      command.title = "robot " + std::to_string(k) + " command";
      measured.title = "robot " + std::to_string(k) + " measured";
      command.group = measured.group = static_cast<int>(k);
      command.dashed = true;
      for (const auto& t : r.traces[k]) {
        command.x.push_back(t.time_s);
        command.y.push_back(t.command[static_cast<std::size_t>(axis)]);
        measured.x.push_back(t.time_s);
        measured.y.push_back(t.measured[static_cast<std::size_t>(axis)]);
      }
      panel.series.push_back(std::move(command));
      panel.series.push_back(std::move(measured));
    }
    p.panels.push_back(std::move(panel));
  }
  return report::PlotTimeSeries(p, png);
}

// --schedule: the HIL's velocity schedule played to one robot in MuJoCo, per-phase tracking.
int EvalWalkSchedule(const EvalRequest& o, const policy::PolicyModel& model, QuadrupedWalk& env) {
  const robot::RobotModel& robot = env.robot_model();
  const std::string schedule_path = FlagText(*o.env, "schedule");
  auto schedule = loop::LoadSchedule(schedule_path, robot);
  if (!schedule) {
    std::fprintf(stderr, "pbppo eval: --schedule: %s\n", schedule.error().message.c_str());
    return 2;
  }
  auto columns = schedule->Columns(robot, {"command_vx", "command_vy", "command_yaw_rate"});
  if (!columns) {
    std::fprintf(stderr, "pbppo eval: --schedule: %s\n", columns.error().message.c_str());
    return 2;
  }
  const std::vector<std::size_t>& field = *columns;
  std::vector<WalkSchedulePhase> phases;
  for (const loop::SchedulePhase& p : schedule->phases)
    phases.push_back({p.name, p.start_s, p.duration_s, {p.values[field[0]], p.values[field[1]], p.values[field[2]]}});
  auto r = EvaluateWalkSchedule(model, env, phases, FlagReal(*o.env, "settle-s"), o.seed);
  if (!r) {
    std::fprintf(stderr, "pbppo eval: %s: %s\n", o.blob.c_str(), r.error().message.c_str());
    return 1;
  }
  if (o.json) {
    nlohmann::json j = {{"blob", o.blob},
                        {"env", "quadruped-walk"},
                        {"terrain", FlagText(*o.env, "terrain")},
                        {"schedule", schedule_path},
                        {"seed", o.seed},
                        {"settle_s", FlagReal(*o.env, "settle-s")},
                        {"fell", r->fell},
                        {"fell_at_s", r->fell_at_s},
                        {"distance_m", r->distance_m},
                        {"phases", nlohmann::json::array()}};
    for (const auto& p : r->phases) {
      auto three = [](const std::array<double, 3>& v) { return nlohmann::json::array({v[0], v[1], v[2]}); };
      j["phases"].push_back({{"name", p.phase.name},
                             {"start_s", p.phase.start_s},
                             {"end_s", p.phase.start_s + p.phase.duration_s},
                             {"command", three(p.phase.command)},
                             {"mean_abs_error", three(p.mean_abs_error)},
                             {"mean_measured", three(p.mean_measured)}});
    }
    std::printf("%s\n", j.dump(2).c_str());
    return r->fell ? 1 : 0;
  }
  std::printf("%s on quadruped-walk (MuJoCo), %s terrain%s, schedule %s, seed %llu\n", o.blob.c_str(),
              FlagText(*o.env, "terrain").c_str(), FlagSet(*o.env, "randomize") ? " (randomised robot)" : "",
              schedule_path.c_str(), static_cast<unsigned long long>(o.seed));
  std::printf("%-10s %6s %6s | %8s %8s %8s | %8s %8s %8s\n", "phase", "from", "to", "cmd vx", "cmd vy", "cmd wz",
              "|e| vx", "|e| vy", "|e| wz");
  for (const auto& p : r->phases)
    std::printf("%-10s %6.1f %6.1f | %8.2f %8.2f %8.2f | %8.3f %8.3f %8.3f\n", p.phase.name.c_str(), p.phase.start_s,
                p.phase.start_s + p.phase.duration_s, p.phase.command[0], p.phase.command[1], p.phase.command[2],
                p.mean_abs_error[0], p.mean_abs_error[1], p.mean_abs_error[2]);
  std::printf("walked %.2f m; %s\n", r->distance_m,
              r->fell ? ("FELL at " + std::to_string(r->fell_at_s) + " s").c_str() : "no fall");
  return r->fell ? 1 : 0;
}

// pbppo eval: the paper's test, or with --schedule the schedule.
int EvalWalk(const EvalRequest& o, Env& e) {
  auto& env = static_cast<QuadrupedWalk&>(e);
  const policy::PolicyModel& model = *o.model;
  if (!FlagText(*o.env, "schedule").empty()) return EvalWalkSchedule(o, model, env);
  const std::string plot = FlagText(*o.env, "plot"), trajectories = FlagText(*o.env, "trajectories");
  const std::string terrain = FlagText(*o.env, "terrain");
  const bool randomize = FlagSet(*o.env, "randomize");
  WalkEvalOptions eo;
  eo.robots = o.episodes > 0 ? o.episodes : 50;
  eo.seed = o.seed;
  eo.trace_robots = plot.empty() && trajectories.empty() ? 0 : 3;
  auto r = EvaluateWalk(model, env, eo);
  if (!r) {
    std::fprintf(stderr, "pbppo eval: %s: %s\n", o.blob.c_str(), r.error().message.c_str());
    return 1;
  }
  const double dur = env.params().episode_s;
  std::string plot_note;
  if (!plot.empty()) {
    char title[200];
    std::snprintf(title, sizeof title, "%s, %s terrain: commanded (dashed) and measured body velocity",
                  std::filesystem::path(o.blob).filename().c_str(), terrain.c_str());
    if (auto st = Plot(plot, *r, title); !st) {
      plot_note = st.error().message;
      std::fprintf(stderr, "pbppo eval: --plot: %s\n", plot_note.c_str());
    }
  }
  if (!trajectories.empty()) {
    std::ofstream f(trajectories);
    f << "robot,t_s,vx_cmd_mps,vx_mps,vy_cmd_mps,vy_mps,yaw_rate_cmd_radps,yaw_rate_radps,x_m,y_m,z_m,yaw_rad,"
         "on_blocks,fell\n";
    for (std::size_t k = 0; k < r->traces.size(); ++k)
      for (const auto& t : r->traces[k])
        f << k << ',' << t.time_s << ',' << t.command[0] << ',' << t.measured[0] << ',' << t.command[1] << ','
          << t.measured[1] << ',' << t.command[2] << ',' << t.measured[2] << ',' << t.position[0] << ','
          << t.position[1] << ',' << t.position[2] << ',' << t.yaw_rad << ',' << t.on_blocks << ',' << t.fell << '\n';
    if (!f) {
      std::fprintf(stderr, "pbppo eval: --trajectories: cannot write '%s'\n", trajectories.c_str());
      return 1;
    }
  }
  if (o.json) {
    nlohmann::json j;
    j["blob"] = o.blob;
    j["env"] = "quadruped-walk";
    j["terrain"] = terrain;
    j["randomize"] = randomize;
    j["robots"] = r->robots;
    j["episode_s"] = dur;
    j["seed"] = o.seed;
    j["mean_abs_error"] = {
        {"vx_mps", r->mean_abs_error[0]}, {"vy_mps", r->mean_abs_error[1]}, {"yaw_rate_radps", r->mean_abs_error[2]}};
    j["mean_abs_error_settled"] = {{"vx_mps", r->mean_abs_error_settled[0]},
                                   {"vy_mps", r->mean_abs_error_settled[1]},
                                   {"yaw_rate_radps", r->mean_abs_error_settled[2]},
                                   {"settle_s", eo.settle_s}};
    j["falls"] = r->falls;
    nlohmann::json falls = nlohmann::json::array();
    for (const auto& f : r->fall_list)
      falls.push_back({{"robot", f.robot},
                       {"time_s", f.time_s},
                       {"command", {f.command[0], f.command[1], f.command[2]}},
                       {"on_blocks", f.on_blocks},
                       {"cause", f.base_contact ? "base contact" : "tilt"}});
    j["fall_list"] = falls;
    j["robots_on_blocks"] = r->robots_on_blocks;
    j["falls_on_blocks"] = r->falls_on_blocks;
    j["steps"] = r->steps;
    j["mean_return"] = r->mean_return;
    j["forward_problems"] = r->forward_problems;
    if (!plot.empty()) j["plot"] = plot_note.empty() ? plot : "";
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("%s on quadruped-walk, %s terrain%s: %d robots x %.0f s, seed %llu\n", o.blob.c_str(), terrain.c_str(),
                randomize ? " (randomised robots)" : "", r->robots, dur, static_cast<unsigned long long>(o.seed));
    std::printf("mean |error|  vx %.3f m/s  vy %.3f m/s  yaw rate %.3f rad/s   (every step)\n", r->mean_abs_error[0],
                r->mean_abs_error[1], r->mean_abs_error[2]);
    std::printf(
        "mean |error|  vx %.3f m/s  vy %.3f m/s  yaw rate %.3f rad/s   (%.0f s or more after a command change)\n",
        r->mean_abs_error_settled[0], r->mean_abs_error_settled[1], r->mean_abs_error_settled[2], eo.settle_s);
    std::printf("falls %d/%d", r->falls, r->robots);
    if (r->robots_on_blocks > 0) std::printf("  (on blocks %d/%d)", r->falls_on_blocks, r->robots_on_blocks);
    std::printf("  mean return %.2f  steps %llu  forward problems %llu\n", r->mean_return,
                static_cast<unsigned long long>(r->steps), static_cast<unsigned long long>(r->forward_problems));
    for (const auto& f : r->fall_list)
      std::printf("  fall: robot %d at %.2f s%s (%s), command vx %.2f vy %.2f yaw rate %.2f\n", f.robot, f.time_s,
                  f.on_blocks ? " on blocks" : "", f.base_contact ? "base contact" : "tilt", f.command[0], f.command[1],
                  f.command[2]);
    if (!plot.empty() && plot_note.empty()) std::printf("plot %s\n", plot.c_str());
  }
  return 0;
}

}  // namespace

EnvSpec QuadrupedWalkEnv() {
  EnvSpec s;
  s.name = "quadruped-walk";
  s.description = "the quadruped's velocity tracking, docs/quadruped_walk.md";
  using K = EnvFlag::Kind;
  // A walk.yaml override is checked as the environment applies it.
  auto applies = [](Status (*apply)(const std::string&, QuadrupedWalkParams&)) {
    return ParsedBy([apply](const std::string& v) {
      QuadrupedWalkParams p;
      return apply(v, p);
    });
  };
  s.flags = {
      Flag("robot", EnvFlag::kBoth, K::kText, "quadruped", "walks a legged robot",
           "the legged robot: a folder of the models (quadruped, go2) or its robot.yaml", {}, true),
      Flag("terrain", EnvFlag::kBoth, K::kText, "flat", "has terrains to choose",
           "flat, or mixed (flat and block episodes 1:1)", OneOf({"flat", "mixed"}), true),
      Flag("commands", EnvFlag::kBoth, K::kText, "", "has velocity commands",
           "VX:VY:YAW command maxima (ranges [-max, max]); default: models/quadruped/walk.yaml's",
           applies(ApplyCommandSpec), true),
      Flag("command-shares", EnvFlag::kTrain, K::kText, "", "has velocity commands",
           "HEADING:ZERO_PLANAR[:SINGLE_AXIS], the share of commands whose yaw rate follows a heading (the rest "
           "draw a yaw rate), the share with vx = vy = 0 (standing or turning in place) and the share along one "
           "axis alone (vx, vy or a yaw rate); default: models/quadruped/walk.yaml's",
           applies(ApplyCommandShares)),
      Flag("command-resample", EnvFlag::kTrain, K::kText, "", "has velocity commands",
           "SECONDS between the training's command draws (each a new command, and a new heading); the paper's "
           "test draws every 10 s whatever this is; default: models/quadruped/walk.yaml's resample_s",
           applies(ApplyCommandResample)),
      Flag("reward-scales", EnvFlag::kTrain, K::kText, "", "has reward scales to set",
           "NAME=VALUE[,NAME=VALUE...] replaces those reward scales of models/quadruped/walk.yaml for this run "
           "(e.g. tracking_ang_vel=1.0; also tracking_sigma, the tracking terms' width)",
           applies(ApplyRewardScales)),
      Flag("randomize", EnvFlag::kEval, K::kSwitch, "", "has randomised robots",
           "randomised robots as in training (friction, mass, gains, latency, pushes); default: the nominal robot"),
      Flag("schedule", EnvFlag::kEval, K::kText, "", "takes a velocity schedule",
           "one robot commanded by this velocity schedule (the HIL's, e.g. models/quadruped/schedules/demo.yaml): "
           "per-phase tracking, as pbppo-hil quadruped prints it"),
      Flag("settle-s", EnvFlag::kEval, K::kReal, "1", "takes a velocity schedule",
           "--schedule: tracking is judged this long after each phase starts", InRange(0, 100)),
      Flag("plot", EnvFlag::kEval, K::kText, "", "draw plots",
           "commanded against measured velocities of the first robots, to this PNG"),
      Flag("trajectories", EnvFlag::kEval, K::kText, "", "write trajectories",
           "every step of the first robots (commanded and measured velocities, pose) to this CSV"),
  };
  s.make = [](const EnvOptions& o) -> Result<std::unique_ptr<Env>> {
    QuadrupedWalkOptions q;
    q.models_dir = ModelsDir(o);
    q.robot = FlagText(o, "robot");
    q.terrain = FlagText(o, "terrain");
    q.commands = FlagText(o, "commands");
    q.command_shares = FlagText(o, "command-shares");
    q.command_resample = FlagText(o, "command-resample");
    q.reward_scales = FlagText(o, "reward-scales");
    // Training always randomises the robot; pbppo eval takes the nominal one unless --randomize,
    // and the paper's test's commands whatever training used.
    q.randomize = o.purpose == EnvPurpose::kTrain || FlagSet(o, "randomize");
    q.paper_test = o.purpose == EnvPurpose::kEval;
    return AsEnv(QuadrupedWalk::Make(q));
  };
  s.evaluation.default_episodes = 50;
  s.evaluation.episodes_are = "robots";
  s.evaluation.run = EvalWalk;
  return s;
}

}  // namespace pbppo::envs
