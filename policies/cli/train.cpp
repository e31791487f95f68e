#include "policies/cli/train.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <vector>

#include "policies/envs/auv_nav.hpp"
#include "policies/envs/env.hpp"
#include "policies/trainer/trainer.hpp"
#include "report/plots.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/robot/io_layout.hpp"
#include "sim_hil/scenarios/auv_sonar.hpp"

namespace pbppo::cli {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<std::int64_t> g_first_sigint_ns{0};
static_assert(std::atomic<std::int64_t>::is_always_lock_free, "used from a signal handler");

std::int64_t MonotonicNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);  // async-signal-safe
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// The first SIGINT asks for a clean stop (log, summary, checkpoint). A second one ends the process at
// once, but only when it comes more than a second later: `timeout -s INT` and a terminal's job control
// can deliver the same interrupt twice (to the process and to its group), which must not kill the run.
extern "C" void OnSigint(int) {
  const std::int64_t now = MonotonicNs();
  const std::int64_t first = g_first_sigint_ns.load();
  if (first == 0) {
    g_first_sigint_ns.store(now);
    g_stop.store(true);
    return;
  }
  if (now - first < 1'000'000'000) return;
  std::signal(SIGINT, SIG_DFL);
  std::raise(SIGINT);
}

int Fail(const std::string& msg, int rc = 2) {
  std::fprintf(stderr, "pbppo train: %s\n", msg.c_str());
  return rc;
}

bool ParseWidths(const std::string& field, const std::string& s, std::vector<int>* out) {
  out->clear();
  std::size_t pos = 0;
  while (pos <= s.size()) {
    const auto dash = s.find('-', pos);
    const std::string part = s.substr(pos, dash == std::string::npos ? std::string::npos : dash - pos);
    char* end = nullptr;
    const long v = std::strtol(part.c_str(), &end, 10);
    if (part.empty() || *end != '\0' || v < 1 || v > 2048) {
      std::fprintf(stderr, "pbppo train: %s: '%s' is not a width in [1, 2048]\n", field.c_str(), part.c_str());
      return false;
    }
    out->push_back(static_cast<int>(v));
    if (dash == std::string::npos) break;
    pos = dash + 1;
  }
  return true;
}

std::string Human(double v) {
  char buf[32];
  if (v >= 1e6) {
    std::snprintf(buf, sizeof buf, "%.2fM", v / 1e6);
  } else if (v >= 1e3) {
    std::snprintf(buf, sizeof buf, "%.1fk", v / 1e3);
  } else {
    std::snprintf(buf, sizeof buf, "%.0f", v);
  }
  return buf;
}

}  // namespace

