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

class Transport {
 public:
  virtual ~Transport() = default;
  // Real-time safe: no allocation, lock or blocking call (a lock-step transport may wait, bounded).
  virtual void Read(const RobotModel& model, RobotData& data) noexcept = 0;
  virtual void Write(const RobotModel& model, RobotData& data) noexcept = 0;
};

}  // namespace pbppo::robot
