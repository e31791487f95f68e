// The quadruped behind its emulated devices: the Simbody plant (on a stand or on the ground),
// one emulated MIT driver per joint and the base IMU, on the robot's CAN buses (SocketCAN, or an
// in-process network for lock-step runs in one thread). One Tick():
//
//   1. drain each bus (optionally waiting for the frames the controller sent: lock-step);
//   2. hand every command/special frame to its motor, which answers at once with the joint's
//      current state; unknown identifiers and wrong lengths are counted and ignored;
//   3. each motor computes its torque from its latest command; the plant advances one tick;
//   4. send the replies and the IMU's three classic frames.
//
// Faults are scheduled by tick (a scenario's data, sim_hil/quadruped_scenario.hpp): a motor goes
// silent, the IMU stops, a fraction of frames is dropped, a bus goes off, the base is pushed.
// Built once from the robot model; nothing is allocated in Tick() (a push re-initialises the
// Simbody integrator, which does).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/transport/can/can_bus.hpp"
#include "runtime/transport/can/can_table.hpp"
#include "runtime/transport/can/memory_bus.hpp"
#include "sim_hil/devices/mit_motor.hpp"
#include "sim_hil/plants/quadruped_plant.hpp"

namespace pbppo::sim {

enum class HilFaultKind : std::uint8_t { kSilentMotor, kImuSilent, kDropFrames, kBusOff, kPush };

struct HilFault {
  HilFaultKind kind = HilFaultKind::kSilentMotor;
  std::uint64_t tick = 0;              // from this tick on (a push: at it)
  int motor = -1;                      // kSilentMotor: index in the CAN map
  int bus = -1;                        // kBusOff: index in the CAN map
  double probability = 0;              // kDropFrames: of each frame a driver receives
  std::uint32_t max_burst = 0;         // kDropFrames: most consecutive drops (0: unbounded)
  double velocity_mps[3] = {0, 0, 0};  // kPush: added to the base
};

const char* ToString(HilFaultKind kind) noexcept;

struct QuadrupedHilOptions {
  std::vector<std::string> interfaces;       // per bus of the CAN map, e.g. {"vcan0", "vcan1"}; empty: the map's
  can::MemoryCanNetwork* network = nullptr;  // in-process buses instead of SocketCAN
  bool receive_all = true;                   // no kernel filter: strays are seen and counted
  std::uint32_t timeout_ticks = 50;          // drivers' command watchdog
  std::uint64_t seed = 1;                    // the drivers' frame drops
  QuadrupedPlantOptions plant;
  std::vector<double> initial_q_rad;  // per actuated joint; empty: the mount's (stand: 0, ground: default pose)
  double base_xyz[3] = {0, 0, 0.48};  // ground: the base's start position (z above the floor)
  double base_yaw_rad = 0;
  std::vector<HilFault> faults;  // sorted by tick
};

class QuadrupedHil {
 public:
  static Result<std::unique_ptr<QuadrupedHil>> Make(const robot::RobotModel& model, const QuadrupedHilOptions& options);

  // One simulation tick. expect_per_bus (may be null): frames to wait for on each bus before
  // stepping (lock-step), for at most wait_ns. Returns false if the plant failed.
  bool Tick(const std::uint32_t* expect_per_bus, std::int64_t wait_ns) noexcept;
  // Lock-step: the frames the controller sends each tick on each bus (one per motor).
  const std::vector<std::uint32_t>& frames_per_tick() const noexcept { return per_bus_; }

  std::uint64_t tick() const noexcept { return tick_; }
  std::size_t bus_count() const noexcept { return buses_.size(); }
  std::uint32_t sent_last_tick(std::size_t bus) const noexcept { return sent_last_[bus]; }
  const can::BusStats& bus_stats(std::size_t bus) const noexcept { return buses_[bus]->stats(); }
  const std::string& interface(std::size_t bus) const noexcept { return buses_[bus]->interface(); }
  const QuadrupedPlant& plant() const noexcept { return *plant_; }
  std::size_t motor_count() const noexcept { return motors_.size(); }
  const MitMotorState& motor(std::size_t i) const noexcept { return motor_state_[i]; }
  std::size_t joint_of_motor(std::size_t i) const noexcept { return joint_of_motor_[i]; }
  std::uint64_t imu_samples() const noexcept { return imu_samples_; }

 private:
  QuadrupedHil() = default;
  void ApplyFaults() noexcept;
  std::unique_ptr<QuadrupedPlant> plant_;
  can::CanCodecTable table_;
  can::CanRxData rx_data_;
  can::MemoryCanNetwork* network_ = nullptr;
  std::vector<std::unique_ptr<can::CanBus>> buses_;
  std::vector<MitMotorConfig> motors_;
  std::vector<MitMotorState> motor_state_;
  std::vector<std::size_t> joint_of_motor_;
  std::vector<std::vector<can::CanFrame>> rx_, tx_;
  std::vector<std::uint32_t> sent_last_, per_bus_;
  std::vector<double> tau_;
  std::vector<HilFault> faults_;
  std::size_t next_fault_ = 0;
  std::vector<std::uint8_t> bus_off_;
  std::uint32_t imu_bus_ = 0, imu_id_ = 0;
  bool has_imu_ = false, imu_silent_ = false;
  std::uint8_t imu_seq_ = 0;
  std::uint64_t imu_samples_ = 0;
  std::uint64_t tick_ = 0;
};

}  // namespace pbppo::sim
