#include "runtime/loop/policy_set.hpp"

#include <algorithm>

namespace pbppo::loop {

PolicySet::PolicySet(const robot::RobotModel& robot, std::vector<std::unique_ptr<CommandSource>> sources)
    : sources_(std::move(sources)),
      rule_(robot.op.switch_rule),
      rule_ticks_(robot.op.switch_ticks),
      last_(robot.commands.size(), 0.0),
      from_(robot.commands.size(), 0.0) {}

void PolicySet::Start(const robot::RobotModel& model, const robot::RobotData& data, LoopData& loop) noexcept {
  // A run (arming, a re-arm, the dead-man held again) starts the source in force, clean; a switch
  // under way is over (nothing to blend from), one asked is still to come.
  left_ = 0;
  have_last_ = false;
  sources_[current_]->Start(model, data, loop);
}

bool PolicySet::Switch() noexcept {
  if (sources_.size() < 2) return false;
  if (pending_ < 0xffffffffu) ++pending_;
  return true;
}

bool PolicySet::Compute(const robot::RobotModel& model, const robot::RobotData& data, LoopData& loop,
                        std::span<double> desired) noexcept {
  if (pending_ > 0 && left_ == 0) {  // begin a switch: from what was sent last
    --pending_;
    ++switches_;
    current_ = (current_ + 1) % sources_.size();
    if (have_last_) {
      std::copy(last_.begin(), last_.end(), from_.begin());
    } else {
      std::copy(desired.begin(), desired.end(), from_.begin());
    }
    left_ = rule_ticks_;
    // Blending, the new source runs from now; holding, from the hold's end (below).
    if (rule_ == robot::SwitchRule::kBlend || left_ == 0) sources_[current_]->Start(model, data, loop);
  }
  bool more = true;
  if (left_ > 0 && rule_ == robot::SwitchRule::kHold) {
    --left_;  // the phase's neutral commands (the default pose), as they came in
    if (left_ == 0) sources_[current_]->Start(model, data, loop);  // it starts after the hold, clean
  } else {
    more = sources_[current_]->Compute(model, data, loop, desired);
    if (left_ > 0) {  // blend: w from 1/N up to 1
      const double w = 1.0 - static_cast<double>(left_ - 1) / static_cast<double>(rule_ticks_);
      for (std::size_t k = 0; k < desired.size(); ++k) desired[k] = from_[k] + w * (desired[k] - from_[k]);
      --left_;
    }
  }
  std::copy(desired.begin(), desired.end(), last_.begin());
  have_last_ = true;
  return more;
}

const char* PolicySet::failure() const noexcept {
  return sources_[current_]->failure();
}

void PolicySet::SaveState(StateWriter& out) const noexcept {
  out.Put(static_cast<std::uint32_t>(current_));
  out.Put(pending_);
  out.Put(left_);
  out.Put(switches_);
  out.Put(have_last_);
  out.PutSpan<double>(last_);
  out.PutSpan<double>(from_);
  for (const auto& s : sources_) s->SaveState(out);
}

bool PolicySet::LoadState(StateReader& in) {
  std::uint32_t current = 0;
  if (!in.GetBelow(current, static_cast<std::uint32_t>(sources_.size()), "policy_set.current")) return false;
  current_ = current;
  if (!(in.Get(pending_, "policy_set.pending") && in.Get(left_, "policy_set.left") &&
        in.Get(switches_, "policy_set.switches") && in.GetBool(have_last_, "policy_set.have_last") &&
        in.GetSpan<double>(last_, "policy_set.last") && in.GetSpan<double>(from_, "policy_set.from")))
    return false;
  for (const auto& s : sources_)
    if (!s->LoadState(in)) return false;
  return true;
}

}  // namespace pbppo::loop
