// The quadruped's operator transport: velocity commands over DDS (runtime/transport/dds/
// operator_dds_link.hpp) mapped onto the robot model's velocity_command stream (fields
// command_vx, command_vy, command_yaw_rate; models/quadruped/robot.yaml). Read takes the newest
// command: a new one writes the fields and marks the stream fresh; the supervisor judges the
// rest (values beyond the fields' bounds or not finite: an invalid sample; silence: a stale
// stream, then safe-stop). No allocation, lock or blocking call.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "runtime/core/result.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/robot/robot_data.hpp"
#include "runtime/transport/dds/operator_dds_link.hpp"

namespace pbppo::quadruped {

class OperatorTransport final : public robot::Transport {
 public:
  // Errors name what the robot lacks (the stream or one of its fields).
  static Result<std::unique_ptr<OperatorTransport>> Create(const robot::RobotModel& model, dds::OperatorDdsLink& link);
  void Read(const robot::RobotModel& model, robot::RobotData& data) noexcept override;
  void Write(const robot::RobotModel&, robot::RobotData&) noexcept override {}

  // Any thread: how many commands were taken, and the one in force (zeros before the first).
  std::uint64_t commands() const noexcept { return commands_.load(std::memory_order_relaxed); }
  robot::VelocityCommand last() const noexcept;

 private:
  explicit OperatorTransport(dds::OperatorDdsLink& link) : link_(link) {}
  dds::OperatorDdsLink& link_;
  std::uint32_t stream_ = 0, vx_ = 0, vy_ = 0, yaw_rate_ = 0;
  dds::VelocityCommandInput in_;
  std::uint64_t version_ = 0;
  std::atomic<std::uint64_t> commands_{0}, seq_{0};
  std::atomic<double> vx_now_{0}, vy_now_{0}, yaw_rate_now_{0};
};

// The controller's status for the operator, from another thread than the tick (`op`: the operator
// transport, null when unbound).
robot::QuadrupedStatus StatusOf(const loop::LoopData& loop, const OperatorTransport* op);

// Publishes StatusOf(loop, op) on `link` every `period_ns` from a thread of its own, and a last
// one when destroyed (a simulator's or a test's controller; pbppo-controller's status thread does
// the same among its other work).
class StatusPublisher {
 public:
  StatusPublisher(dds::OperatorDdsLink& link, const loop::LoopData& loop, const OperatorTransport* op,
                  std::int64_t period_ns);
  ~StatusPublisher();
  StatusPublisher(const StatusPublisher&) = delete;
  StatusPublisher& operator=(const StatusPublisher&) = delete;

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace pbppo::quadruped
