#include "policies/onnx/isaac_env.hpp"

#include <optional>
#include <regex>

#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::onnx {
namespace {

using robot::YamlFields;

// An Isaac Lab env.yaml (params/env.yaml of a run) as the deploy.yaml it implies, so that one
// reader checks both. Patterns are Isaac Lab's: regular expressions matched against a whole joint
// name (a joint matched by two patterns of one map is refused, as Isaac Lab does).
class EnvYaml {
 public:
  EnvYaml(const YamlFields& f, const robot::RobotModel& robot, const std::vector<std::string>& joints)
      : f_(f), robot_(robot), joints_(joints) {}

  Result<YAML::Node> Convert(const YAML::Node& env, std::vector<std::string>* notes);

 private:
  // The value of joint `joint` in `v` (a value, or a map of patterns to values); `fallback` where
  // no pattern matches (nullopt: refused).
  Result<YAML::Node> PerJoint(const YAML::Node& v, const std::string& where, const std::string& joint,
                              const std::optional<double>& fallback) const;

  const YamlFields& f_;
  const robot::RobotModel& robot_;
  const std::vector<std::string>& joints_;
};

Result<YAML::Node> EnvYaml::PerJoint(const YAML::Node& v, const std::string& where, const std::string& joint,
                                     const std::optional<double>& fallback) const {
  if (!v || v.IsNull()) {
    if (fallback) return YAML::Node(*fallback);
    return f_.Fail(where, "missing");
  }
  if (v.IsScalar() || v.IsSequence()) return YAML::Node(v);
  if (!v.IsMap()) return f_.Fail(where, YamlFields::Quote(v) + " is neither a value nor a map of joint patterns");
  YAML::Node found;
  std::string by;
  for (const auto& kv : v) {
    const std::string pattern = YamlKey(kv.first);
    std::regex re;
    try {
      re = std::regex(pattern);
    } catch (const std::regex_error&) {
      return f_.Fail(where, "'" + pattern + "' is not a regular expression");
    }
    if (!std::regex_match(joint, re)) continue;
    if (!by.empty()) return f_.Fail(where, "joint " + joint + " matches both '" + by + "' and '" + pattern + "'");
    found = kv.second;
    by = pattern;
  }
  if (!by.empty()) return found;
  if (fallback) return YAML::Node(*fallback);
  return f_.Fail(where, "no pattern matches joint " + joint);
}

Result<YAML::Node> EnvYaml::Convert(const YAML::Node& env, std::vector<std::string>* notes) {
  YAML::Node d(YAML::NodeType::Map);
  if (joints_.empty())
    return f_.Fail("",
                   "an Isaac Lab env.yaml does not hold the articulation's joint order: give it with --joints "
                   "(Isaac Lab prints it as env.scene['robot'].joint_names), in the robot's joint names");
  // Policy joint order -> motor index.
  YAML::Node ids(YAML::NodeType::Sequence);
  std::vector<std::size_t> motor_of;
  for (const std::string& j : joints_) {
    std::size_t m = 0;
    while (m < robot_.motors.size() && robot_.motors[m].joint != j) ++m;
    if (m == robot_.motors.size()) {
      std::string known;
      for (const auto& mo : robot_.motors) known += (known.empty() ? "" : ", ") + mo.joint;
      return MakeError(ErrorCode::kInvalidValue,
                       "--joints: '" + j + "' is not a joint of robot '" + robot_.name + "' (" + known + ")");
    }
    ids.push_back(m);
    motor_of.push_back(m);
  }
  d["joint_ids_map"] = ids;
  double dt = 0, decimation = 0;
  YAML::Node sim;
  PBPPO_TRY(f_.Map(env, "sim", "", &sim));
  PBPPO_TRY(f_.Number(sim, "dt", "sim", 1e-6, 1.0, &dt));
  PBPPO_TRY(f_.Number(env, "decimation", "", 1, 1000, &decimation));
  d["step_dt"] = dt * decimation;
  // The robot: default pose and gains by joint pattern.
  const YAML::Node scene = env["scene"];
  const YAML::Node robot_cfg = scene.IsMap() ? scene["robot"] : YAML::Node();
  if (!robot_cfg || !robot_cfg.IsMap()) return f_.Fail("scene.robot", "missing");
  const YAML::Node init = robot_cfg["init_state"];
  const YAML::Node pos = init && init.IsMap() ? init["joint_pos"] : YAML::Node();
  YAML::Node defaults(YAML::NodeType::Sequence);
  std::vector<double> default_pos;
  for (const std::string& j : joints_) {
    auto v = PerJoint(pos, "scene.robot.init_state.joint_pos", j, 0.0);  // unmatched: the USD's, 0
    if (!v) return std::move(v).error();
    double x = 0;
    PBPPO_TRY(f_.Scalar(*v, "scene.robot.init_state.joint_pos (" + j + ")", -1e3, 1e3, &x));
    defaults.push_back(x);
    default_pos.push_back(x);
  }
  d["default_joint_pos"] = defaults;
  const YAML::Node actuators = robot_cfg["actuators"];
  if (!actuators || !actuators.IsMap()) return f_.Fail("scene.robot.actuators", "missing");
  std::vector<YAML::Node> kp(robot_.motors.size(), YAML::Node(0.0)), kd(robot_.motors.size(), YAML::Node(0.0));
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    const std::string& j = joints_[i];
    std::string group;
    for (const auto& kv : actuators) {
      const std::string name = YamlKey(kv.first);
      const YAML::Node exprs = kv.second.IsMap() ? kv.second["joint_names_expr"] : YAML::Node();
      if (!exprs || !exprs.IsSequence())
        return f_.Fail("scene.robot.actuators." + name + ".joint_names_expr", "missing: a list of joint patterns");
      bool hit = false;
      for (const auto& e : exprs) {
        try {
          hit = hit || std::regex_match(j, std::regex(e.as<std::string>()));
        } catch (const std::exception&) {
          return f_.Fail("scene.robot.actuators." + name + ".joint_names_expr",
                         YamlFields::Quote(e) + " is not a regular expression");
        }
      }
      if (!hit) continue;
      if (!group.empty())
        return f_.Fail("scene.robot.actuators", "joint " + j + " is in actuator groups " + group + " and " + name);
      group = name;
      const std::string w = "scene.robot.actuators." + group;
      auto p = PerJoint(kv.second["stiffness"], w + ".stiffness", j, std::nullopt);
      if (!p) return std::move(p).error();
      auto dm = PerJoint(kv.second["damping"], w + ".damping", j, std::nullopt);
      if (!dm) return std::move(dm).error();
      kp[motor_of[i]] = *p;
      kd[motor_of[i]] = *dm;
    }
    if (group.empty()) return f_.Fail("scene.robot.actuators", "joint " + j + " is in no actuator group");
  }
  for (const YAML::Node& v : kp) d["stiffness"].push_back(v);
  for (const YAML::Node& v : kd) d["damping"].push_back(v);
  // Actions: one joint position term over every joint.
  YAML::Node actions;
  PBPPO_TRY(f_.Map(env, "actions", "", &actions));
  if (actions.size() != 1) return f_.Fail("actions", std::to_string(actions.size()) + " terms; one expected");
  const std::string term = YamlKey(actions.begin()->first);
  const YAML::Node a = actions.begin()->second;
  const std::string w = "actions." + term;
  if (!a.IsMap()) return f_.Fail(w, "not a map");
  const std::string cls = a["class_type"] && a["class_type"].IsScalar() ? a["class_type"].Scalar() : "";
  const std::string suffix = ":JointPositionAction";
  if (cls.size() < suffix.size() || cls.compare(cls.size() - suffix.size(), suffix.size(), suffix) != 0)
    return f_.Fail(w + ".class_type", "'" + cls + "': the layout expresses JointPositionAction only");
  YAML::Node jpa(YAML::NodeType::Map), scale(YAML::NodeType::Sequence), offset(YAML::NodeType::Sequence);
  const bool use_default =
      a["use_default_offset"] && a["use_default_offset"].IsScalar() && a["use_default_offset"].Scalar() == "true";
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    auto sv = PerJoint(a["scale"], w + ".scale", joints_[i], std::nullopt);
    if (!sv) return std::move(sv).error();
    scale.push_back(*sv);
    if (use_default) {
      offset.push_back(default_pos[i]);
    } else {
      auto ov = PerJoint(a["offset"], w + ".offset", joints_[i], 0.0);
      if (!ov) return std::move(ov).error();
      offset.push_back(*ov);
    }
  }
  YAML::Node clip = a["clip"];
  if (clip && clip.IsMap()) {
    YAML::Node per(YAML::NodeType::Sequence);
    for (const std::string& j : joints_) {
      auto cv = PerJoint(clip, w + ".clip", j, std::nullopt);
      if (!cv) return std::move(cv).error();
      per.push_back(*cv);
    }
    clip = per;
  }
  jpa["clip"] = clip ? clip : YAML::Node();
  jpa["joint_names"] = a["joint_names"] ? a["joint_names"] : YAML::Node();
  jpa["scale"] = scale;
  jpa["offset"] = offset;
  jpa["joint_ids"] = YAML::Node();
  d["actions"]["JointPositionAction"] = jpa;
  // Observations: the policy group's terms, in order; the group's history, where it has one,
  // stands for every term's.
  const YAML::Node groups = env["observations"];
  const YAML::Node group = groups && groups.IsMap() ? groups["policy"] : YAML::Node();
  if (!group || !group.IsMap()) return f_.Fail("observations.policy", "missing: the policy's observation group");
  if (group["concatenate_terms"] && group["concatenate_terms"].IsScalar() &&
      group["concatenate_terms"].Scalar() != "true")
    return f_.Fail("observations.policy.concatenate_terms", "false: the policy takes one vector");
  const YAML::Node group_history = group["history_length"];
  const bool group_has_history =
      group_history && group_history.IsScalar() && group_history.Scalar() != "0" && group_history.Scalar() != "null";
  YAML::Node obs(YAML::NodeType::Map);
  for (const auto& kv : group) {
    if (!kv.second.IsMap() || !kv.second["func"]) continue;  // the group's own settings
    const std::string name = YamlKey(kv.first);
    const std::string tw = "observations.policy." + name;
    if (!kv.second["func"].IsScalar())
      return f_.Fail(tw + ".func", YamlFields::Quote(kv.second["func"]) + " is not a name");
    const std::string func = kv.second["func"].Scalar();
    const auto colon = func.rfind(':');
    const std::string kind = colon == std::string::npos ? func : func.substr(colon + 1);
    if (kv.second["modifiers"] && !kv.second["modifiers"].IsNull())
      return f_.Fail(tw + ".modifiers", "the layout cannot express a term's modifiers");
    if (obs[kind]) return f_.Fail(tw, "a second " + kind + " term (the layout observes each signal once)");
    YAML::Node t(YAML::NodeType::Map);
    t["params"] = kv.second["params"] ? kv.second["params"] : YAML::Node();
    t["clip"] = kv.second["clip"] ? kv.second["clip"] : YAML::Node();
    t["scale"] = kv.second["scale"] ? kv.second["scale"] : YAML::Node();
    t["history_length"] = group_has_history             ? group_history
                          : kv.second["history_length"] ? kv.second["history_length"]
                                                        : YAML::Node();
    obs[kind] = t;
    if (kind != name) notes->push_back("term:        observations.policy." + name + " read as " + func);
  }
  d["observations"] = obs;
  const YAML::Node commands = env["commands"];
  if (commands && commands.IsMap() && commands["base_velocity"] && commands["base_velocity"]["ranges"]) {
    YAML::Node ranges(YAML::NodeType::Map);
    for (const auto& kv : commands["base_velocity"]["ranges"])
      if (kv.second.IsSequence()) ranges[YamlKey(kv.first)] = kv.second;
    d["commands"]["base_velocity"]["ranges"] = ranges;
  }
  std::string order;
  for (const std::string& j : joints_) order += (order.empty() ? "" : ", ") + j;
  notes->push_back("joints:      the articulation's order, as --joints gives it: " + order);
  return d;
}

}  // namespace

Result<YAML::Node> IsaacEnvAsDeploy(const YAML::Node& env, const std::string& origin, const robot::RobotModel& robot,
                                    const std::vector<std::string>& joints, std::vector<std::string>* notes) {
  const YamlFields f(origin);
  EnvYaml reader(f, robot, joints);
  return reader.Convert(env, notes);
}

}  // namespace pbppo::onnx