void AddTrainOptions(CLI::App& s, TrainOptions& o) {
  s.add_option("--env", o.env, "Environment: pendulum, auv-nav");
  s.add_option("--layout", o.layout, "Obstacle layout of auv-nav: easy, medium, hard, mixed (one drawn per episode)");
  s.add_option("--exploring-starts", o.exploring_starts,
               "auv-nav: probability that a training episode starts anywhere in the arena with a random current "
               "target (success is counted only from the layout's start)");
  s.add_option(
      "--progress", o.progress,
      "auv-nav: the reward's progress term: euclidean (the paper: straight-line distance and bearing to "
      "the target) or geodesic (shortest path around obstacles), for every layout or per layout as "
      "LAYOUT=MODE,... (e.g. hard=geodesic; the others keep it); default: models/auv/auv.yaml's task.progress");
  s.add_option("--geodesic-margin", o.geodesic_margin,
               "auv-nav: DISTANCE_M:COST, the geodesic path pays up to COST extra per metre within DISTANCE_M beyond "
               "l_safe of obstacles (keeps the progress term off the collision boundary); default: auv.yaml's "
               "task.geodesic_margin (none)");
  s.add_option("--clearance-penalty", o.clearance_penalty,
               "auv-nav: DISTANCE_M:PER_STEP, each step within DISTANCE_M beyond l_safe of an obstacle costs up to "
               "PER_STEP (linear, the full cost at l_safe); default: auv.yaml's task.clearance_penalty (none)");
  s.add_option("--extra-obstacles", o.extra_obstacles,
               "auv-nav, training: each episode draws N more random obstacles than its layout file says (0-16), "
               "so that the policy has to steer by its sonar rather than learn a route");
  s.add_option("--schedule", o.schedule,
               "Clip schedule: fixed:EPS, pbppo-paper[:wi-ad|:wo-ad], pbppo-reference[:wi-ad|:wo-ad], pbppo");
  s.add_option("--arms", o.arms, "Candidate clip bounds: MIN:MAX:N (linspace) or a,b,c; each in [0, 1]");
  s.add_option("--feedback", o.feedback, "Bandit feedback: eval (k deterministic episodes) or rollout");
  s.add_option("--eval-episodes", o.eval_episodes, "k, evaluation episodes per iteration (eval feedback)");
  s.add_option("--bandit-lambda", o.bandit_lambda, "Exploration weight (default: 5 paper/reference, 1 pbppo)");
  s.add_option("--bandit-gamma", o.bandit_gamma, "Bandit discount (default: 0.99 paper/reference, 0.95 pbppo)");
  s.add_option("--steps", o.steps, "Training environment steps (e.g. 2e5)");
  s.add_option("--seed", o.seed, "Seed");
  s.add_option("--out", o.out, "Output folder (log.csv, summary.json, policy.blob, plots)")->required();
  s.add_option("--threads", o.threads, "Worker threads (rollout envs; >= 2 also splits policy/value updates)");
  s.add_option("--envs", o.envs, "Parallel environments");
  s.add_option("--rollout", o.rollout, "Steps per environment and iteration");
  s.add_option("--minibatch", o.minibatch, "Minibatch size");
  s.add_option("--epochs", o.epochs, "Epochs per iteration");
  s.add_option("--lr", o.lr, "Adam learning rate");
  s.add_flag("--anneal-lr", o.anneal_lr, "Decay the learning rate linearly to 0 over the budget");
  s.add_flag("--keep-best", o.keep_best, "Also write best.blob: the policy of the best last-100-episode return");
  s.add_option("--snapshots", o.snapshots,
               "Also write N blobs evenly spaced over the run into OUT/snapshots/ (named by training steps), "
               "to choose among on held-out episodes (tools/select_auv.sh)");
  s.add_option("--gamma", o.gamma, "Discount");
  s.add_option("--gae-lambda", o.gae_lambda, "GAE lambda");
  s.add_option("--ent-coef", o.ent_coef, "Entropy coefficient");
  s.add_option("--vf-coef", o.vf_coef, "Value loss coefficient");
  s.add_option("--max-grad-norm", o.max_grad_norm, "Global gradient-norm clip (<= 0: off)");
  s.add_option("--clip-vf", o.clip_vf, "Value clipping range (<= 0: off)");
  s.add_option("--hidden", o.hidden, "Policy hidden widths, e.g. 64-64");
  s.add_option("--value-hidden", o.value_hidden, "Value hidden widths (default: --hidden)");
  s.add_option("--activation", o.activation, "Hidden activation: tanh, elu, relu, identity");
  s.add_option("--log-std-init", o.log_std_init, "Initial log standard deviation");
  s.add_flag("--normalize-obs", o.normalize_obs, "Running observation normalisation (frozen into the blob)");
  s.add_flag("--scale-rewards", o.scale_rewards, "Scale rewards by the running std of the discounted return");
  s.add_flag("--no-adv-norm", o.no_adv_norm, "No per-minibatch advantage normalisation");
  s.add_flag("--no-plots", o.no_plots, "Do not run gnuplot");
  s.add_option("--checkpoint-seconds", o.checkpoint_seconds, "Seconds between checkpoint blobs");
  s.add_option("--models", o.models, "Models folder (default: the source tree's models/)");
  s.add_option("--critic-warmup", o.critic_warmup,
               "With --init: the first N iterations train only the (fresh) value network, the policy is held");
  s.add_option("--init", o.init,
               "Start from this blob's policy and observation normaliser (same IO layout, --hidden and "
               "--activation; value network and log-std start fresh), e.g. to continue on a harder layout");
  s.add_flag("--quiet", o.quiet, "No progress line");
}

