// A scripted operator: a schedule file of phases, each holding values for the fields of one
// declared stream (the quadruped's velocity command) for a while, played as that stream's
// transport. It stands where a DDS command topic would, so tests and the demo drive the robot
// with the same samples an operator would send, at the stream's period, and a recorded log
// replays them like any other input. The schedule's clock starts at its first Read.
//
//   stream: velocity_command      # a declared stream of the robot
//   phases:                       # each: name, duration_s, and values for any of its fields (else 0)
//     - {name: stand, duration_s: 2.0}
//     - {name: forward, duration_s: 4.0, command_vx: 0.5}
//
// Values are checked against the fields' bounds at load (errors name the file, phase and field).
// After the last phase the schedule falls silent (the stream goes stale: the supervisor acts);
// finished() says so.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/robot_data.hpp"
#include "runtime/robot/robot_model.hpp"

namespace pbppo::loop {

struct SchedulePhase {
  std::string name;
  double start_s = 0, duration_s = 0;
  std::vector<double> values;  // one per field of the stream
};

struct Schedule {
  std::string path, stream;
  std::uint32_t stream_index = 0;
  std::vector<SchedulePhase> phases;
  double duration_s() const noexcept { return phases.empty() ? 0 : phases.back().start_s + phases.back().duration_s; }
  // The phase at time t (s from the schedule's start); -1 after the end.
  int PhaseAt(double t_s) const noexcept;
  // Where each named field of the stream sits in a phase's values (e.g. the velocity command's
  // command_vx, command_vy, command_yaw_rate); errors name the file and the field it lacks.
  Result<std::vector<std::size_t>> Columns(const robot::RobotModel& model,
                                           std::initializer_list<std::string_view> fields) const;
};

Result<Schedule> ParseSchedule(const std::string& yaml_text, const std::string& origin, const robot::RobotModel& model);
Result<Schedule> LoadSchedule(const std::string& path, const robot::RobotModel& model);

class ScheduleTransport final : public robot::Transport {
 public:
  // The schedule's stream must be delivered by `transport` (a robot.yaml transport).
  static Result<std::unique_ptr<ScheduleTransport>> Create(const robot::RobotModel& model, Schedule schedule);
  void Read(const robot::RobotModel& model, robot::RobotData& data) noexcept override;
  void Write(const robot::RobotModel&, robot::RobotData&) noexcept override {}

  const Schedule& schedule() const noexcept { return schedule_; }
  bool finished() const noexcept { return finished_; }
  // Silences the source from now on (a test's dead operator).
  void Kill() noexcept { killed_ = true; }
  // The operator comes back (its samples go on at the schedule's time).
  void Revive() noexcept { killed_ = false; }
  std::uint64_t samples() const noexcept { return samples_; }

 private:
  explicit ScheduleTransport(Schedule s) : schedule_(std::move(s)) {}
  Schedule schedule_;
  std::uint32_t first_field_ = 0, period_ticks_ = 1;
  double tick_s_ = 0;
  bool started_ = false, finished_ = false, killed_ = false;
  std::uint64_t start_tick_ = 0, samples_ = 0;
};

}  // namespace pbppo::loop
