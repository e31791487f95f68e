// The AUV's transport: its DDS link (runtime/transport/dds/auv_dds_link.hpp) mapped onto the robot
// model (models/auv/robot.yaml). Read takes the newest sensor sample: a new one (another tick or
// stamp than the last) writes the sensor stream's fields (by name: x_m, sonar_3_m, ...) and marks
// it fresh; the link's health is lost when the vehicle is gone (no matched writer, or no sample
// for lost_after), degraded when samples were rejected or commands dropped since the last tick.
// Write queues the command: the tick, the sample it answers, surge_speed and yaw_rate, the mode.
// No allocation, lock or blocking call.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <thread>

#include "firmware/auv/sample_fields.hpp"
#include "runtime/core/result.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/robot/robot_data.hpp"
#include "runtime/rt/tick_clock.hpp"
#include "runtime/transport/dds/auv_dds_link.hpp"

namespace pbppo::auv {

// The controller's status for the vehicle (models/auv/idl/AuvControllerStatus.idl), from another
// thread than the tick.
robot::AuvControllerStatus StatusOf(const loop::LoopData& loop);

class AuvTransport final : public robot::Transport {
 public:
  // `transport`: the robot.yaml transport (kind dds, messages auv) this is. Errors name the field
  // the robot lacks.
  static Result<std::unique_ptr<AuvTransport>> Create(const robot::RobotModel& model, const std::string& transport,
                                                      dds::AuvDdsLink& link, std::int64_t lost_after_ns);

  void Read(const robot::RobotModel& model, robot::RobotData& data) noexcept override;
  void Write(const robot::RobotModel& model, robot::RobotData& data) noexcept override;

  std::uint64_t send_failures() const noexcept { return send_failures_; }

 private:
  AuvTransport(dds::AuvDdsLink& link, std::int64_t lost_after_ns) : link_(link), lost_after_ns_(lost_after_ns) {}
  dds::AuvDdsLink& link_;
  std::int64_t lost_after_ns_;
  std::uint32_t link_index_ = 0;
  SampleFields fields_;
  std::uint32_t surge_command_ = 0, yaw_command_ = 0;
  dds::AuvSensorInput in_;
  bool have_ = false;
  std::uint64_t last_tick_ = 0;
  std::int64_t last_stamp_ = 0;
  std::uint64_t rejected_ = 0, dropped_ = 0, send_failures_ = 0;
};

// Lock-step with the vehicle (a simulator in lock-step): one tick per new sample, or one per
// timeout without a sample (a vanished vehicle is then seen as stale samples); the vehicle's
// episode end stops the loop (loop::RequestStop) after the tick that answers it.
std::thread PaceLockStep(dds::AuvDdsLink& link, rt::LockStepClock& clock, const std::atomic<bool>& done,
                         std::int64_t timeout_ns, std::atomic<bool>* episode_end);

}  // namespace pbppo::auv
