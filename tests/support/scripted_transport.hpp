// A transport in memory for tests of the loop: the test puts a stream's fields for the next Read
// (a new sample) and link health; Write keeps what the loop sent. Preallocated: Read and Write
// never allocate, so the loop's allocation tests hold with it.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "runtime/robot/robot_data.hpp"

namespace pbppo::test {

class ScriptedTransport final : public robot::Transport {
 public:
  explicit ScriptedTransport(const robot::RobotModel& m)
      : values_(m.fields.size(), 0.0),
        pending_(m.streams.size(), 0),
        health_(m.supervisor_model.transport_names.size()),
        command(m.commands.size(), 0.0),
        motors(m.motors.size(), robot::MotorCommand::kNone) {}

  // The next Read delivers these values of stream `s` (its fields, in order) as a new sample.
  void Put(const robot::RobotModel& m, std::uint32_t s, std::span<const double> values) noexcept {
    const robot::StreamSpec& spec = m.streams[s];
    for (std::uint32_t k = 0; k < spec.field_count && k < values.size(); ++k) values_[spec.first_field + k] = values[k];
    pending_[s] = 1;
  }
  // One field of stream `s` (the others as last put), delivered as a new sample.
  void PutField(const robot::RobotModel& m, std::uint32_t field, double value) noexcept {
    values_[field] = value;
    pending_[m.fields[field].stream] = 1;
  }
  void SetHealth(std::size_t link, safety::TransportHealth h) noexcept { health_[link] = h; }

  void Read(const robot::RobotModel& m, robot::RobotData& d) noexcept override {
    for (std::size_t s = 0; s < pending_.size(); ++s) {
      if (pending_[s] == 0) continue;
      const robot::StreamSpec& spec = m.streams[s];
      for (std::uint32_t k = 0; k < spec.field_count; ++k)
        d.fields[spec.first_field + k] = values_[spec.first_field + k];
      d.fresh[s] = 1;
      pending_[s] = 0;
    }
    for (std::size_t k = 0; k < health_.size(); ++k) d.transports[k] = health_[k];
  }
  void Write(const robot::RobotModel&, robot::RobotData& d) noexcept override {
    for (std::size_t k = 0; k < command.size(); ++k) command[k] = d.command[k];
    for (std::size_t k = 0; k < motors.size(); ++k) motors[k] = d.motors[k];
    mode = d.mode;
    tick = d.tick;
    ++writes;
  }

 private:
  std::vector<double> values_;
  std::vector<std::uint8_t> pending_;
  std::vector<safety::TransportHealth> health_;

 public:
  // What the last Write sent.
  std::vector<double> command;
  std::vector<robot::MotorCommand> motors;
  safety::Mode mode = safety::Mode::kNominal;
  std::uint64_t tick = 0, writes = 0;
};

}  // namespace pbppo::test