int Train(const TrainOptions& o) {
  trainer::TrainConfig c;
  c.env = o.env;
  c.models_dir = o.models;
  c.layout = o.layout;
  c.exploring_starts = o.exploring_starts;
  c.progress = o.progress;
  c.geodesic_margin = o.geodesic_margin;
  c.clearance_penalty = o.clearance_penalty;
  c.extra_obstacles = o.extra_obstacles;
  if (!(o.steps >= 1 && o.steps <= 1e12)) return Fail("--steps: " + std::to_string(o.steps) + " is not in [1, 1e12]");
  c.total_steps = static_cast<std::uint64_t>(std::llround(o.steps));
  c.seed = o.seed;
  c.threads = o.threads;
  c.num_envs = o.envs;
  c.rollout_steps = o.rollout;
  c.minibatch = o.minibatch;
  c.epochs = o.epochs;
  c.learning_rate = o.lr;
  c.anneal_lr = o.anneal_lr;
  c.keep_best = o.keep_best;
  c.snapshots = o.snapshots;
  c.critic_warmup = o.critic_warmup;
  c.gamma = o.gamma;
  c.gae_lambda = o.gae_lambda;
  c.ent_coef = o.ent_coef;
  c.vf_coef = o.vf_coef;
  c.max_grad_norm = o.max_grad_norm;
  c.clip_vf = o.clip_vf;
  c.log_std_init = o.log_std_init;
  c.normalize_observations = o.normalize_obs;
  c.init_blob = o.init;
  c.scale_rewards = o.scale_rewards;
  c.normalize_advantages = !o.no_adv_norm;
  c.plots = !o.no_plots;
  c.checkpoint_seconds = o.checkpoint_seconds;
  c.out_dir = o.out;
  if (!ParseWidths("--hidden", o.hidden, &c.policy_hidden)) return 2;
  if (!ParseWidths("--value-hidden", o.value_hidden.empty() ? o.hidden : o.value_hidden, &c.value_hidden)) return 2;
  if (!policy::ParseActivation(o.activation, &c.activation)) {
    return Fail("--activation '" + o.activation + "' unknown (tanh, elu, relu, identity)");
  }
  std::vector<double> arms;
  if (o.schedule.rfind("fixed", 0) != 0) {
    auto a = trainer::ParseArms(o.arms);
    if (!a) return Fail(a.error().message);
    arms = a.value();
  }
  auto sc = trainer::ParseSchedule(o.schedule, arms);
  if (!sc) return Fail(sc.error().message);
  c.schedule = sc.value();
  if (o.feedback == "eval") {
    c.schedule.feedback = trainer::FeedbackSource::kEval;
  } else if (o.feedback == "rollout") {
    c.schedule.feedback = trainer::FeedbackSource::kRollout;
  } else {
    return Fail("--feedback '" + o.feedback + "' unknown (eval or rollout)");
  }
  c.schedule.eval_episodes = o.eval_episodes;
  if (o.bandit_lambda >= 0) c.schedule.lambda = o.bandit_lambda;
  if (o.bandit_gamma >= 0) {
    if (o.bandit_gamma > 1) return Fail("--bandit-gamma: " + std::to_string(o.bandit_gamma) + " is not in [0, 1]");
    c.schedule.gamma = o.bandit_gamma;
  }
  if (auto st = c.Validate(); !st) return Fail(st.error().message);
  {
    envs::EnvOptions eo;
    eo.models_dir = c.models_dir;
    eo.layout = c.layout;
    eo.exploring_starts = c.exploring_starts;
    eo.progress = c.progress;
    eo.geodesic_margin = c.geodesic_margin;
    eo.clearance_penalty = c.clearance_penalty;
    eo.extra_obstacles = c.extra_obstacles;
    if (auto env = envs::MakeEnv(c.env, eo); !env) return Fail(env.error().message);
  }

  g_stop.store(false);
  g_first_sigint_ns.store(0);
  c.stop = &g_stop;
  auto previous = std::signal(SIGINT, OnSigint);
  auto last_print = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  bool printed = false;
  auto progress = [&](const trainer::Progress& p) {
    if (o.quiet) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_print < std::chrono::milliseconds(250) && p.env_steps < p.total_steps) return;
    last_print = now;
    printed = true;
    char success[32] = "";
    if (std::isfinite(p.task_success)) std::snprintf(success, sizeof success, "  success %.0f%%", 100 * p.task_success);
    std::fprintf(stderr, "\r%s/%s steps  %s steps/s  ETA %.0fs  return %.1f%s  eps %.3f   ",
                 Human(static_cast<double>(p.env_steps)).c_str(), Human(static_cast<double>(p.total_steps)).c_str(),
                 Human(p.steps_per_second).c_str(), p.eta_seconds, p.mean_return, success, p.epsilon);
    std::fflush(stderr);
  };
  std::fprintf(stderr, "pbppo train: %s, %s, seed %llu -> %s\n", c.env.c_str(), c.schedule.Describe().c_str(),
               static_cast<unsigned long long>(c.seed), c.out_dir.c_str());
  auto r = trainer::Train(c, progress);
  std::signal(SIGINT, previous);
  if (printed) std::fprintf(stderr, "\n");
  if (!r) return Fail(r.error().message, 1);
  std::printf("env steps %llu (+ %llu evaluation steps = %llu)  wall %.1f s  %.0f steps/s\n",
              static_cast<unsigned long long>(r->env_steps), static_cast<unsigned long long>(r->eval_steps),
              static_cast<unsigned long long>(r->env_steps + r->eval_steps), r->wall_seconds, r->steps_per_second);
  std::printf("final return (last 100 training episodes) %.2f\n", r->final_return);
  std::printf("blob %s/policy.blob\n%s\n", c.out_dir.c_str(), r->plots_note.c_str());
  if (r->interrupted) {
    std::fprintf(stderr, "pbppo train: interrupted; log and last checkpoint are in %s\n", c.out_dir.c_str());
    return 130;
  }
  return 0;
}

