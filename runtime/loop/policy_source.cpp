#include "runtime/loop/policy_source.hpp"

#include <algorithm>

#include "runtime/core/clock.hpp"

namespace pbppo::loop {

PolicySource::PolicySource(const policy::PolicyModel& policy, policy::PolicyData data, robot::SignalProgram signals,
                           robot::ObservationBuilder builder)
    : policy_(policy), data_(std::move(data)), signals_(std::move(signals)), builder_(std::move(builder)) {}

Result<std::unique_ptr<PolicySource>> PolicySource::Create(const robot::RobotModel& m,
                                                           const policy::PolicyModel& policy) {
  if (!m.io) return MakeError(ErrorCode::kMismatch, m.path + ": files: no io_layout (the policy's layout)");
  const robot::IoLayout& layout = *m.io;
  if (auto st = robot::CheckPolicyMatchesLayout(policy.description(), layout); !st) return st.error();
  auto signals = robot::SignalProgram::ForLayout(m, layout);
  if (!signals) return std::move(signals).error();
  auto builder = robot::ObservationBuilder::Create(layout, signals->names());
  if (!builder) return std::move(builder).error();
  auto data = policy::MakePolicyData(policy);
  if (!data) return std::move(data).error();
  std::unique_ptr<PolicySource> s(new PolicySource(policy, std::move(*data), std::move(*signals), std::move(*builder)));
  for (std::size_t i = 0; i < layout.actions.size(); ++i) {
    const robot::ActionElement& a = layout.actions[i];
    const int c = m.CommandIndex(a.command);
    for (const robot::MotorSpec& mo : m.motors)
      if (c < 0 && mo.velocity_commanded() && (a.command == "q_des_" + mo.joint || a.command == "kp_" + mo.joint))
        return MakeError(ErrorCode::kMismatch, "io layout '" + layout.robot + "': actions[" + std::to_string(i) +
                                                   "] '" + a.name + "': command '" + a.command + "': joint '" +
                                                   mo.joint + "' is velocity-commanded" +
                                                   (mo.continuous ? " (continuous)" : "") +
                                                   ": it takes no position target (command dq_des_" + mo.joint + ")");
    if (c < 0) {
      std::string known;
      for (const auto& k : m.commands) known += (known.empty() ? "" : ", ") + k.name;
      return MakeError(ErrorCode::kMismatch, "io layout '" + layout.robot + "': actions[" + std::to_string(i) + "] '" +
                                                 a.name + "': command '" + a.command +
                                                 "' is not a command of the robot (" + known + ")");
    }
    for (std::uint32_t prev : s->command_of_action_)
      if (prev == static_cast<std::uint32_t>(c))
        return MakeError(ErrorCode::kMismatch, "io layout '" + layout.robot + "': actions[" + std::to_string(i) +
                                                   "]: command '" + a.command + "' appears twice");
    s->command_of_action_.push_back(static_cast<std::uint32_t>(c));
    s->scale_.push_back(a.scale);
    s->offset_.push_back(a.offset);
  }
  for (std::int32_t stream : s->signals_.streams())
    if (stream >= 0 &&
        std::find(s->streams_.begin(), s->streams_.end(), static_cast<std::uint32_t>(stream)) == s->streams_.end())
      s->streams_.push_back(static_cast<std::uint32_t>(stream));
  s->values_.assign(s->signals_.size(), 0.0);
  s->obs_.assign(s->builder_.observation_size(), 0.0f);
  s->action_.assign(layout.actions.size(), 0.0f);
  s->last_action_.assign(layout.actions.size(), 0.0f);
  return s;
}

void PolicySource::Start(const robot::RobotModel&, const robot::RobotData& d, LoopData&) noexcept {
  start_tick_ = d.tick;
  first_ = true;
  have_action_ = false;
  status_ = policy::ForwardStatus::kOk;
  std::fill(last_action_.begin(), last_action_.end(), 0.0f);
  data_.ResetState();  // a recurrent policy starts each run from its clean state
}

bool PolicySource::Compute(const robot::RobotModel& m, const robot::RobotData& d, LoopData& loop,
                           std::span<double> desired) noexcept {
  const bool due = m.policy_trigger >= 0 ? d.fresh[static_cast<std::size_t>(m.policy_trigger)] != 0
                                         : (d.tick - start_tick_) % m.policy_period_ticks == 0;
  if (due) {
    rt::TickProfiler& prof = loop.profiler();
    const std::int64_t t0 = MonotonicNs();
    bool valid = true;
    for (std::uint32_t s : streams_) valid = valid && d.streams[s].seen && d.streams[s].invalid_input < 0;
    if (valid) {
      signals_.Compute(d.fields, last_action_, values_.data());
      builder_.Build(values_.data(), first_, obs_.data());
      first_ = false;
    }
    const std::int64_t t1 = MonotonicNs();
    if (!first_) {  // an observation exists
      std::span<float> in = data_.observation();
      std::copy(obs_.begin(), obs_.end(), in.begin());
      status_ = policy::Forward(policy_, data_);
      const std::span<const float> a = data_.action();
      std::copy(a.begin(), a.end(), action_.begin());
      for (std::size_t i = 0; i < action_.size(); ++i)
        last_action_[i] = static_cast<float>((static_cast<double>(action_[i]) - offset_[i]) / scale_[i]);
      have_action_ = true;
      ++runs_;
    }
    prof.Record(rt::Stage::kObserve, t1 - t0);
    prof.Record(rt::Stage::kInfer, MonotonicNs() - t1);
  }
  if (have_action_)
    for (std::size_t i = 0; i < action_.size(); ++i) desired[command_of_action_[i]] = static_cast<double>(action_[i]);
  for (const robot::MotorSpec& mo : m.motors) {  // the gains the policy was trained with (position motors)
    if (mo.policy_kp >= 0) desired[mo.kp] = mo.policy_kp;
    if (mo.policy_kd >= 0) desired[mo.kd] = mo.policy_kd;
  }
  return true;
}

void PolicySource::SaveState(StateWriter& o) const noexcept {
  o.Put(start_tick_);
  o.Put(runs_);
  o.Put(first_);
  o.Put(have_action_);
  o.Put(status_);
  o.PutSpan<float>(builder_.history());
  o.PutSpan<float>(obs_);
  o.PutSpan<float>(action_);
  o.PutSpan<float>(last_action_);
  for (std::uint64_t v : {data_.forward_calls, data_.nonfinite_observations, data_.nonfinite_actions}) o.Put(v);
  if (policy_.recurrent()) o.PutSpan<float>(data_.state());  // only then: feed-forward records as before
}

bool PolicySource::LoadState(StateReader& in) {
  return in.Get(start_tick_, "policy.start_tick") && in.Get(runs_, "policy.runs") &&
         in.GetBool(first_, "policy.first") && in.GetBool(have_action_, "policy.have_action") &&
         in.GetBelow(status_, policy::kForwardStatusCount, "policy.status") &&
         in.GetSpan<float>(builder_.history(), "policy.history") && in.GetSpan<float>(obs_, "policy.observation") &&
         in.GetSpan<float>(action_, "policy.action") && in.GetSpan<float>(last_action_, "policy.last_action") &&
         in.Get(data_.forward_calls, "policy.forward_calls") &&
         in.Get(data_.nonfinite_observations, "policy.nonfinite_observations") &&
         in.Get(data_.nonfinite_actions, "policy.nonfinite_actions") &&
         (!policy_.recurrent() || in.GetSpan<float>(data_.state(), "policy.recurrent_state"));
}

const char* PolicySource::failure() const noexcept {
  return status_ == policy::ForwardStatus::kOk ? nullptr : policy::ToString(status_);
}

}  // namespace pbppo::loop
