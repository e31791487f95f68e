// A policy as the loop's command source: on its period (robot.yaml timing.policy_period_s) or on
// each new sample of its trigger stream (timing.policy_trigger), the layout's signals -> the
// observation (robot::SignalProgram, robot::ObservationBuilder, straight into PolicyData's input)
// -> Forward -> the action, whose elements are the layout's commands (the blob applies the
// layout's action map). Between runs the action is held. Forward's status is the supervisor's
// inference input. An observation is built only from streams that have a sample and pass the
// sample check; the first one fills the history (the start of the run phase).
//
// A recurrent policy's state starts clean at each Start() (arming) and is part of the saved state,
// so a recorded run replays from any snapshot.
//
// last_action_<name> signals see the previous run's action in policy units: (command - offset) /
// scale through the layout's action map (0 before the first run).
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/robot/observation_builder.hpp"
#include "runtime/robot/signals.hpp"

namespace pbppo::loop {

class PolicySource final : public CommandSource {
 public:
  // Refuses a policy trained for another layout (naming the first difference), a layout signal
  // the robot does not offer, an action whose command the robot does not have.
  static Result<std::unique_ptr<PolicySource>> Create(const robot::RobotModel& robot,
                                                      const policy::PolicyModel& policy);

  void Start(const robot::RobotModel& model, const robot::RobotData& data, LoopData& loop) noexcept override;
  bool Compute(const robot::RobotModel& model, const robot::RobotData& data, LoopData& loop,
               std::span<double> desired) noexcept override;
  const char* failure() const noexcept override;
  // The observation's history, the last observation and action, when the next run is due, and a
  // recurrent policy's state.
  void SaveState(StateWriter& out) const noexcept override;
  bool LoadState(StateReader& in) override;

  std::span<const float> observation() const noexcept { return obs_; }  // of the last run
  std::span<const float> action() const noexcept { return action_; }    // of the last run
  std::uint64_t runs() const noexcept { return runs_; }

 private:
  PolicySource(const policy::PolicyModel& policy, policy::PolicyData data, robot::SignalProgram signals,
               robot::ObservationBuilder builder);
  const policy::PolicyModel& policy_;
  policy::PolicyData data_;
  robot::SignalProgram signals_;
  robot::ObservationBuilder builder_;
  std::vector<std::uint32_t> command_of_action_;
  std::vector<double> scale_, offset_;  // the layout's action map (last_action)
  std::vector<std::uint32_t> streams_;  // the streams the observation reads
  std::vector<double> values_;
  std::vector<float> obs_, action_, last_action_;
  std::uint64_t start_tick_ = 0, runs_ = 0;
  bool first_ = true, have_action_ = false;
  policy::ForwardStatus status_ = policy::ForwardStatus::kOk;
};

}  // namespace pbppo::loop
