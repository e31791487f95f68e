// Several command sources in one controller (several policies: pbppo-controller --policy A
// --switch-policy B ...), one of them running at a time; the operator's switch request
// (robot.yaml operator.switch_policy; CommandSource::Switch) moves to the next in turn, back to
// the first after the last. Every source was loaded and self-tested at start; a switch allocates
// nothing and happens at the next run tick, by the robot file's rule (operator.switch):
//
//   blend   the new source starts clean (a policy's history, last action and recurrent state) and
//           its commands are blended in over the rule's ticks: (1 - w) x the command at the switch
//           + w x the new source's, w rising linearly from 1/N to 1, then the new source alone
//   hold    the phase's neutral commands (the default pose) for the rule's ticks, then the new
//           source, started clean
//
// A switch asked while another is under way is taken after it. The set's state (which source, the
// switch under way, every source's own state) is saved in a log's snapshot.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "runtime/loop/loop.hpp"
#include "runtime/robot/robot_model.hpp"

namespace pbppo::loop {

class PolicySet final : public CommandSource {
 public:
  // `sources` (at least two) in the order a switch moves through them; the first runs first.
  PolicySet(const robot::RobotModel& robot, std::vector<std::unique_ptr<CommandSource>> sources);

  void Start(const robot::RobotModel& model, const robot::RobotData& data, LoopData& loop) noexcept override;
  bool Compute(const robot::RobotModel& model, const robot::RobotData& data, LoopData& loop,
               std::span<double> desired) noexcept override;
  const char* failure() const noexcept override;
  bool Switch() noexcept override;
  void SaveState(StateWriter& out) const noexcept override;
  bool LoadState(StateReader& in) override;

  std::size_t current() const noexcept { return current_; }
  std::uint64_t switches() const noexcept { return switches_; }
  std::size_t size() const noexcept { return sources_.size(); }

 private:
  std::vector<std::unique_ptr<CommandSource>> sources_;
  robot::SwitchRule rule_;
  std::uint32_t rule_ticks_ = 0;
  std::size_t current_ = 0;
  std::uint32_t pending_ = 0;        // switches asked, not begun
  std::uint32_t left_ = 0;           // ticks of the switch under way (blend or hold) still to go
  std::uint64_t switches_ = 0;       // begun
  std::vector<double> last_, from_;  // the last command out; the command at the switch
  bool have_last_ = false;
};

}  // namespace pbppo::loop
