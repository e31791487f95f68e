#include "policies/envs/walk_eval.hpp"

#include <cmath>

namespace pbppo::envs {

Result<WalkScheduleResult> EvaluateWalkSchedule(const policy::PolicyModel& model, QuadrupedWalk& env,
                                                const std::vector<WalkSchedulePhase>& phases, double settle_s,
                                                std::uint64_t seed) {
  if (auto st = robot::CheckPolicyMatchesLayout(model.description(), env.layout()); !st) return st.error();
  if (phases.empty()) return MakeError(ErrorCode::kInvalidValue, "schedule: no phase");
  const double dt = env.params().policy_dt_s();
  const double end_s = phases.back().start_s + phases.back().duration_s;
  if (end_s > env.params().episode_s + 1e-9)
    return MakeError(ErrorCode::kInvalidValue, "schedule: " + std::to_string(end_s) + " s is longer than an episode (" +
                                                   std::to_string(env.params().episode_s) + " s)");
  auto data = policy::MakePolicyData(model);
  if (!data) return std::move(data).error();
  auto command_at = [&](double t) {
    for (const WalkSchedulePhase& p : phases)
      if (t < p.start_s + p.duration_s) return p.command;
    return phases.back().command;
  };
  WalkScheduleResult res;
  for (const WalkSchedulePhase& p : phases) res.phases.push_back({p, {}, {}, 0});
  Rng rng(seed);
  std::vector<float> obs(env.observation_size()), act(env.action_size());
  env.HoldCommand(command_at(0.0));
  env.Reset(rng, obs);
  std::array<double, 3> last_pos = env.telemetry().position;
  bool first = true;
  const auto steps = static_cast<int>(std::lround(end_s / dt));
  for (int k = 0; k < steps; ++k) {
    std::copy(obs.begin(), obs.end(), data->observation().begin());
    (void)policy::Forward(model, *data);
    robot::ToPolicyUnits(env.layout(), data->action(), act);
    env.HoldCommand(command_at((k + 1) * dt));  // observed at the end of this step
    const StepResult r = env.Step(act, obs);
    const WalkTelemetry& t = env.telemetry();
    res.trace.push_back(t);
    if (!first) res.distance_m += std::hypot(t.position[0] - last_pos[0], t.position[1] - last_pos[1]);
    first = false;
    last_pos = t.position;
    // The step's velocity is judged against the command it was given (the phase at its start).
    const double t0 = k * dt;
    for (WalkSchedulePhaseResult& p : res.phases) {
      if (t0 < p.phase.start_s + settle_s - 1e-9 || t0 >= p.phase.start_s + p.phase.duration_s) continue;
      for (std::size_t a = 0; a < 3; ++a) {
        p.mean_abs_error[a] += std::fabs(p.phase.command[a] - t.measured[a]);
        p.mean_measured[a] += t.measured[a];
      }
      ++p.samples;
    }
    if (r.terminated) {
      res.fell = t.fell;
      res.fell_at_s = t.time_s;
      break;
    }
    if (r.truncated) break;
  }
  for (WalkSchedulePhaseResult& p : res.phases)
    for (std::size_t a = 0; a < 3; ++a)
      if (p.samples > 0) {
        p.mean_abs_error[a] /= static_cast<double>(p.samples);
        p.mean_measured[a] /= static_cast<double>(p.samples);
      }
  return res;
}

Result<WalkEvalResult> EvaluateWalk(const policy::PolicyModel& model, QuadrupedWalk& env, const WalkEvalOptions& o) {
  if (auto st = robot::CheckPolicyMatchesLayout(model.description(), env.layout()); !st) return st.error();
  if (o.robots < 1) return MakeError(ErrorCode::kInvalidValue, "robots: " + std::to_string(o.robots) + " is below 1");
  if (!env.options().paper_test)
    return MakeError(ErrorCode::kInvalidValue,
                     "the environment is not set up for the paper's test (QuadrupedWalkOptions::paper_test)");
  auto data = policy::MakePolicyData(model);
  if (!data) return std::move(data).error();
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
      robot::ToPolicyUnits(env.layout(), data->action(), act);
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
