// What changes per tick of a robot, made up front from its model (MakeRobotData allocates; the
// tick never does), and the one interface of every transport (CAN, DDS, a replayed log):
//
//   Read   drains what arrived: the fields of every stream with a new sample and its `fresh`
//          mark, and the health of the transports it serves;
//   Write  sends the commands (and, for motors, whether to switch them on or off).
//
// Transports are the only code that knows sockets or DDS; the loop (runtime/loop) sees this.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/robot/robot_model.hpp"
#include "runtime/safety/supervisor.hpp"

namespace pbppo::robot {

// What Write sends a motor this tick.
enum class MotorCommand : std::uint8_t {
  kNone,     // nothing
  kEnable,   // switch it on (MIT: enter motor mode)
  kCommand,  // its commands (MIT: a command frame)
  kDisable,  // switch it off (MIT: exit motor mode)
};

struct RobotData {
  std::uint64_t tick = 0;                           // this tick (0, 1, 2 ...)
  std::vector<double> fields;                       // the newest value of every field
  std::vector<std::uint8_t> fresh;                  // per stream: a new sample this tick (Read sets it)
  std::vector<safety::StreamState> streams;         // per stream: seen, age, the sample check's finding
  std::vector<std::uint64_t> samples;               // per stream: samples received
  std::vector<safety::TransportHealth> transports;  // per link (TransportSpec): this tick's health (Read sets it)
  std::vector<double> command;                      // what Write sends (the supervisor's output)
  std::vector<MotorCommand> motors;                 // per motor
  safety::Mode mode = safety::Mode::kNominal;       // the supervisor's mode (for transports that carry it)
};

RobotData MakeRobotData(const RobotModel& model);

// The controller's state as another thread than the tick sees it, for status messages and
// summaries (runtime/loop fills it from its loop's status).
struct ControllerStatus {
  std::uint64_t tick = 0;
  std::uint8_t phase = 0;  // runtime/loop's Phase
  safety::Mode mode = safety::Mode::kNominal;
  std::uint32_t cause = 0;  // 1 << the latched cause of the mode, 0: none
  safety::CauseCounts counts;
  std::uint64_t deadline_misses = 0;
  double tick_median_us = 0, tick_max_us = 0;
};

class Transport {
 public:
  virtual ~Transport() = default;
  // Real-time safe: no allocation, lock or blocking call (a lock-step transport may wait, bounded).
  virtual void Read(const RobotModel& model, RobotData& data) noexcept = 0;
  virtual void Write(const RobotModel& model, RobotData& data) noexcept = 0;

  // The rest is for set-up and other threads than the tick; each has a default for transports
  // that have nothing to do there.
  // Before the loop starts: waits for what the robot file says must be there (a DDS peer);
  // the error names the transport and what is missing.
  virtual Status Connect(std::int64_t timeout_ns) {
    (void)timeout_ns;
    return {};
  }
  // Lock-step pacing: true when this transport delivers `stream` and WaitForSample can wait for it.
  virtual bool Paces(std::uint32_t stream) const noexcept {
    (void)stream;
    return false;
  }
  // Waits up to `timeout_ns` for a sample of `stream` newer than *version (0 before the first):
  // true, and *version the newest, when one came.
  virtual bool WaitForSample(std::uint32_t stream, std::uint64_t* version, std::int64_t timeout_ns) {
    (void)stream;
    (void)version;
    (void)timeout_ns;
    return false;
  }
  // The controller's status, every status period (status messages, where the robot file declares them).
  virtual void PublishStatus(const ControllerStatus& status) { (void)status; }
  // After the loop: the last status published and what was sent delivered (bounded waits), devices released.
  virtual void Finish(const ControllerStatus& status) { (void)status; }
  // A line for the run's summary (what was received and sent, failures); empty: none.
  virtual std::string Summary() const { return {}; }
};

}  // namespace pbppo::robot
