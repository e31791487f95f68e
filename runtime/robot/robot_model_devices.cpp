#include <algorithm>
#include <cmath>

#include "runtime/robot/robot_model_parts.hpp"

namespace pbppo::robot::detail {
namespace {
using Rule = YamlFields::TextRule;
}  // namespace

Status Builder::ReadStale(const YAML::Node& parent, const std::string& where, StaleLimits* out) const {
  YAML::Node n;
  PBPPO_TRY(f.Map(parent, "stale_after", where, &n));
  const std::string w = YamlFields::Join(where, "stale_after");
  PBPPO_TRY(f.Keys(n, w, {"degraded", "safe_stop", "lost"}));
  PBPPO_TRY(f.Number(n, "degraded", w, 0.0, 1e6, &out->degraded));
  PBPPO_TRY(f.Number(n, "safe_stop", w, 0.0, 1e6, &out->safe_stop));
  PBPPO_TRY(f.Number(n, "lost", w, 0.0, 1e6, &out->lost));
  if (!(out->degraded < out->safe_stop && out->safe_stop < out->lost))
    return f.Fail(w, "degraded " + YamlFields::Num(out->degraded) + ", safe_stop " + YamlFields::Num(out->safe_stop) +
                         ", lost " + YamlFields::Num(out->lost) + " must increase");
  return {};
}

Status Builder::AddField(const std::string& name, double lo, double hi, const std::string& where) {
  if (m.FieldIndex(name) >= 0) return f.Fail(where, "field '" + name + "' appears twice");
  if (!(lo <= hi)) return f.Fail(where, "min " + YamlFields::Num(lo) + " is above max " + YamlFields::Num(hi));
  m.fields.push_back(FieldSpec{name, lo, hi, static_cast<std::uint32_t>(m.streams.size() - 1)});
  ++m.streams.back().field_count;
  return {};
}

Status Builder::AddCommand(CommandSpec c, const std::string& where) {
  if (m.CommandIndex(c.name) >= 0) return f.Fail(where, "command '" + c.name + "' appears twice");
  m.commands.push_back(std::move(c));
  return {};
}

Status Builder::StartStream(StreamSpec s, const std::string& where) {
  if (m.StreamIndex(s.name) >= 0) return f.Fail(where, "stream '" + s.name + "' appears twice");
  if (m.TransportIndex(s.transport) < 0) return f.Fail(where, "unknown transport '" + s.transport + "'");
  s.first_field = static_cast<std::uint32_t>(m.fields.size());
  s.field_count = 0;
  m.streams.push_back(std::move(s));
  return {};
}

// The motors section's settings every motor shares; *motors: the section.
Status Builder::MotorSection(const YAML::Node& root, MotorSettings* ms, YAML::Node* motors) {
  PBPPO_TRY(f.Map(root, "motors", "", motors));
  const bool can = m.can.has_value();
  if (can)
    PBPPO_TRY(f.Keys(*motors, "motors",
                     {"stale_after", "invalid_safe_stop", "position_margin_rad", "velocity_factor", "policy_gains"}));
  else
    PBPPO_TRY(f.Keys(*motors, "motors",
                     {"transport", "stale_after", "invalid_safe_stop", "position_margin_rad", "velocity_factor",
                      "torque_factor", "gain_limits", "policy_gains", "lost_per_sample_max"}));
  if (motors->operator[]("policy_gains")) {
    YAML::Node g;
    PBPPO_TRY(f.Map(*motors, "policy_gains", "motors", &g));
    PBPPO_TRY(f.Keys(g, "motors.policy_gains", {"kp_nm_rad", "kd_nm_s_rad"}));
    PBPPO_TRY(f.Number(g, "kp_nm_rad", "motors.policy_gains", 0.0, 1e4, &ms->policy_kp));
    PBPPO_TRY(f.Number(g, "kd_nm_s_rad", "motors.policy_gains", 0.0, 1e3, &ms->policy_kd));
  }
  ms->proto.period_s = m.tick_period_s;
  ms->proto.kind = StreamKind::kMotor;
  PBPPO_TRY(ReadStale(*motors, "motors", &ms->proto.stale_after));
  PBPPO_TRY(f.Count(*motors, "invalid_safe_stop", "motors", 1, 1000000, &ms->proto.invalid_safe_stop));
  PBPPO_TRY(f.Number(*motors, "position_margin_rad", "motors", 0.0, 10.0, &ms->margin));
  PBPPO_TRY(f.Number(*motors, "velocity_factor", "motors", 1.0, 100.0, &ms->factor));
  if (!can) PBPPO_TRY(f.OptionalNumber(*motors, "torque_factor", "motors", 1.0, 100.0, &ms->torque_factor));
  if (!can && motors->operator[]("lost_per_sample_max"))
    PBPPO_TRY(f.Number(*motors, "lost_per_sample_max", "motors", 0.0, 4294967295.0, &ms->lost_max));
  return {};
}

// Streams, fields, commands and motors: the CAN map's MIT motors and IMUs; or, without a CAN map,
// a motor per actuated joint of the description and the IMUs the imus section names, all
// delivered by the transport `motors.transport` names (a DDS message maps their fields).
Status Builder::Devices(const YAML::Node& root) {
  if (!m.can && !(root["motors"] && root["motors"].IsMap() && root["motors"]["transport"])) return {};
  if (!m.body)
    return f.Fail(m.can ? "files" : "motors", "motors need a description (the URDF gives the joints' limits)");
  const RobotDescription& body = *m.body;
  MotorSettings ms;
  YAML::Node motors;
  PBPPO_TRY(MotorSection(root, &ms, &motors));
  if (!m.can) {
    PBPPO_TRY(f.Text(motors, "transport", "motors", &ms.proto.transport, Rule::kToken));
    const int t = m.TransportIndex(ms.proto.transport);
    if (t < 0) return f.Fail("motors.transport", "'" + ms.proto.transport + "' is not a transport of the robot");
    if (m.transports[static_cast<std::size_t>(t)].kind == "can")
      return f.Fail("motors.transport", "motors on a transport of kind can come from files.can_map");
    DriverLimits limits;
    limits.name = "motors.gain_limits";
    YAML::Node g;
    PBPPO_TRY(f.Map(motors, "gain_limits", "motors", &g));
    PBPPO_TRY(f.Keys(g, "motors.gain_limits", {"kp_max", "kd_max"}));
    PBPPO_TRY(f.Number(g, "kp_max", "motors.gain_limits", 0.0, 1e4, &limits.kp_max));
    PBPPO_TRY(f.Number(g, "kd_max", "motors.gain_limits", 0.0, 1e3, &limits.kd_max));
    for (std::size_t j = 0; j < body.joint_count(); ++j)
      PBPPO_TRY(Motor(body.joint_names[j], static_cast<std::uint32_t>(j), limits, ms,
                      "motors: joint '" + body.joint_names[j] + "'"));
    if (!root["imus"]) return {};
    YAML::Node imus;
    PBPPO_TRY(f.Map(root, "imus", "", &imus));
    PBPPO_TRY(f.Keys(imus, "imus", {"names", "stale_after", "invalid_safe_stop"}));
    StreamSpec proto = ms.proto;
    proto.kind = StreamKind::kImu;
    PBPPO_TRY(ReadStale(imus, "imus", &proto.stale_after));
    PBPPO_TRY(f.Count(imus, "invalid_safe_stop", "imus", 1, 1000000, &proto.invalid_safe_stop));
    YAML::Node names;
    PBPPO_TRY(f.List(imus, "names", "imus", true, &names));
    for (std::size_t k = 0; k < names.size(); ++k) {
      const std::string w = "imus.names[" + std::to_string(k) + "]";
      if (!names[k].IsScalar()) return f.Fail(w, "expected an IMU's name");
      // A DDS IMU's floats carry what the sensor measures: a gyro's 2000 deg/s, 16 g.
      PBPPO_TRY(ImuStream(names[k].as<std::string>(), static_cast<std::uint32_t>(k), proto, 35.0, 160.0, w));
    }
    return {};
  }
  const CanMap& map = *m.can;
  int can_transport = -1;
  for (std::size_t t = 0; t < m.transports.size(); ++t)
    if (m.transports[t].kind == "can") can_transport = static_cast<int>(t);
  if (can_transport < 0) return f.Fail("transports", "no transport of kind can for the CAN map");
  if (map.motors.size() != body.joint_count())
    return f.Fail("files.can_map", "the CAN map has " + std::to_string(map.motors.size()) +
                                       " motors, the description " + std::to_string(body.joint_count()) +
                                       " actuated joints");
  ms.proto.transport = m.transports[static_cast<std::size_t>(can_transport)].name;
  for (std::size_t k = 0; k < map.motors.size(); ++k) {
    const CanMotor& cm = map.motors[k];
    const MitRange& r = map.range_of(cm);
    DriverLimits limits{
        r.p_min,  r.p_max, std::min(r.v_max, -r.v_min),    r.t_min, r.t_max, r.kp_min, r.kp_max, r.kd_min,
        r.kd_max, true,    map.actuators[cm.actuator].name};
    PBPPO_TRY(Motor(cm.joint, static_cast<std::uint32_t>(k), limits, ms,
                    "files.can_map: motors[" + std::to_string(k) + "] '" + cm.joint + "'"));
  }
  if (map.imus.empty()) return {};
  YAML::Node imus;
  PBPPO_TRY(f.Map(root, "imus", "", &imus));
  PBPPO_TRY(f.Keys(imus, "imus", {"stale_after", "invalid_safe_stop"}));
  StreamSpec proto = ms.proto;
  proto.kind = StreamKind::kImu;
  PBPPO_TRY(ReadStale(imus, "imus", &proto.stale_after));
  PBPPO_TRY(f.Count(imus, "invalid_safe_stop", "imus", 1, 1000000, &proto.invalid_safe_stop));
  // The codecs' ranges: a quaternion component within 1, 32.8 rad/s, 163.8 m/s^2.
  for (std::size_t k = 0; k < map.imus.size(); ++k)
    PBPPO_TRY(ImuStream(map.imus[k].name, static_cast<std::uint32_t>(k), proto, 32.8, 163.9,
                        "files.can_map: imus[" + std::to_string(k) + "] '" + map.imus[k].name + "'"));
  return {};
}

// The motor of `joint` (device: its index in the CAN map or the description): its stream, its
// reply's fields and its commands.
Status Builder::Motor(const std::string& joint, std::uint32_t device, const DriverLimits& r, const MotorSettings& ms,
                      const std::string& where) {
  const RobotDescription& body = *m.body;
  const auto it = std::find(body.joint_names.begin(), body.joint_names.end(), joint);
  if (it == body.joint_names.end()) return f.Fail(where, "is not a joint of " + body.urdf_path);
  const auto j = static_cast<std::size_t>(it - body.joint_names.begin());
  const UrdfJoint& uj = body.joint_at(j);
  const double tau = std::min({uj.effort_nm, r.t_max, -r.t_min});
  const double v = std::min(uj.velocity_rad_s, r.v_max);
  const bool velocity = body.velocity_commanded(j);
  if (velocity && r.kp_min > 0)
    return f.Fail(where, "actuator '" + r.name + "' has kp_min " + YamlFields::Num(r.kp_min) +
                             ": velocity-commanded joint '" + joint + "' needs kp 0 exactly");
  if (uj.continuous() && r.mit) {
    // The multi-turn angle is unwrapped from one reply to the next: the joint must turn less than
    // half the MIT position range between two replies the supervisor still accepts.
    const double gap_s = (ms.proto.stale_after.lost + 1) * ms.proto.period_s, turn = gap_s * ms.factor * v;
    if (!(turn < 0.5 * (r.p_max - r.p_min)))
      return f.Fail("motors.stale_after.lost",
                    YamlFields::Num(ms.proto.stale_after.lost) + " periods without a reply let continuous joint '" +
                        joint + "' turn up to " + YamlFields::Num(turn) + " rad (" + YamlFields::Num(ms.factor) +
                        " x " + YamlFields::Num(v) + " rad/s for " + YamlFields::Num(gap_s) +
                        " s) between two replies, not less than half its MIT position range [" +
                        YamlFields::Num(r.p_min) + ", " + YamlFields::Num(r.p_max) +
                        "]: its multi-turn angle could not be unwrapped");
  }
  StreamSpec s = ms.proto;
  s.name = joint;
  s.device = device;
  PBPPO_TRY(StartStream(std::move(s), where));
  MotorSpec mo;
  mo.joint = joint;
  mo.stream = static_cast<std::uint32_t>(m.streams.size() - 1);
  mo.control = body.control[j];
  mo.continuous = uj.continuous();
  mo.default_q_rad = body.default_q_rad[j];
  mo.sit_q_rad = body.sit_q_rad.empty() ? std::nan("") : body.sit_q_rad[j];
  mo.policy_kp = velocity ? -1 : ms.policy_kp;
  mo.policy_kd = velocity ? -1 : ms.policy_kd;
  mo.q_field = static_cast<std::uint32_t>(m.fields.size());
  // A continuous joint has no position bound: its field is only checked for being finite.
  PBPPO_TRY(AddField("q_" + joint, uj.lower_rad - ms.margin, uj.upper_rad + ms.margin, where));
  mo.dq_field = mo.q_field + 1;
  PBPPO_TRY(AddField("dq_" + joint, -ms.factor * v, ms.factor * v, where));
  mo.tau_field = mo.q_field + 2;
  // An MIT reply cannot leave its range; another driver's estimate is bounded by the effort limit.
  const double tau_lo = r.mit ? std::min(r.t_min, -tau) : -ms.torque_factor * tau;
  const double tau_hi = r.mit ? std::max(r.t_max, tau) : ms.torque_factor * tau;
  PBPPO_TRY(AddField("tau_" + joint, tau_lo, tau_hi, where));
  // The frames its driver lost since the previous sample (a transport maps it to the increase of
  // the driver's counter): beyond the robot file's allowance, the sample is invalid.
  if (ms.lost_max >= 0) {
    mo.lost_field = static_cast<std::int32_t>(m.fields.size());
    PBPPO_TRY(AddField("lost_" + joint, 0.0, ms.lost_max, where));
  }
  const auto motor = static_cast<std::int32_t>(m.motors.size());
  auto command = [&](const char* prefix, double lo, double hi, double neutral, safety::StopKind stop, double stop_value,
                     std::uint32_t* index) {
    return MotorCommand({prefix + joint, lo, hi, neutral, stop, stop_value, motor,
                         stop == safety::StopKind::kHoldInput ? static_cast<std::int32_t>(mo.q_field) : -1},
                        where, index);
  };
  // Safe-stop damps: no stiffness, the damping gain, no speed, no torque (a position-commanded
  // motor's target is the measured position). A velocity-commanded motor has no q_des_ or kp_:
  // it holds zero speed with its velocity gain (stand-up, hold) or the damping gain (safe-stop).
  mo.q = mo.kp = kNoCommand;
  if (!velocity)
    PBPPO_TRY(command("q_des_", std::max(uj.lower_rad, r.p_min), std::min(uj.upper_rad, r.p_max), mo.default_q_rad,
                      safety::StopKind::kHoldInput, 0.0, &mo.q));
  PBPPO_TRY(command("dq_des_", -v, v, 0.0, safety::StopKind::kValue, 0.0, &mo.dq));
  if (!velocity)
    PBPPO_TRY(command("kp_", std::max(0.0, r.kp_min), r.kp_max, body.kp_nm_rad, safety::StopKind::kValue, 0.0, &mo.kp));
  PBPPO_TRY(command("kd_", std::max(0.0, r.kd_min), r.kd_max,
                    velocity ? body.velocity_kd_nm_s_rad[j] : body.kd_nm_s_rad, safety::StopKind::kValue,
                    body.damping_kd_nm_s_rad, &mo.kd));
  PBPPO_TRY(command("tau_ff_", -tau, tau, 0.0, safety::StopKind::kValue, 0.0, &mo.tau));
  m.motors.push_back(mo);
  return {};
}

Status Builder::MotorCommand(const MotorCommandSpec& c, const std::string& where, std::uint32_t* index) {
  if (!(c.neutral >= c.lo && c.neutral <= c.hi))
    return f.Fail(where, "command '" + c.name + "': its neutral value " + YamlFields::Num(c.neutral) +
                             " (the description's default pose or gains) is outside [" + YamlFields::Num(c.lo) + ", " +
                             YamlFields::Num(c.hi) + "] (the joint's and the actuator's limits)");
  CommandSpec s;
  s.name = c.name;
  s.min = s.degraded_min = c.lo;
  s.max = s.degraded_max = c.hi;
  s.neutral = c.neutral;
  s.stop = c.stop;
  s.stop_value = c.stop_value;
  s.motor = c.motor;
  s.hold_input = c.hold_input;
  *index = static_cast<std::uint32_t>(m.commands.size());
  return AddCommand(std::move(s), where);
}

// An IMU's stream: its quaternion, gyro (rad/s) and acceleration (m/s^2) fields, each component
// within 1.001, `gyro` and `accel`.
Status Builder::ImuStream(const std::string& n, std::uint32_t device, const StreamSpec& proto, double gyro,
                          double accel, const std::string& where) {
  StreamSpec s = proto;
  s.name = n;
  s.device = device;
  PBPPO_TRY(StartStream(std::move(s), where));
  for (const char* q : {"_qw", "_qx", "_qy", "_qz"}) PBPPO_TRY(AddField(n + q, -1.001, 1.001, where));
  for (const char* g : {"_gyro_x", "_gyro_y", "_gyro_z"}) PBPPO_TRY(AddField(n + g, -gyro, gyro, where));
  for (const char* a : {"_accel_x", "_accel_y", "_accel_z"}) PBPPO_TRY(AddField(n + a, -accel, accel, where));
  return {};
}

Status Builder::Signals(const YAML::Node& root) {
  if (!root["signals"]) return {};
  YAML::Node n;
  PBPPO_TRY(f.Map(root, "signals", "", &n));
  using Op = SignalSpec::Op;
  static const std::pair<const char*, Op> kOps[] = {{"field", Op::kField},
                                                    {"wrap", Op::kWrap},
                                                    {"cos", Op::kCos},
                                                    {"sin", Op::kSin},
                                                    {"min", Op::kMin},
                                                    {"gravity_x", Op::kGravityX},
                                                    {"gravity_y", Op::kGravityY},
                                                    {"gravity_z", Op::kGravityZ}};
  for (const auto& kv : n) {
    const std::string name = kv.first.as<std::string>();
    const std::string w = "signals." + name;
    const YAML::Node def = kv.second;
    PBPPO_TRY(f.Keys(def, w, {"field", "minus", "wrap", "cos", "sin", "min", "gravity_x", "gravity_y", "gravity_z"}));
    const char* key = nullptr;
    Op op = Op::kField;
    for (const auto& [k, o] : kOps) {
      if (!def[k]) continue;
      if (key != nullptr) return f.Fail(w, std::string("both '") + key + "' and '" + k + "'");
      key = k;
      op = o;
    }
    if (key == nullptr) return f.Fail(w, "expected one of field, wrap, cos, sin, min, gravity_x|y|z");
    std::string arg;
    PBPPO_TRY(f.Text(def, key, w, &arg, Rule::kToken));
    double minus = 0;
    if (def["minus"]) {
      if (op != Op::kField) return f.Fail(w + ".minus", "goes with 'field' only");
      std::string p;
      PBPPO_TRY(f.Text(def, "minus", w, &p, Rule::kToken));
      auto v = m.Parameter(p);
      if (!v) return f.Fail(w + ".minus", "'" + p + "' is not a parameter of the robot");
      minus = *v;
      op = Op::kMinus;
    }
    const bool repeat = name.find("{i}") != std::string::npos;
    if (repeat && (op == Op::kMin || op >= Op::kGravityX || arg.find("{i}") == std::string::npos))
      return f.Fail(w, "a signal repeated over {i} needs a field with {i}");
    std::uint32_t count = 1;
    if (repeat)
      for (count = 0; m.FieldIndex(ExpandIndex(arg, count)) >= 0;) ++count;
    for (std::uint32_t i = 0; i < count; ++i) {
      SignalSpec s;
      s.name = ExpandIndex(name, i);
      s.op = op;
      s.value = minus;
      PBPPO_TRY(SignalFields(op, repeat ? ExpandIndex(arg, i) : arg, w + "." + key, &s.fields));
      for (const auto& o : m.signals)
        if (o.name == s.name) return f.Fail(w, "signal '" + s.name + "' appears twice");
      m.signals.push_back(std::move(s));
    }
    if (count == 0) return f.Fail(w + "." + key, "'" + arg + "' names no field of the robot");
  }
  return {};
}

// The fields a signal reads: one field; every field of a {i} pattern (min); an IMU's quaternion.
Status Builder::SignalFields(SignalSpec::Op op, const std::string& arg, const std::string& where,
                             std::vector<std::uint32_t>* out) {
  using Op = SignalSpec::Op;
  out->clear();
  if (op == Op::kMin) {
    for (std::uint32_t i = 0;; ++i) {
      const int k = m.FieldIndex(ExpandIndex(arg, i));
      if (k < 0) break;
      out->push_back(static_cast<std::uint32_t>(k));
      if (arg.find("{i}") == std::string::npos) break;
    }
  } else if (op >= Op::kGravityX) {
    for (const char* q : {"_qw", "_qx", "_qy", "_qz"}) {
      const int k = m.FieldIndex(arg + q);
      if (k < 0) return f.Fail(where, "'" + arg + "' is not an IMU of the robot (no field " + arg + q + ")");
      out->push_back(static_cast<std::uint32_t>(k));
    }
  } else {
    const int k = m.FieldIndex(arg);
    if (k >= 0) out->push_back(static_cast<std::uint32_t>(k));
  }
  if (out->empty()) return f.Fail(where, "'" + arg + "' is not a field of the robot");
  return {};
}

}  // namespace pbppo::robot::detail
