#include "policies/cli/eval.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "policies/cli/train.hpp"
#include "policies/envs/registry.hpp"
#include "runtime/core/cli_checks.hpp"
#include "runtime/policy/kernel_option.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/robot/io_layout.hpp"

namespace pbppo::cli {

void AddEvalOptions(CLI::App& s, EvalOptions& o) {
  s.add_option("blob", o.blob, "Policy blob file")->required();
  AddEnvOptions(s, o.env, envs::EnvFlag::kEval);
  std::string sizes;
  for (const envs::EnvSpec& e : envs::Environments())
    if (e.evaluation.default_episodes != 100 || e.evaluation.episodes_are != "episodes")
      sizes += "; " + e.name + ": " + e.evaluation.episodes_are + ", default " +
               std::to_string(e.evaluation.default_episodes);
  s.add_option("--episodes", o.episodes, "Episodes (default 100" + sizes + ")")->check(CLI::Range(1, 1000000));
  s.add_option("--seed", o.seed, "Seed for the initial states")->check(cli_checks::NonNegativeInteger());
  policy::AddKernelOption(s, o.kernel);
  s.add_flag("--json", o.json, "Print JSON");
}

namespace {

// Wilson score interval for a binomial proportion at 95 %.
std::pair<double, double> Wilson95(double k, double n) {
  const double z = 1.959963985, p = k / n, d = 1 + z * z / n;
  const double c = (p + z * z / (2 * n)) / d, h = z * std::sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d;
  return {std::max(0.0, c - h), std::min(1.0, c + h)};
}

}  // namespace

int Eval(const EvalOptions& o) {
  // The environment and its flags first (bad input: exit 2), then the blob (exit 1).
  auto resolved = envs::ResolveEnvOptions(o.env);
  if (!resolved) {
    std::fprintf(stderr, "pbppo eval: %s\n", resolved.error().message.c_str());
    return 2;
  }
  const envs::EnvSpec& spec = *envs::FindEnv(o.env.name);
  auto env = spec.make(*resolved);
  if (!env) {
    std::fprintf(stderr, "pbppo eval: %s\n", env.error().message.c_str());
    return 2;
  }
  policy::LoadOptions load;
  load.kernel = policy::KernelOption(o.kernel);
  auto model = policy::PolicyModel::FromFile(o.blob, load);
  if (!model) {
    std::fprintf(stderr, "pbppo eval: %s\n", model.error().message.c_str());
    return 1;
  }
  envs::Env& e = **env;
  if (auto st = robot::CheckPolicyMatchesLayout(model->description(), e.layout()); !st) {
    std::fprintf(stderr, "pbppo eval: %s: %s\n", o.blob.c_str(), st.error().message.c_str());
    return 1;
  }
  envs::EvalRequest request;
  request.blob = o.blob;
  request.model = &model.value();
  request.env = &resolved.value();
  request.episodes = o.episodes;
  request.seed = o.seed;
  request.json = o.json;
  if (spec.evaluation.run) return spec.evaluation.run(request, e);
  std::unique_ptr<envs::EpisodeHooks> hooks;
  if (spec.evaluation.hooks) {
    auto h = spec.evaluation.hooks(request, e);
    if (!h) {
      std::fprintf(stderr, "pbppo eval: %s\n", h.error().message.c_str());
      return 2;
    }
    hooks = std::move(h).value();
  }
  if (!hooks) hooks = std::make_unique<envs::EpisodeHooks>();
  const bool through_ends = hooks->through_ends();
  const int episodes = o.episodes > 0 ? o.episodes : spec.evaluation.default_episodes;
  auto data = policy::MakePolicyData(model.value());
  if (!data) {
    std::fprintf(stderr, "pbppo eval: %s\n", data.error().message.c_str());
    return 1;
  }
  // The blob outputs commands (the layout's map applied); the environment takes policy units.
  Rng rng(o.seed);
  std::vector<float> obs(e.observation_size()), act(e.action_size());
  std::vector<double> returns;
  std::uint64_t steps = 0, bad = 0;
  int successes = 0, failures = 0, timeouts = 0, goals = 0;
  double success_time = 0;
  for (int ep = 0; ep < episodes; ++ep) {
    e.Reset(rng, obs);
    hooks->Started(ep, e);
    double ret = 0;
    long k = 0;
    for (;;) {
      std::copy(obs.begin(), obs.end(), data->observation().begin());
      if (policy::Forward(model.value(), data.value()) != policy::ForwardStatus::kOk) ++bad;
      robot::ToPolicyUnits(e.layout(), data->action(), act);
      const envs::StepResult r = e.Step(act, obs);
      ret += r.reward;
      ++steps;
      ++k;
      hooks->Stepped(ep, k, e);
      if (through_ends ? k >= static_cast<long>(e.max_episode_steps()) : (r.terminated || r.truncated)) break;
    }
    returns.push_back(ret);
    const envs::EpisodeInfo info = e.episode_info();
    if (info.available) {
      successes += info.success;
      failures += info.failure;
      timeouts += !info.success && !info.failure;
      goals += info.goals;
      if (info.success) success_time += info.time_s;
    }
    hooks->Ended(ep, e, ret);
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
  // What the environment adds: its keys in the JSON report, its lines in the text one.
  nlohmann::json extra = nlohmann::json::object();
  std::string extra_text;
  const std::string problem =
      hooks->Finish(e, envs::EvalTotals{episodes, o.seed, successes, failures, timeouts}, extra, extra_text);
  if (!problem.empty()) std::fprintf(stderr, "pbppo eval: %s\n", problem.c_str());
  if (o.json) {
    nlohmann::json j;
    j["blob"] = o.blob;
    j["env"] = e.name();
    j["episodes"] = episodes;
    j["seed"] = o.seed;
    j["mean_return"] = mean;
    j["std_return"] = sd;
    j["min_return"] = lo;
    j["max_return"] = hi;
    j["steps"] = steps;
    j["through_ends"] = through_ends;
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
    j.update(extra);
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf(
        "%s on %s: %d episodes%s, seed %llu, %s kernel\n", o.blob.c_str(), e.name().c_str(), episodes,
        through_ends ? (" of " + std::to_string(e.max_episode_steps()) + " steps through episode ends").c_str() : "",
        static_cast<unsigned long long>(o.seed), policy::ToString(model->kernel()));
    if (task) {
      std::printf(
          "success %d/%d = %.1f%% (95%% CI %.1f-%.1f%%)  collisions %d  timeouts %d  targets/episode %.2f  "
          "mean time (successes) %.1f s\n",
          successes, episodes, 100 * successes / n, 100 * ci_lo, 100 * ci_hi, failures, timeouts, goals / n, mean_time);
    }
    std::printf("mean return %.2f  std %.2f  min %.2f  max %.2f  steps %llu  forward problems %llu\n", mean, sd, lo, hi,
                static_cast<unsigned long long>(steps), static_cast<unsigned long long>(bad));
    std::printf("%s", extra_text.c_str());
  }
  return 0;
}

}  // namespace pbppo::cli
