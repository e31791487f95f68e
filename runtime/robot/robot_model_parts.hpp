// Pieces of LoadRobotModel (runtime/robot/robot_model.cpp): the fields, streams and commands it
// adds, those of the CAN map's motors and IMUs, and the declared signals. Internal to pbppo::robot.
#pragma once

#include <string>

#include "runtime/robot/robot_model.hpp"
#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::robot::detail {

// The motors section's settings every motor shares.
struct MotorSettings {
  StreamSpec proto;  // its stream: transport, period, staleness, invalid samples
  double margin = 0, factor = 0;
  double torque_factor = 1.5;  // motors without a CAN map: a reported torque beyond this x the effort limit is a fault
  double policy_kp = -1, policy_kd = -1;
  double lost_max = -1;  // motors without a CAN map: lost_<joint>'s largest value per sample (-1: no such field)
};

// What a motor's driver accepts besides the joint's own limits (an MIT range; a motor without a
// CAN map: the robot file's gain limits, nothing else).
struct DriverLimits {
  double p_min = -HUGE_VAL, p_max = HUGE_VAL, v_max = HUGE_VAL, t_min = -HUGE_VAL, t_max = HUGE_VAL;
  double kp_min = 0, kp_max = 0, kd_min = 0, kd_max = 0;
  bool mit = false;  // an MIT range (its torque bounds the reported torque; continuous joints unwrap in it)
  std::string name;  // for errors: the actuator
};

// One command of a motor: its limits, its neutral value and what safe-stop sends.
struct MotorCommandSpec {
  std::string name;
  double lo = 0, hi = 0, neutral = 0;
  safety::StopKind stop = safety::StopKind::kValue;
  double stop_value = 0;
  std::int32_t motor = -1, hold_input = -1;
};

// An axis's shaping in robot.yaml (range, scale, dead_zone: AxisShape) for field `field`, whose
// range must hold what it can give. `device_range`: the range is required and whole (a device's raw
// counts); else it is optional, [-1, 1] by default (robot_model_operator.cpp).
Status ReadAxisShape(const RobotModel& m, const YamlFields& f, const YAML::Node& a, const std::string& wa,
                     std::uint32_t field, bool device_range, AxisShape* out);

struct Builder {
  RobotModel& m;
  const YamlFields& f;

  Status StartStream(StreamSpec s, const std::string& where);
  Status AddField(const std::string& name, double lo, double hi, const std::string& where);
  Status AddCommand(CommandSpec c, const std::string& where);
  // A stream's stale_after: {degraded, safe_stop, lost} (sample periods, increasing).
  Status ReadStale(const YAML::Node& parent, const std::string& where, StaleLimits* out) const;
  // Streams, fields, commands and motors of the CAN map's MIT motors and IMUs, or of the
  // description's joints and the imus section's IMUs on another transport (the motors and imus
  // sections).
  Status Devices(const YAML::Node& root);
  // The signals section.
  Status Signals(const YAML::Node& root);
  // The transports section: names, kinds and settings (before the streams that name them).
  Status Transports(const YAML::Node& root);
  // The messages of DDS transports, mapped onto streams, fields and commands (after them); IDL
  // files (relative to `dir`) read through `read`.
  Status DdsMessages(const YAML::Node& root, const IdlFileReader& read, const std::string& dir);
  // The axes and buttons of evdev transports, mapped onto their streams' fields (after the
  // streams; robot_model_operator.cpp).
  Status EvdevMappings(const YAML::Node& root);
  // The operator section: requests from fields (after the streams; robot_model_operator.cpp).
  Status Operator(const YAML::Node& root);
  Status From(const YAML::Node& from);  // operator.from
  // timing.lockstep (after the streams).
  Status Lockstep(const YAML::Node& root);

 private:
  Status SignalFields(SignalSpec::Op op, const std::string& arg, const std::string& where,
                      std::vector<std::uint32_t>* out);
  Status MotorSection(const YAML::Node& root, MotorSettings* ms, YAML::Node* motors);
  Status Motor(const std::string& joint, std::uint32_t device, const DriverLimits& limits,
               const MotorSettings& settings, const std::string& where);
  Status ImuStream(const std::string& name, std::uint32_t device, const StreamSpec& proto, double gyro, double accel,
                   const std::string& where);
  Status MotorCommand(const MotorCommandSpec& command, const std::string& where, std::uint32_t* index);
  Status CanImus(const YAML::Node& root, StreamSpec proto);
  // Entries with "{joint}" or "{motor}" in the key or the value, once per motor; others as they are.
  std::vector<std::pair<std::string, std::string>> PerMotor(const YAML::Node& map) const;
  Status InMessage(const YAML::Node& n, const std::string& where, std::uint32_t transport, DdsMessageSpec* out);
  Status OutMessage(const YAML::Node& n, const std::string& where, DdsMessageSpec* out);
  Status Checksum(const YAML::Node& n, const std::string& where, DdsMessageSpec* out);
  Status DdsMessage(const YAML::Node& n, const std::string& where, std::uint32_t transport, const IdlFileReader& read,
                    const std::string& dir);
  // A value of an outgoing (status: a status) message's leaf: terms joined by " + ".
  Result<std::vector<ValueTerm>> Value(const std::string& text, bool status, const std::string& where) const;
};

}  // namespace pbppo::robot::detail
