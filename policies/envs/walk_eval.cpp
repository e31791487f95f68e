#include "policies/envs/walk_eval.hpp"

#include <cmath>

namespace pbppo::envs {

Result<WalkEvalResult> EvaluateWalk(const policy::PolicyModel& model, QuadrupedWalk& env, const WalkEvalOptions& o) {
  if (auto st = robot::CheckPolicyMatchesLayout(model.description(), env.layout()); !st) return st.error();
  if (o.robots < 1) return MakeError(ErrorCode::kInvalidValue, "robots: " + std::to_string(o.robots) + " is below 1");
  if (env.params().resample_s != kWalkEvalResampleS)
    return MakeError(ErrorCode::kInvalidValue, "the test resamples commands every " +
                                                   std::to_string(kWalkEvalResampleS) + " s, the environment every " +
                                                   std::to_string(env.params().resample_s) + " s");
  auto data = policy::MakePolicyData(model);
  if (!data) return std::move(data).error();
  const policy::PolicySpec& spec = model.description();
  WalkEvalResult res;
  res.robots = o.robots;
  Rng rng(o.seed);
  std::vector<float> obs(env.observation_size()), act(env.action_size());
  std::array<double, 3> sum{}, sum_settled{};
  double returns = 0;
  for (int robot = 0; robot < o.robots; ++robot) {
    env.Reset(rng, obs);
    std::vector<WalkTelemetry> trace;
    std::uint32_t command = env.telemetry().command_index;
    double since_change = 0;
    for (;;) {
      std::copy(obs.begin(), obs.end(), data->observation().begin());
      if (policy::Forward(model, *data) != policy::ForwardStatus::kOk) ++res.forward_problems;
      // The blob gives joint targets (its action map applied); the environment takes policy units.
      for (std::size_t j = 0; j < act.size(); ++j)
        act[j] = (data->action()[j] - spec.action_offset[j]) / spec.action_scale[j];
      const StepResult r = env.Step(act, obs);
      returns += r.reward;
      const WalkTelemetry& t = env.telemetry();
      since_change = t.command_index != command ? 0.0 : since_change + env.params().policy_dt_s();
      command = t.command_index;
      ++res.steps;
      const bool settled = since_change >= o.settle_s - 1e-9;
      res.settled_steps += settled;
      for (int a = 0; a < 3; ++a) {
        const auto k = static_cast<std::size_t>(a);
        const double e = std::fabs(t.command[k] - t.measured[k]);
        sum[k] += e;
        if (settled) sum_settled[k] += e;
      }
      if (robot < o.trace_robots) trace.push_back(t);
      if (r.terminated || r.truncated) break;
    }
    const bool blocks = env.telemetry().on_blocks;
    res.robots_on_blocks += blocks;
    if (env.telemetry().fell) {
      ++res.falls;
      res.falls_on_blocks += blocks;
      res.fall_list.push_back(
          {robot, env.telemetry().time_s, env.telemetry().command, blocks, env.telemetry().base_contact});
    }
    if (robot < o.trace_robots) res.traces.push_back(std::move(trace));
  }
  for (std::size_t k = 0; k < 3; ++k) {
    res.mean_abs_error[k] = sum[k] / static_cast<double>(res.steps);
    res.mean_abs_error_settled[k] =
        res.settled_steps > 0 ? sum_settled[k] / static_cast<double>(res.settled_steps) : std::nan("");
  }
  res.mean_return = returns / o.robots;
  return res;
}

}  // namespace pbppo::envs