void AddEvalOptions(CLI::App& s, EvalOptions& o) {
  s.add_option("blob", o.blob, "Policy blob file")->required();
  s.add_option("--env", o.env, "Environment: pendulum, auv-nav");
  s.add_option("--layout", o.layout, "Obstacle layout of auv-nav: easy, medium, hard, mixed (one drawn per episode)");
  s.add_option("--episodes", o.episodes, "Episodes")->check(CLI::Range(1, 1000000));
  s.add_option("--seed", o.seed, "Seed for the initial states");
  s.add_option("--models", o.models, "Models folder (default: the source tree's models/)");
  s.add_option("--plot", o.plot, "auv-nav: write the trajectories over the map to this PNG");
  s.add_option("--trajectories", o.trajectories, "auv-nav: write every episode's trajectory to this CSV");
  s.add_option("--outcomes", o.outcomes,
               "auv-nav: write one row per episode to this CSV (outcome, targets, time, return, end pose, clearance, "
               "the nearest obstacle and the random obstacles)");
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

int Eval(const EvalOptions& o) {
  auto model = policy::PolicyModel::FromFile(o.blob);
  if (!model) {
    std::fprintf(stderr, "pbppo eval: %s\n", model.error().message.c_str());
    return 1;
  }
  envs::EnvOptions eo;
  eo.models_dir = o.models;
  eo.layout = o.layout;
  auto env = envs::MakeEnv(o.env, eo);
  if (!env) {
    std::fprintf(stderr, "pbppo eval: %s\n", env.error().message.c_str());
    return 2;
  }
  if (auto st = robot::CheckPolicyMatchesLayout(model->description(), (*env)->layout()); !st) {
    std::fprintf(stderr, "pbppo eval: %s: %s\n", o.blob.c_str(), st.error().message.c_str());
    return 1;
  }
  auto* auv = dynamic_cast<envs::AuvNav*>(env->get());
  if ((!o.plot.empty() || !o.trajectories.empty() || !o.outcomes.empty()) && auv == nullptr) {
    std::fprintf(stderr, "pbppo eval: --plot, --trajectories and --outcomes need --env auv-nav (not '%s')\n",
                 o.env.c_str());
    return 2;
  }
  if (!o.plot.empty() && o.layout == "mixed") {
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
  const auto& spec = model->description();
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
      for (std::size_t j = 0; j < act.size(); ++j) {
        const float scale = spec.action_scale[j];
        act[j] = scale != 0.f ? (data->action()[j] - spec.action_offset[j]) / scale : 0.f;
      }
      const envs::StepResult r = e.Step(act, obs);
      ret += r.reward;
      ++steps;
      ++k;
      record();
      if (r.terminated || r.truncated) break;
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
    std::printf("%s on %s: %d episodes, seed %llu\n", o.blob.c_str(), e.name().c_str(), o.episodes,
                static_cast<unsigned long long>(o.seed));
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
