#include "runtime/robot/robot_data.hpp"

namespace pbppo::robot {

RobotData MakeRobotData(const RobotModel& m) {
  RobotData d;
  d.fields.assign(m.fields.size(), 0.0);
  d.fresh.assign(m.streams.size(), 0);
  d.streams.assign(m.streams.size(), {});
  d.samples.assign(m.streams.size(), 0);
  d.transports.assign(m.supervisor_model.transport_names.size(), {});
  for (const CommandSpec& c : m.commands) d.command.push_back(c.neutral);
  d.motors.assign(m.motors.size(), MotorCommand::kNone);
  return d;
}

}  // namespace pbppo::robot
