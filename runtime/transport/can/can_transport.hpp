// The CAN transport of a robot with MIT motors and IMUs (its CAN map): one SocketCAN bus per map
// bus (or an in-process bus: memory_bus.hpp), the controller's id -> codec table, and the robot's fields and commands.
//
//   Read   drains every bus (with lock-step, first waits, bounded, for the frames the peer owes
//          this tick), decodes replies and IMU samples into the motors' and IMUs' fields and marks
//          their streams fresh; each bus's health is a link of the transport: a fault on bus-off
//          or socket errors, degraded on dropped frames or error-passive. A continuous joint's
//          driver wraps its position in the MIT range [p_min, p_max): its q_ field is the
//          multi-turn angle, unwrapped from one reply to the next (whole turns of the range
//          counted; the first reply is the start).
//   Write  per motor: enter motor mode, a command frame from its q_des_, dq_des_, kp_, kd_, tau_ff_ commands
//          (a velocity-commanded motor: p_des 0, kp 0), or exit motor mode (RobotData::motors); one
//          sendmmsg per bus.
//
// Every frame sent and received can go to a candump log. Nothing is allocated after Open.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/robot_data.hpp"
#include "runtime/transport/can/can_table.hpp"
#include "runtime/transport/can/candump_log.hpp"
#include "runtime/transport/can/memory_bus.hpp"
#include "runtime/transport/can/socketcan.hpp"

namespace pbppo::can {

struct CanTransportOptions {
  std::vector<std::string> interfaces;      // per bus of the CAN map; empty: the map's own
  bool receive_all = false;                 // no kernel filter: strays are seen and counted
  std::string candump_path;                 // every frame sent and received ("": none)
  std::size_t command_record_capacity = 0;  // commands kept for RecordedCommands() (0: none)
  // In-process buses instead of SocketCAN (bus b of the map is the network's bus b; interfaces
  // are then the network's bus names). The network must outlive the transport.
  MemoryCanNetwork* network = nullptr;
};

// "can0,can1" (a command line's interface list) -> {"can0", "can1"}; "" -> {} (the map's own).
// Errors quote the list when a name is empty.
Result<std::vector<std::string>> ParseInterfaceList(const std::string& list);

// A command as the transport encoded it (before quantisation).
struct CommandRecord {
  std::uint64_t tick = 0;
  std::uint32_t motor = 0;
  double q_rad = 0, dq_rad_s = 0, kp = 0, kd = 0, tau_nm = 0;
};

class CanTransport final : public robot::Transport {
 public:
  // `transport`: the robot.yaml transport (kind can) this is. Errors name the interface and call.
  static Result<std::unique_ptr<CanTransport>> Open(const robot::RobotModel& model, const std::string& transport,
                                                    const CanTransportOptions& options);
  ~CanTransport() override;

  void Read(const robot::RobotModel& model, robot::RobotData& data) noexcept override;
  void Write(const robot::RobotModel& model, robot::RobotData& data) noexcept override;

  // Lock-step with a simulator: each Read first waits up to wait_ns for what is owed on each bus
  // (an answer to every frame sent last tick, and the IMUs' frames of a tick). 0: just drain.
  void SetLockStep(std::int64_t wait_ns) noexcept { wait_ns_ = wait_ns; }
  // The frames the next Read waits for on each bus, instead (a test driving both sides).
  void Expect(std::span<const std::uint32_t> per_bus) noexcept;
  void Stop();  // flushes the candump log
  void Finish(const robot::ControllerStatus&) override { Stop(); }

  std::size_t bus_count() const noexcept { return buses_.size(); }
  const BusStats& bus_stats(std::size_t bus) const noexcept { return buses_[bus]->stats(); }
  std::uint32_t sent_last_tick(std::size_t bus) const noexcept { return sent_last_[bus]; }
  std::uint64_t commands_sent(std::size_t motor) const noexcept { return frames_sent_[motor]; }
  std::uint64_t replies(std::size_t motor) const noexcept { return rx_.reply_count[motor]; }
  std::uint64_t imu_samples() const noexcept { return rx_.imu_count.empty() ? 0 : rx_.imu_count[0]; }
  const ImuSample& imu() const noexcept { return rx_.imu[0]; }
  const std::vector<CommandRecord>& RecordedCommands() const noexcept { return records_; }
  std::uint64_t records_dropped() const noexcept { return records_dropped_; }
  std::uint64_t candump_dropped() const noexcept;
  const std::vector<std::string>& interfaces() const noexcept { return interfaces_; }

 private:
  CanTransport() = default;
  double Unwrap(std::size_t motor, double q) noexcept;
  std::uint32_t first_link_ = 0;
  std::vector<std::string> interfaces_;
  CanCodecTable table_;
  CanRxData rx_;
  std::vector<std::unique_ptr<CanBus>> buses_;
  std::unique_ptr<CandumpLogger> log_;
  std::vector<std::vector<CanFrame>> rx_buf_, tx_buf_;
  std::vector<std::uint32_t> sent_last_, imu_frames_, expect_;
  bool expect_set_ = false;
  std::int64_t wait_ns_ = 0;
  std::vector<std::uint64_t> seen_replies_, seen_imu_, frames_sent_;
  std::vector<std::uint8_t> have_q_;  // per motor: a reply was seen (continuous joints' unwrapping)
  std::vector<double> last_q_;        // per motor: the last reply's position, as the driver wraps it
  std::vector<std::int64_t> turns_;   // per motor: whole MIT ranges turned since the first reply
  std::vector<std::uint32_t> imu_first_field_, imu_stream_;  // per IMU, in the robot model
  std::vector<BusStats> last_stats_;
  std::vector<CommandRecord> records_;
  std::uint64_t records_dropped_ = 0;
  std::size_t record_capacity_ = 0;
};

}  // namespace pbppo::can
