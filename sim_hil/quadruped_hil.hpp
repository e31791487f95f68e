// The quadruped behind its emulated devices: the Simbody plant (on a stand or on the ground)
// and, on the robot's CAN buses, one emulated MIT driver per joint and the base IMU
// (sim_hil/can_devices.hpp: SocketCAN, or an in-process network for lock-step runs in one
// thread). One Tick(): the devices receive and answer the controller's frames, each motor's
// torque is applied, the plant advances one tick, the replies and the IMU's sample go out.
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
#include "sim_hil/can_devices.hpp"
#include "sim_hil/plants/quadruped_plant.hpp"

namespace pbppo::sim {

// Each fault, and the event that ends it (a motor answers again, the IMU comes back, a bus is
// restarted, a motor's replies are good again; frame drops end with drop_frames 0).
enum class HilFaultKind : std::uint8_t {
  kSilentMotor,
  kImuSilent,
  kDropFrames,
  kBusOff,
  kPush,
  kBusRestored,
  kMotorBack,
  kImuBack,
  kBadReplies,  // a motor reports its position at the top of its MIT range (out of the joint's bounds)
  kGoodReplies,
};

struct HilFault {
  HilFaultKind kind = HilFaultKind::kSilentMotor;
  std::uint64_t tick = 0;              // from this tick on (a push: at it)
  int motor = -1;                      // kSilentMotor, kMotorBack, kBadReplies, kGoodReplies: in the CAN map
  int bus = -1;                        // kBusOff, kBusRestored: index in the CAN map
  double probability = 0;              // kDropFrames: of each frame a driver receives
  std::uint32_t max_burst = 0;         // kDropFrames: most consecutive drops (0: unbounded)
  double velocity_mps[3] = {0, 0, 0};  // kPush: added to the base
};

const char* ToString(HilFaultKind kind) noexcept;

struct QuadrupedHilOptions : CanDevicesOptions {
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
  const std::vector<std::uint32_t>& frames_per_tick() const noexcept { return devices_->frames_per_tick(); }

  std::uint64_t tick() const noexcept { return tick_; }
  std::size_t bus_count() const noexcept { return devices_->bus_count(); }
  std::uint32_t sent_last_tick(std::size_t bus) const noexcept { return devices_->sent_last_tick(bus); }
  const can::BusStats& bus_stats(std::size_t bus) const noexcept { return devices_->bus_stats(bus); }
  const std::string& interface(std::size_t bus) const noexcept { return devices_->interface(bus); }
  const QuadrupedPlant& plant() const noexcept { return *plant_; }
  const CanDevices& devices() const noexcept { return *devices_; }
  std::size_t motor_count() const noexcept { return devices_->motor_count(); }
  const MitMotorState& motor(std::size_t i) const noexcept { return devices_->motor(i); }
  std::size_t joint_of_motor(std::size_t i) const noexcept { return devices_->joint_of_motor(i); }
  std::uint64_t imu_samples() const noexcept { return devices_->imu_samples(); }

 private:
  QuadrupedHil() = default;
  void ApplyFaults() noexcept;
  std::unique_ptr<QuadrupedPlant> plant_;
  std::unique_ptr<CanDevices> devices_;
  std::vector<double> q_, dq_, tau_;  // per joint
  std::vector<HilFault> faults_;
  std::size_t next_fault_ = 0;
  std::uint64_t tick_ = 0;
};

}  // namespace pbppo::sim
