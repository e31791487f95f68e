// The quadruped on a stand behind its emulated devices: the Simbody plant, one emulated MIT
// driver per joint and the base IMU, on the robot's CAN buses (SocketCAN). One Tick():
//
//   1. drain each bus (optionally waiting for the frames the controller sent: lock-step);
//   2. hand every command/special frame to its motor, which answers at once with the joint's
//      current state; unknown identifiers and wrong lengths are counted and ignored;
//   3. each motor computes its torque from its latest command; the plant advances one tick;
//   4. send the replies and the IMU's three classic frames.
//
// Built once from the robot description and the CAN map; nothing is allocated in Tick().
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/can_map.hpp"
#include "runtime/robot/urdf.hpp"
#include "runtime/transport/can/can_table.hpp"
#include "runtime/transport/can/socketcan.hpp"
#include "sim_hil/devices/mit_motor.hpp"
#include "sim_hil/plants/quadruped_plant.hpp"

namespace pbppo::sim {

struct StandHilOptions {
  std::vector<std::string> interfaces;  // per bus of the CAN map, e.g. {"vcan0", "vcan1"}
  bool receive_all = true;              // no kernel filter: strays are seen and counted
  std::uint32_t timeout_ticks = 50;     // drivers' command watchdog
  // Test faults of the emulated drivers.
  double drop_probability = 0;
  std::uint32_t max_drop_burst = 0;
  std::uint64_t seed = 1;
  int silent_motor = -1;  // index in the CAN map
  std::uint64_t silent_from_tick = UINT64_MAX;
  std::vector<double> initial_q_rad;  // per actuated joint; empty: all zero (legs straight down)
};

class StandHil {
 public:
  static Result<std::unique_ptr<StandHil>> Make(const robot::RobotDescription& robot, const robot::CanMap& map,
                                                const StandHilOptions& options);

  // One simulation tick. expect_per_bus (may be null): frames to wait for on each bus before
  // stepping (lock-step), for at most wait_ns. Returns false if the plant failed.
  bool Tick(const std::uint32_t* expect_per_bus, std::int64_t wait_ns) noexcept;

  std::uint64_t tick() const noexcept { return tick_; }
  std::size_t bus_count() const noexcept { return buses_.size(); }
  std::uint32_t sent_last_tick(std::size_t bus) const noexcept { return sent_last_[bus]; }
  const can::BusStats& bus_stats(std::size_t bus) const noexcept { return buses_[bus]->stats(); }
  can::SocketCanBus& bus(std::size_t bus) noexcept { return *buses_[bus]; }
  const QuadrupedStandPlant& plant() const noexcept { return *plant_; }
  std::size_t motor_count() const noexcept { return motors_.size(); }
  const MitMotorState& motor(std::size_t i) const noexcept { return motor_state_[i]; }
  const MitMotorConfig& motor_config(std::size_t i) const noexcept { return motors_[i]; }
  std::size_t joint_of_motor(std::size_t i) const noexcept { return joint_of_motor_[i]; }

 private:
  StandHil() = default;
  std::unique_ptr<QuadrupedStandPlant> plant_;
  can::CanCodecTable table_;
  can::CanRxData rx_data_;
  std::vector<std::unique_ptr<can::SocketCanBus>> buses_;
  std::vector<MitMotorConfig> motors_;
  std::vector<MitMotorState> motor_state_;
  std::vector<std::size_t> joint_of_motor_;
  std::vector<std::vector<can::CanFrame>> rx_, tx_;
  std::vector<std::uint32_t> sent_last_;
  std::vector<double> tau_;
  std::uint32_t imu_bus_ = 0, imu_id_ = 0;
  bool has_imu_ = false;
  std::uint8_t imu_seq_ = 0;
  std::uint64_t tick_ = 0;
};

}  // namespace pbppo::sim
