#include "policies/cli/eval.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <vector>

#include "policies/cli/eval_walk.hpp"
#include "policies/cli/train.hpp"
#include "policies/envs/auv_nav.hpp"
#include "policies/envs/env.hpp"
#include "policies/envs/mujoco_tasks.hpp"
#include "policies/envs/walk_eval.hpp"
#include "report/plots.hpp"
#include "runtime/core/cli_checks.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/robot/io_layout.hpp"
#include "sim_hil/scenarios/auv_sonar.hpp"

namespace pbppo::cli {

void AddEvalOptions(CLI::App& s, EvalOptions& o) {
  s.add_option("blob", o.blob, "Policy blob file")->required();
  AddEnvOptions(s, o.env);
  s.add_option("--episodes", o.episodes, "Episodes (quadruped-walk: robots; default 100, quadruped-walk 50)")
      ->check(CLI::Range(1, 1000000));
  s.add_flag("--randomize", o.env.randomize,
             "quadruped-walk: randomised robots as in training (friction, mass, gains, latency, pushes); default: "
             "the nominal robot");
  s.add_option("--schedule", o.schedule,
               "quadruped-walk: one robot commanded by this velocity schedule (the HIL's, e.g. "
               "models/quadruped/schedules/demo.yaml): per-phase tracking, as pbppo-hil quadruped prints it");
  s.add_option("--settle-s", o.settle_s, "--schedule: tracking is judged this long after each phase starts")
      ->check(CLI::Range(0.0, 100.0));
  s.add_option("--seed", o.seed, "Seed for the initial states")->check(cli_checks::NonNegativeInteger());
  s.add_option("--plot", o.plot, "auv-nav: write the trajectories over the map to this PNG");
  s.add_option("--trajectories", o.trajectories, "auv-nav: write every episode's trajectory to this CSV");
  s.add_option("--outcomes", o.outcomes,
               "auv-nav: write one row per episode to this CSV (outcome, targets, time, return, end pose, clearance, "
               "the nearest obstacle and the random obstacles)");
  s.add_flag("--through-ends", o.through_ends,
             "MuJoCo tasks: every episode runs 1000 steps, on through terminations (the paper's script's way)");
  s.add_option("--kernel", o.kernel,
               "Forward kernel: auto (AVX-512 where the CPU has it), portable (the same figures on every machine that "
               "runs this build) "
               "or avx512")
      ->check(CLI::IsMember({"auto", "portable", "avx512"}));
  s.add_flag("--json", o.json, "Print JSON");
}

namespace {

struct EpisodeTrace {
  std::vector<std::array<double, 2>> xy;
  std::vector<sim::Circle> circles;  // this episode's obstacles (fixed and random)
  bool success = false, collided = false;
};

// Wilson score interval for a binomial proportion at 95 %.
std::pair<double, double> Wilson95(double k, double n) {
  const double z = 1.959963985, p = k / n, d = 1 + z * z / n;
  const double c = (p + z * z / (2 * n)) / d, h = z * std::sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d;
  return {std::max(0.0, c - h), std::min(1.0, c + h)};
}

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

// Opens an eval CSV output and writes its header; an empty path writes nothing (true).
bool OpenCsv(std::ofstream& out, const std::string& path, const char* option, const char* header) {
  if (path.empty()) return true;
  out.open(path);
  if (!out) {
    std::fprintf(stderr, "pbppo eval: %s: cannot write '%s'\n", option, path.c_str());
    return false;
  }
  out << header << '\n';
  return true;
}

// One --outcomes row: how the episode ended, where, and what was nearest there ("wall", "layout" obstacle
// or "random" obstacle); the random obstacles (those beyond the layout's) as x:y:radius separated by spaces.
void WriteOutcome(std::ostream& out, int episode, const envs::AuvNav& auv, double ret) {
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

}  // namespace

int Eval(const EvalOptions& o_in) {
  const bool walk = o_in.env.name == "quadruped-walk";
  if (o_in.env.randomize && !walk) {
    std::fprintf(stderr, "pbppo eval: --randomize: only quadruped-walk has randomised robots, not '%s'\n",
                 o_in.env.name.c_str());
    return 2;
  }
  policy::LoadOptions load;
  for (policy::Kernel k : {policy::Kernel::kAuto, policy::Kernel::kPortable, policy::Kernel::kAvx512}) {
    if (o_in.kernel == policy::ToString(k)) load.kernel = k;
  }
  auto model = policy::PolicyModel::FromFile(o_in.blob, load);
  if (!model) {
    std::fprintf(stderr, "pbppo eval: %s\n", model.error().message.c_str());
    return 1;
  }
  envs::EnvOptions env_options = o_in.env;
  env_options.paper_test = walk;  // the paper's test's commands, whatever training used
  auto env = envs::MakeEnv(env_options);
  if (!env) {
    std::fprintf(stderr, "pbppo eval: %s\n", env.error().message.c_str());
    return 2;
  }
  if (!o_in.schedule.empty() && !walk) {
    std::fprintf(stderr, "pbppo eval: --schedule: only quadruped-walk takes a velocity schedule, not '%s'\n",
                 o_in.env.name.c_str());
    return 2;
  }
  if (o_in.through_ends && envs::FindMujocoTask(o_in.env.name) == nullptr) {
    std::fprintf(stderr, "pbppo eval: --through-ends: only the MuJoCo tasks step on after an episode ends, not '%s'\n",
                 o_in.env.name.c_str());
    return 2;
  }
  if (walk) return EvalWalk(o_in, *model, dynamic_cast<envs::QuadrupedWalk&>(**env));
  EvalOptions o = o_in;
  if (o.episodes == 0) o.episodes = 100;
  if (auto st = robot::CheckPolicyMatchesLayout(model->description(), (*env)->layout()); !st) {
    std::fprintf(stderr, "pbppo eval: %s: %s\n", o.blob.c_str(), st.error().message.c_str());
    return 1;
  }
  auto* auv = dynamic_cast<envs::AuvNav*>(env->get());
  if ((!o.plot.empty() || !o.trajectories.empty() || !o.outcomes.empty()) && auv == nullptr) {
    std::fprintf(stderr, "pbppo eval: --plot, --trajectories and --outcomes need --env auv-nav (not '%s')\n",
                 o.env.name.c_str());
    return 2;
  }
  if (!o.plot.empty() && o.env.layout == "mixed") {
    std::fprintf(stderr, "pbppo eval: --plot needs one layout (easy, medium or hard), not 'mixed'\n");
    return 2;
  }
  auto data = policy::MakePolicyData(model.value());
  if (!data) {
    std::fprintf(stderr, "pbppo eval: %s\n", data.error().message.c_str());
    return 1;
  }
  envs::Env& e = **env;
  // The blob outputs commands (the layout's map applied); the environment takes policy units.
  Rng rng(o.seed);
  std::vector<float> obs(e.observation_size()), act(e.action_size());
  std::vector<double> returns;
  std::vector<EpisodeTrace> traces;
  std::ofstream traj, outcomes;
  if (!OpenCsv(traj, o.trajectories, "--trajectories",
               "episode,step,t_s,x_m,y_m,yaw_rad,v_cmd_mps,w_cmd_radps,target") ||
      !OpenCsv(outcomes, o.outcomes, "--outcomes",
               "episode,layout,outcome,targets,time_s,return,x_m,y_m,yaw_rad,clearance_m,nearest,random_obstacles")) {
    return 2;
  }
  std::uint64_t steps = 0, bad = 0;
  int successes = 0, failures = 0, timeouts = 0, goals = 0;
  double success_time = 0;
  for (int ep = 0; ep < o.episodes; ++ep) {
    e.Reset(rng, obs);
    double ret = 0;
    EpisodeTrace tr;
    long k = 0;
    auto record = [&] {
      if (auv == nullptr) return;
      const auto& v = auv->task().vehicle();
      tr.xy.push_back({v.x_m, v.y_m});
      if (traj.is_open()) {
        traj << ep << ',' << k << ',' << v.time_s << ',' << v.x_m << ',' << v.y_m << ',' << v.yaw_rad << ','
             << auv->task().commanded_speed_mps() << ',' << auv->task().commanded_yaw_rate_radps() << ','
             << auv->task().target_index() << '\n';
      }
    };
    if (auv != nullptr) tr.circles = auv->task().world().circles;
    record();
    for (;;) {
      std::copy(obs.begin(), obs.end(), data->observation().begin());
      if (policy::Forward(model.value(), data.value()) != policy::ForwardStatus::kOk) ++bad;
      robot::ToPolicyUnits(e.layout(), data->action(), act);
      const envs::StepResult r = e.Step(act, obs);
      ret += r.reward;
      ++steps;
      ++k;
      record();
      if (o.through_ends ? k >= static_cast<long>(e.max_episode_steps()) : (r.terminated || r.truncated)) break;
    }
    returns.push_back(ret);
    const envs::EpisodeInfo info = e.episode_info();
    if (info.available) {
      successes += info.success;
      failures += info.failure;
      timeouts += !info.success && !info.failure;
      goals += info.goals;
      if (info.success) success_time += info.time_s;
      tr.success = info.success;
      tr.collided = info.failure;
    }
    if (outcomes.is_open()) WriteOutcome(outcomes, ep, *auv, ret);
    if (auv != nullptr && !o.plot.empty()) traces.push_back(std::move(tr));
  }
  const double n = static_cast<double>(returns.size());
  double mean = 0, var = 0;
  for (double r : returns) mean += r;
  mean /= n;
  for (double r : returns) var += (r - mean) * (r - mean);
  const double sd = std::sqrt(var / n);
  const double lo = *std::min_element(returns.begin(), returns.end());
  const double hi = *std::max_element(returns.begin(), returns.end());
  const bool task = e.episode_info().available;
  const auto [ci_lo, ci_hi] = Wilson95(successes, n);
  const double mean_time = successes > 0 ? success_time / successes : std::nan("");
  std::string plot_note;
  if (!o.plot.empty()) {
    char title[200];
    std::snprintf(title, sizeof title, "%s, %d episodes from seed %llu: %d successes, %d collisions, %d timeouts",
                  e.name().c_str(), o.episodes, static_cast<unsigned long long>(o.seed), successes, failures, timeouts);
    if (auto st = PlotTrajectories(o.plot, auv->config(), traces, title); !st) {
      plot_note = st.error().message;
      std::fprintf(stderr, "pbppo eval: --plot: %s\n", plot_note.c_str());
    }
  }
  if (o.json) {
    nlohmann::json j;
    j["blob"] = o.blob;
    j["env"] = e.name();
    j["episodes"] = o.episodes;
    j["seed"] = o.seed;
    j["mean_return"] = mean;
    j["std_return"] = sd;
    j["min_return"] = lo;
    j["max_return"] = hi;
    j["steps"] = steps;
    j["through_ends"] = o.through_ends;
    j["kernel"] = policy::ToString(model->kernel());
    j["forward_problems"] = bad;
    if (task) {
      j["successes"] = successes;
      j["success_rate"] = successes / n;
      j["success_rate_ci95"] = {ci_lo, ci_hi};
      j["collisions"] = failures;
      j["timeouts"] = timeouts;
      j["mean_goals"] = goals / n;
      j["mean_success_time_s"] = successes > 0 ? nlohmann::json(mean_time) : nlohmann::json();
    }
    if (!o.plot.empty()) j["plot"] = plot_note.empty() ? o.plot : "";
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf(
        "%s on %s: %d episodes%s, seed %llu, %s kernel\n", o.blob.c_str(), e.name().c_str(), o.episodes,
        o.through_ends ? (" of " + std::to_string(e.max_episode_steps()) + " steps through episode ends").c_str() : "",
        static_cast<unsigned long long>(o.seed), policy::ToString(model->kernel()));
    if (task) {
      std::printf(
          "success %d/%d = %.1f%% (95%% CI %.1f-%.1f%%)  collisions %d  timeouts %d  targets/episode %.2f  "
          "mean time (successes) %.1f s\n",
          successes, o.episodes, 100 * successes / n, 100 * ci_lo, 100 * ci_hi, failures, timeouts, goals / n,
          mean_time);
    }
    std::printf("mean return %.2f  std %.2f  min %.2f  max %.2f  steps %llu  forward problems %llu\n", mean, sd, lo, hi,
                static_cast<unsigned long long>(steps), static_cast<unsigned long long>(bad));
    if (!o.plot.empty() && plot_note.empty()) std::printf("plot %s\n", o.plot.c_str());
  }
  return 0;
}

}  // namespace pbppo::cli
