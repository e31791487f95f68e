#include "policies/cli/train.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "policies/envs/env.hpp"
#include "policies/trainer/trainer.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/robot/io_layout.hpp"

namespace pbppo::cli {
namespace {

std::atomic<bool> g_stop{false};

extern "C" void OnSigint(int) {
  g_stop.store(true);
  std::signal(SIGINT, SIG_DFL);  // a second Ctrl-C ends the process at once
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
  s.add_option("--env", o.env, "Environment: pendulum");
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
  s.add_flag("--quiet", o.quiet, "No progress line");
}

int Train(const TrainOptions& o) {
  trainer::TrainConfig c;
  c.env = o.env;
  c.models_dir = o.models;
  if (!(o.steps >= 1 && o.steps <= 1e12)) return Fail("--steps: " + std::to_string(o.steps) + " is not in [1, 1e12]");
  c.total_steps = static_cast<std::uint64_t>(std::llround(o.steps));
  c.seed = o.seed;
  c.threads = o.threads;
  c.num_envs = o.envs;
  c.rollout_steps = o.rollout;
  c.minibatch = o.minibatch;
  c.epochs = o.epochs;
  c.learning_rate = o.lr;
  c.gamma = o.gamma;
  c.gae_lambda = o.gae_lambda;
  c.ent_coef = o.ent_coef;
  c.vf_coef = o.vf_coef;
  c.max_grad_norm = o.max_grad_norm;
  c.clip_vf = o.clip_vf;
  c.log_std_init = o.log_std_init;
  c.normalize_observations = o.normalize_obs;
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
    if (auto env = envs::MakeEnv(c.env, eo); !env) return Fail(env.error().message);
  }

  g_stop.store(false);
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
    std::fprintf(stderr, "\r%s/%s steps  %s steps/s  ETA %.0fs  return %.1f  eps %.3f   ",
                 Human(static_cast<double>(p.env_steps)).c_str(), Human(static_cast<double>(p.total_steps)).c_str(),
                 Human(p.steps_per_second).c_str(), p.eta_seconds, p.mean_return, p.epsilon);
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
  s.add_option("--env", o.env, "Environment: pendulum");
  s.add_option("--episodes", o.episodes, "Episodes")->check(CLI::Range(1, 1000000));
  s.add_option("--seed", o.seed, "Seed for the initial states");
  s.add_option("--models", o.models, "Models folder (default: the source tree's models/)");
  s.add_flag("--json", o.json, "Print JSON");
}

int Eval(const EvalOptions& o) {
  auto model = policy::PolicyModel::FromFile(o.blob);
  if (!model) {
    std::fprintf(stderr, "pbppo eval: %s\n", model.error().message.c_str());
    return 1;
  }
  envs::EnvOptions eo;
  eo.models_dir = o.models;
  auto env = envs::MakeEnv(o.env, eo);
  if (!env) {
    std::fprintf(stderr, "pbppo eval: %s\n", env.error().message.c_str());
    return 2;
  }
  if (auto st = robot::CheckPolicyMatchesLayout(model->description(), (*env)->layout()); !st) {
    std::fprintf(stderr, "pbppo eval: %s: %s\n", o.blob.c_str(), st.error().message.c_str());
    return 1;
  }
  auto data = policy::MakePolicyData(model.value());
  if (!data) {
    std::fprintf(stderr, "pbppo eval: %s\n", data.error().message.c_str());
    return 1;
  }
  envs::Env& e = **env;
  Rng rng(o.seed);
  std::vector<float> obs(e.observation_size()), act(e.action_size());
  std::vector<double> returns;
  std::uint64_t steps = 0, bad = 0;
  for (int ep = 0; ep < o.episodes; ++ep) {
    e.Reset(rng, obs);
    double ret = 0;
    for (;;) {
      std::copy(obs.begin(), obs.end(), data->observation().begin());
      if (policy::Forward(model.value(), data.value()) != policy::ForwardStatus::kOk) ++bad;
      std::copy(data->action().begin(), data->action().end(), act.begin());
      const envs::StepResult r = e.Step(act, obs);
      ret += r.reward;
      ++steps;
      if (r.terminated || r.truncated) break;
    }
    returns.push_back(ret);
  }
  double mean = 0, var = 0;
  for (double r : returns) mean += r;
  mean /= static_cast<double>(returns.size());
  for (double r : returns) var += (r - mean) * (r - mean);
  const double sd = std::sqrt(var / static_cast<double>(returns.size()));
  const double lo = *std::min_element(returns.begin(), returns.end());
  const double hi = *std::max_element(returns.begin(), returns.end());
  if (o.json) {
    nlohmann::json j;
    j["blob"] = o.blob;
    j["env"] = o.env;
    j["episodes"] = o.episodes;
    j["seed"] = o.seed;
    j["mean_return"] = mean;
    j["std_return"] = sd;
    j["min_return"] = lo;
    j["max_return"] = hi;
    j["steps"] = steps;
    j["forward_problems"] = bad;
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("%s on %s: %d episodes, seed %llu\n", o.blob.c_str(), o.env.c_str(), o.episodes,
                static_cast<unsigned long long>(o.seed));
    std::printf("mean return %.2f  std %.2f  min %.2f  max %.2f  steps %llu  forward problems %llu\n", mean, sd, lo, hi,
                static_cast<unsigned long long>(steps), static_cast<unsigned long long>(bad));
  }
  return 0;
}

}  // namespace pbppo::cli
