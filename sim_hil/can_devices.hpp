// A robot's emulated CAN devices, for any plant: one emulated MIT driver per motor of the CAN map
// (sim_hil/devices/mit_motor.hpp) and its first IMU (classic frames), on the map's buses (SocketCAN,
// or an in-process network for lock-step runs in one thread). The plant gives each actuated
// joint's position and velocity (in the description's joint order) and takes their torques; a HIL
// ticks:
//
//   1. Receive: drain each bus (optionally waiting for the frames the controller sent: lock-step);
//      hand every command/special frame to its motor, which answers at once with the joint's
//      current state; unknown identifiers and wrong lengths are counted and ignored;
//   2. Torques: each motor's torque from its latest command; the plant advances one tick;
//   3. Send: the replies and the IMU's sample.
//
// A continuous joint's driver wraps the position it reports into its MIT range (as the transport
// expects, runtime/transport/can/can_transport.hpp). Faults of the devices (a silent motor, frame
// drops, a bus off, a silent IMU) are switched on by the HIL. Built once; nothing is allocated
// per tick.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/transport/can/can_bus.hpp"
#include "runtime/transport/can/can_table.hpp"
#include "runtime/transport/can/imu_codec.hpp"
#include "runtime/transport/can/memory_bus.hpp"
#include "sim_hil/devices/mit_motor.hpp"

namespace pbppo::sim {

struct CanDevicesOptions {
  std::vector<std::string> interfaces;       // per bus of the CAN map, e.g. {"vcan0", "vcan1"}; empty: the map's
  can::MemoryCanNetwork* network = nullptr;  // in-process buses instead of SocketCAN
  bool receive_all = true;                   // no kernel filter: strays are seen and counted
  std::uint32_t timeout_ticks = 50;          // drivers' command watchdog
  std::uint64_t seed = 1;                    // the drivers' frame drops
};

class CanDevices {
 public:
  // `who` prefixes the errors ("quadruped HIL"). Needs the model's description and CAN map.
  static Result<std::unique_ptr<CanDevices>> Make(const robot::RobotModel& model, const CanDevicesOptions& options,
                                                  const std::string& who);

  // 1. q, dq: per actuated joint (the description's order), the plant's state now.
  // expect_per_bus (may be null): frames to wait for on each bus, for at most wait_ns.
  void Receive(const std::uint32_t* expect_per_bus, std::int64_t wait_ns, const double* q, const double* dq,
               std::uint64_t tick) noexcept;
  // 2. Each motor's torque for this tick, into tau (per actuated joint).
  void Torques(const double* q, const double* dq, std::uint64_t tick, double* tau) noexcept;
  // 3. The replies and, when the map has an IMU and it is not silent, its sample.
  void Send(const can::ImuSample& imu) noexcept;

  // Faults, and their ends.
  void SilenceMotor(std::size_t motor, std::uint64_t tick) noexcept { motors_[motor].silent_from_tick = tick; }
  void RestoreMotor(std::size_t motor) noexcept { motors_[motor].silent_from_tick = UINT64_MAX; }
  // A motor whose replies report its position at the top of its MIT range (a broken encoder).
  void BadReplies(std::size_t motor, bool on) noexcept { bad_reply_[motor] = on ? 1 : 0; }
  void DropFrames(double probability, std::uint32_t max_burst) noexcept;
  // A bus goes off (off) or is restarted (the controller reads the matching error frame).
  void SetBusOff(std::size_t bus, bool off = true) noexcept;
  void SilenceImu(bool silent = true) noexcept { imu_silent_ = silent; }

  // Lock-step: the frames the controller sends each tick on each bus (one per motor).
  const std::vector<std::uint32_t>& frames_per_tick() const noexcept { return per_bus_; }
  std::size_t bus_count() const noexcept { return buses_.size(); }
  std::uint32_t sent_last_tick(std::size_t bus) const noexcept { return sent_last_[bus]; }
  const can::BusStats& bus_stats(std::size_t bus) const noexcept { return buses_[bus]->stats(); }
  const std::string& interface(std::size_t bus) const noexcept { return buses_[bus]->interface(); }
  std::size_t motor_count() const noexcept { return motors_.size(); }
  const MitMotorState& motor(std::size_t i) const noexcept { return motor_state_[i]; }
  std::size_t joint_of_motor(std::size_t i) const noexcept { return joint_of_motor_[i]; }
  bool has_imu() const noexcept { return has_imu_; }
  std::uint64_t imu_samples() const noexcept { return imu_samples_; }

 private:
  CanDevices() = default;
  can::CanCodecTable table_;
  can::CanRxData rx_data_;
  can::MemoryCanNetwork* network_ = nullptr;
  std::vector<std::unique_ptr<can::CanBus>> buses_;
  std::vector<MitMotorConfig> motors_;
  std::vector<MitMotorState> motor_state_;
  std::vector<std::size_t> joint_of_motor_;
  std::vector<std::vector<can::CanFrame>> rx_, tx_;
  std::vector<std::uint32_t> sent_last_, per_bus_;
  std::vector<std::uint8_t> bus_off_, bad_reply_;
  std::uint32_t imu_bus_ = 0, imu_id_ = 0;
  bool has_imu_ = false, imu_silent_ = false;
  std::uint8_t imu_seq_ = 0;
  std::uint64_t imu_samples_ = 0;
};

// Ticks a HIL program until `stop`, a failed tick or `max_ticks` (0: no limit): in lock-step
// (`tick` waits for the controller's frames itself) or free-running on absolute deadlines every
// period_ns (ticks that end after their deadline are counted as overruns).
struct HilLoopResult {
  bool ok = true;
  std::uint64_t ticks = 0, overruns = 0;
  double wall_s = 0;
};
HilLoopResult RunHilLoop(const std::function<bool()>& tick, bool lockstep, std::int64_t period_ns,
                         std::uint64_t max_ticks, const std::atomic<bool>& stop);

// One line per motor (frames, replies, drops, watchdog, motor mode, the joint's position) and per
// bus (rx, tx, strays, error frames), for a HIL program's summary.
void PrintDeviceSummary(const CanDevices& devices, const robot::CanMap& map, const double* q);

}  // namespace pbppo::sim
