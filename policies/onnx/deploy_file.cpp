#include "policies/onnx/deploy_file.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "policies/onnx/isaac_env.hpp"
#include "runtime/robot/signals.hpp"
#include "runtime/robot/text_file.hpp"
#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::onnx {
namespace {

using robot::YamlFields;

// One observation term's elements: the robot signal of each and the offset subtracted from it.
struct TermSignals {
  std::vector<std::string> signals;
  std::vector<double> offsets;
};

// A list of numbers `key` of exactly n entries (a scalar stands for n equal ones where `scalar_ok`).
Status Numbers(const YamlFields& f, const YAML::Node& map, const char* key, const std::string& where, std::size_t n,
               bool scalar_ok, std::vector<double>* out) {
  const std::string field = YamlFields::Join(where, key);
  const YAML::Node v = map[key];
  if (!v) return f.Fail(field, "missing");
  out->clear();
  if (v.IsScalar() && scalar_ok) {
    double x = 0;
    PBPPO_TRY(f.Scalar(v, field, -1e9, 1e9, &x));
    out->assign(n, x);
    return {};
  }
  if (!v.IsSequence()) return f.Fail(field, YamlFields::Quote(v) + " is not a list of numbers");
  if (v.size() != n)
    return f.Fail(field, std::to_string(v.size()) + " values, expected " + std::to_string(n) +
                             (where.empty() ? "" : " (one per element of " + where + ")"));
  for (std::size_t i = 0; i < n; ++i) {
    double x = 0;
    PBPPO_TRY(f.Scalar(v[i], field + "[" + std::to_string(i) + "]", -1e9, 1e9, &x));
    out->push_back(x);
  }
  return {};
}

bool Null(const YAML::Node& v) {
  return !v || v.IsNull();
}

// A YAML number as the layout file writes it: exact for float32 and float64 values.
std::string Num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

class Reader {
 public:
  Reader(const std::string& path, const robot::RobotModel& robot, const Model& model, const AgentFile* agent)
      : f_(path), path_(path), robot_(robot), model_(model), agent_(agent) {}

  Result<DeployImport> Run(const YAML::Node& root, const std::string& format, const std::string& layout_path,
                           const std::string& mapping_path);

 private:
  Status Joints(const YAML::Node& root);
  Status Gains(const YAML::Node& root);
  Status Actions(const YAML::Node& root);
  Status Observations(const YAML::Node& root);
  Result<TermSignals> Term(const std::string& name, const YAML::Node& term, const std::string& where);
  std::string Layout() const;
  Result<std::string> Mapping() const;

  YamlFields f_;
  std::string path_;
  const robot::RobotModel& robot_;
  const Model& model_;
  const AgentFile* agent_;                     // its clip_actions bounds the raw actions; may be null
  std::vector<std::uint32_t> motor_of_joint_;  // policy joint -> robot motor (joint_ids_map)
  std::vector<double> default_pos_;            // policy order
  struct Obs {
    std::string term, signal;
    double scale = 1, offset = 0, clip = 0;  // clip 0: none
    std::uint32_t history = 1;
  };
  struct Act {
    std::string joint;
    double scale = 1, offset = 0, low = 0, high = 0;
  };
  std::vector<Obs> obs_;
  std::vector<std::vector<std::size_t>> terms_;  // per term, its elements in obs_
  std::vector<std::uint32_t> term_history_;
  std::vector<Act> act_;
  std::vector<std::string> notes_;
};

Status Reader::Joints(const YAML::Node& root) {
  const YAML::Node ids = root["joint_ids_map"];
  if (!ids || !ids.IsSequence() || ids.size() == 0)
    return f_.Fail("joint_ids_map", "missing or empty: the robot's motor index of each policy joint");
  const auto motors = static_cast<long>(robot_.motors.size());
  std::vector<int> policy_joint_of(robot_.motors.size(), -1);
  for (std::size_t i = 0; i < ids.size(); ++i) {
    double v = 0;
    const std::string w = "joint_ids_map[" + std::to_string(i) + "]";
    PBPPO_TRY(f_.Scalar(ids[i], w, 0, 1e9, &v));
    if (v != std::floor(v) || v >= static_cast<double>(motors))
      return f_.Fail(w, YamlFields::Num(v) + " is not a motor index of robot '" + robot_.name + "' (0.." +
                            std::to_string(motors - 1) + ")");
    const auto m = static_cast<std::uint32_t>(v);
    if (policy_joint_of[m] >= 0)
      return f_.Fail(w, "motor " + std::to_string(m) + " (" + robot_.motors[m].joint + ") is already policy joint " +
                            std::to_string(policy_joint_of[m]));
    if (robot_.motors[m].velocity_commanded())
      return f_.Fail(w, "motor " + std::to_string(m) + " (" + robot_.motors[m].joint +
                            ") is velocity-commanded: a JointPositionAction cannot drive it");
    policy_joint_of[m] = static_cast<int>(i);
    motor_of_joint_.push_back(m);
  }
  std::string uncovered;
  for (std::size_t m = 0; m < robot_.motors.size(); ++m)
    if (policy_joint_of[m] < 0) uncovered += (uncovered.empty() ? "" : ", ") + robot_.motors[m].joint;
  if (!uncovered.empty())
    notes_.push_back("joints:      the policy drives " + std::to_string(motor_of_joint_.size()) + " of " +
                     std::to_string(motors) + " motors; not " + uncovered + " (they keep their neutral commands)");
  PBPPO_TRY(Numbers(f_, root, "default_joint_pos", "", motor_of_joint_.size(), false, &default_pos_));
  // The file names no joint: a default pose far from the robot's is the sign of a file for another
  // robot or of a joint_ids_map in another order, either of which would send targets to the wrong
  // joints. Within kPoseTolerance: said, and the file's offsets used.
  constexpr double kPoseTolerance = 0.1;
  double worst = 0;
  std::string at;
  for (std::size_t i = 0; i < motor_of_joint_.size(); ++i) {
    const robot::MotorSpec& mo = robot_.motors[motor_of_joint_[i]];
    const double d = std::fabs(default_pos_[i] - mo.default_q_rad);
    if (d > kPoseTolerance)
      return f_.Fail("default_joint_pos[" + std::to_string(i) + "]",
                     YamlFields::Num(default_pos_[i]) + " rad for policy joint " + std::to_string(i) + " (motor " +
                         std::to_string(motor_of_joint_[i]) + ", " + mo.joint + "), but the robot's default pose is " +
                         YamlFields::Num(mo.default_q_rad) +
                         " rad there: a deploy file for another robot, or a "
                         "joint_ids_map in another joint order?");
    if (d > worst) {
      worst = d;
      at = mo.joint;
    }
  }
  if (worst > 1e-3)
    notes_.push_back("default pose: differs from the robot's by up to " + YamlFields::Num(worst) + " rad (" + at +
                     "): the controller stands the robot up to its own pose, the policy's offsets are the file's");
  return {};
}

// stiffness and damping in motor order: the gains the robot tracks the policy's targets with.
Status Reader::Gains(const YAML::Node& root) {
  for (const char* key : {"stiffness", "damping"}) {
    const YAML::Node v = root[key];
    if (!v || !v.IsSequence()) return f_.Fail(key, "missing: the gains the policy was trained with, in motor order");
    for (std::size_t i = 0; i < motor_of_joint_.size(); ++i) {
      const std::uint32_t m = motor_of_joint_[i];
      const std::string w = std::string(key) + "[" + std::to_string(m) + "]";
      if (m >= v.size())
        return f_.Fail(key, std::to_string(v.size()) + " values, but joint_ids_map names motor " + std::to_string(m));
      double g = 0;
      PBPPO_TRY(f_.Scalar(v[m], w, 0, 1e9, &g));
      const robot::MotorSpec& mo = robot_.motors[m];
      const bool kp = std::string(key) == "stiffness";
      const double robot_gain = kp ? mo.policy_kp : mo.policy_kd;
      if (robot_gain < 0)
        return f_.Fail(w, YamlFields::Num(g) + " for joint " + mo.joint + ", but robot '" + robot_.name +
                              "' declares no policy gains (robot.yaml motors.policy_gains)");
      if (std::fabs(g - robot_gain) > 1e-6 * std::max(1.0, std::fabs(robot_gain)))
        return f_.Fail(w, YamlFields::Num(g) + " for joint " + mo.joint + ", but robot '" + robot_.name +
                              "' tracks a policy's targets with " + (kp ? "kp " : "kd ") + YamlFields::Num(robot_gain) +
                              " (robot.yaml motors.policy_gains): the policy would run with other gains than it "
                              "was trained with");
    }
  }
  return {};
}

Status Reader::Actions(const YAML::Node& root) {
  YAML::Node actions;
  PBPPO_TRY(f_.Map(root, "actions", "", &actions));
  for (const auto& kv : actions) {
    const std::string name = YamlKey(kv.first);
    if (name != "JointPositionAction")
      return f_.Fail("actions." + name,
                     "an action term the layout cannot express (only JointPositionAction: joint "
                     "position targets)");
  }
  if (actions.size() != 1) return f_.Fail("actions", "one term expected (JointPositionAction)");
  const YAML::Node a = actions["JointPositionAction"];
  const std::string where = "actions.JointPositionAction";
  if (!a.IsMap()) return f_.Fail(where, "not a map");
  PBPPO_TRY(f_.Keys(a, where, {"clip", "joint_names", "scale", "offset", "joint_ids"}));
  const YAML::Node names = a["joint_names"];
  if (!Null(names) && !(names.IsSequence() && names.size() == 1 && names[0].IsScalar() && names[0].Scalar() == ".*"))
    return f_.Fail(where + ".joint_names", YamlFields::Quote(names) + ": only [.*] (every joint of joint_ids_map)");
  if (!Null(a["joint_ids"]))
    return f_.Fail(where + ".joint_ids",
                   YamlFields::Quote(a["joint_ids"]) + ": only null (the action drives every joint of joint_ids_map)");
  const std::size_t n = motor_of_joint_.size();
  std::vector<double> scale, offset;
  PBPPO_TRY(Numbers(f_, a, "scale", where, n, true, &scale));
  PBPPO_TRY(Numbers(f_, a, "offset", where, n, true, &offset));
  const YAML::Node clip = a["clip"];
  if (!Null(clip) && (!clip.IsSequence() || clip.size() != n))
    return f_.Fail(where + ".clip", "expected null or " + std::to_string(n) + " [low, high] pairs");
  for (std::size_t i = 0; i < n; ++i) {
    const robot::MotorSpec& mo = robot_.motors[motor_of_joint_[i]];
    const robot::CommandSpec& c = robot_.commands[mo.q];
    Act x{mo.joint, scale[i], offset[i], c.min, c.max};
    if (scale[i] == 0.0)
      return f_.Fail(where + ".scale[" + std::to_string(i) + "]", "0: the policy could not move joint " + mo.joint);
    if (!Null(clip)) {
      const std::string w = where + ".clip[" + std::to_string(i) + "]";
      const YAML::Node pair = clip[i];
      if (!pair.IsSequence() || pair.size() != 2) return f_.Fail(w, "expected [low, high]");
      double lo = 0, hi = 0;
      PBPPO_TRY(f_.Scalar(pair[0], w + "[0]", -1e9, 1e9, &lo));
      PBPPO_TRY(f_.Scalar(pair[1], w + "[1]", -1e9, 1e9, &hi));
      x.low = std::max(x.low, lo);
      x.high = std::min(x.high, hi);
      if (!(lo <= hi) || !(x.low <= x.high))
        return f_.Fail(w, "[" + YamlFields::Num(lo) + ", " + YamlFields::Num(hi) + "] leaves no target inside joint " +
                              mo.joint + "'s limits [" + YamlFields::Num(c.min) + ", " + YamlFields::Num(c.max) + "]");
    }
    // rsl_rl's clip_actions: the environment wrapper clips the raw action before the action term
    // scales and offsets it, so each target lies within offset -+ clip x |scale|.
    if (agent_ != nullptr && agent_->clip_actions > 0) {
      const double c_raw = agent_->clip_actions, lo = offset[i] - c_raw * std::fabs(scale[i]),
                   hi = offset[i] + c_raw * std::fabs(scale[i]);
      x.low = std::max(x.low, lo);
      x.high = std::min(x.high, hi);
      if (!(x.low <= x.high))
        return MakeError(ErrorCode::kInvalidValue,
                         agent_->origin + ": clip_actions: " + YamlFields::Num(c_raw) + " bounds joint " + mo.joint +
                             "'s targets to [" + YamlFields::Num(lo) + ", " + YamlFields::Num(hi) +
                             "], outside its limits [" + YamlFields::Num(c.min) + ", " + YamlFields::Num(c.max) + "]");
    }
    act_.push_back(x);
  }
  if (agent_ != nullptr && agent_->clip_actions > 0)
    notes_.push_back("actions:     " + agent_->origin + " clip_actions " + YamlFields::Num(agent_->clip_actions) +
                     ": each raw action within [-" + YamlFields::Num(agent_->clip_actions) + ", " +
                     YamlFields::Num(agent_->clip_actions) + "] before its scale (the targets' limits narrowed)");
  return {};
}

// The signals of a term: names as the robot's signals and fields spell them (runtime/robot/signals.hpp).
Result<TermSignals> Reader::Term(const std::string& name, const YAML::Node& term, const std::string& where) {
  TermSignals t;
  const YAML::Node params = term["params"];
  const bool no_params = Null(params) || (params.IsMap() && params.size() == 0);
  auto joints = [&](const char* prefix, bool relative) {
    for (std::size_t i = 0; i < motor_of_joint_.size(); ++i) {
      t.signals.push_back(prefix + robot_.motors[motor_of_joint_[i]].joint);
      t.offsets.push_back(relative ? default_pos_[i] : 0.0);
    }
  };
  if (name == "base_ang_vel") {
    t.signals = {"base_ang_vel_x", "base_ang_vel_y", "base_ang_vel_z"};
  } else if (name == "projected_gravity") {
    t.signals = {"projected_gravity_x", "projected_gravity_y", "projected_gravity_z"};
  } else if (name == "velocity_commands" || name == "generated_commands") {
    const bool base_velocity = !Null(params) && params.IsMap() && params.size() == 1 && params["command_name"] &&
                               params["command_name"].IsScalar() && params["command_name"].Scalar() == "base_velocity";
    if (!params)
      return f_.Fail(where,
                     "missing field 'params': the robot's operator gives base_velocity only ({command_name: "
                     "base_velocity})");
    if (!base_velocity)
      return f_.Fail(where + ".params", YamlFields::Quote(params) +
                                            ": the robot's operator gives base_velocity only ({command_name: "
                                            "base_velocity})");
    t.signals = {"command_vx", "command_vy", "command_yaw_rate"};
  } else if (name == "joint_pos_rel" || name == "joint_pos") {
    joints("q_", name == "joint_pos_rel");
  } else if (name == "joint_vel_rel" || name == "joint_vel") {
    joints("dq_", false);  // the default joint velocity is 0
  } else if (name == "last_action" || name == "actions") {
    joints("last_action_", false);
  } else {
    return f_.Fail(where, "an observation term no signal of robot '" + robot_.name +
                              "' gives (the importer knows base_ang_vel, projected_gravity, velocity_commands, "
                              "joint_pos_rel, joint_pos, joint_vel_rel, joint_vel, last_action)");
  }
  if (t.offsets.empty()) t.offsets.assign(t.signals.size(), 0.0);
  if (name != "velocity_commands" && name != "generated_commands" && !no_params)
    return f_.Fail(where + ".params", YamlFields::Quote(params) +
                                          ": parameters the layout cannot express (a joint subset, another asset)");
  return t;
}

Status Reader::Observations(const YAML::Node& root) {
  YAML::Node obs;
  PBPPO_TRY(f_.Map(root, "observations", "", &obs));
  if (obs.size() == 0) return f_.Fail("observations", "no term");
  for (const auto& kv : obs) {
    const std::string name = YamlKey(kv.first);
    const std::string where = "observations." + name;
    const YAML::Node term = kv.second;
    if (!term.IsMap()) return f_.Fail(where, "not a map");
    PBPPO_TRY(f_.Keys(term, where, {"params", "clip", "scale", "history_length"}));
    auto signals = Term(name, term, where);
    if (!signals) return std::move(signals).error();
    const std::size_t n = signals->signals.size();
    std::vector<double> scale(n, 1.0);
    if (!Null(term["scale"])) PBPPO_TRY(Numbers(f_, term, "scale", where, n, true, &scale));
    double history = 1;
    if (!Null(term["history_length"])) PBPPO_TRY(f_.Number(term, "history_length", where, 0, 64, &history));
    if (history != std::floor(history))
      return f_.Fail(where + ".history_length", YamlFields::Num(history) + " is not a whole number");
    // Isaac Lab clips the term's value, then scales it; the layout scales, then clips: a
    // symmetric clip c becomes c |scale| per element.
    double clip = 0;
    const YAML::Node c = term["clip"];
    if (!Null(c)) {
      std::vector<double> lohi;
      PBPPO_TRY(Numbers(f_, term, "clip", where, 2, false, &lohi));
      if (!(lohi[1] > 0 && lohi[0] == -lohi[1]))
        return f_.Fail(where + ".clip", "[" + YamlFields::Num(lohi[0]) + ", " + YamlFields::Num(lohi[1]) +
                                            "] is not symmetric about 0: the layout clips symmetrically");
      clip = lohi[1];
    }
    std::vector<std::size_t> elements;
    for (std::size_t k = 0; k < n; ++k) {
      if (scale[k] == 0.0) return f_.Fail(where + ".scale[" + std::to_string(k) + "]", "0: the element would be lost");
      for (const Obs& o : obs_)
        if (o.signal == signals->signals[k])
          return f_.Fail(where, "signal " + signals->signals[k] + " is already observed by term " + o.term +
                                    " (a layout element is one signal)");
      elements.push_back(obs_.size());
      obs_.push_back({name, signals->signals[k], scale[k], signals->offsets[k], clip * std::fabs(scale[k]),
                      std::max<std::uint32_t>(1, static_cast<std::uint32_t>(history))});
    }
    terms_.push_back(std::move(elements));
    term_history_.push_back(std::max<std::uint32_t>(1, static_cast<std::uint32_t>(history)));
  }
  return {};
}

std::string Reader::Layout() const {
  std::string t = "# The IO layout of " + path_ + " for robot '" + robot_.name +
                  "' (pbppo import-onnx --deploy): each\n# observation is clamp((signal - offset) * scale, -clip, "
                  "clip) with its history, each action\n# command = clamp(action * scale + offset, low, high).\n";
  t += "robot: " + robot_.io->robot + "\nobservations:\n";
  for (const Obs& o : obs_) {
    t += "  - {name: " + o.signal + ", signal: " + o.signal + ", scale: " + Num(o.scale);
    if (o.offset != 0.0) t += ", offset: " + Num(o.offset);
    if (o.clip > 0.0) t += ", clip: " + Num(o.clip);
    if (o.history > 1) t += ", history: " + std::to_string(o.history);
    t += "}  # " + o.term + "\n";
  }
  t += "actions:\n";
  for (const Act& a : act_)
    t += "  - {name: " + a.joint + ", command: q_des_" + a.joint + ", unit: rad, scale: " + Num(a.scale) +
         ", offset: " + Num(a.offset) + ", low: " + Num(a.low) + ", high: " + Num(a.high) + "}\n";
  return t;
}

Result<std::string> Reader::Mapping() const {
  std::string t = "# The mapping of " + model_.origin + " onto the layout beside it, from " + path_ +
                  " (pbppo import-onnx --deploy).\n";
  t += "robot: " + robot_.io->robot + "\n";
  t += "input: {name: " + model_.input.name + ", size: " + std::to_string(model_.input.size) + "}\n";
  t += "output: {name: " + model_.output.name + ", size: " + std::to_string(model_.output.size) + "}\n";
  // A recurrent model's state: rsl_rl's exporter names it X_in -> X_out.
  std::string state;
  for (std::size_t i = 1; i < model_.inputs.size(); ++i) {
    const std::string& in = model_.inputs[i].name;
    const bool named = in.size() > 3 && in.compare(in.size() - 3, 3, "_in") == 0;
    const std::string out = named ? in.substr(0, in.size() - 3) + "_out" : "";
    if (!named || model_.FindOutput(out) == nullptr)
      return MakeError(ErrorCode::kUnsupported,
                       model_.origin + ": graph input '" + in +
                           "' is not the observation and has no '<name>_out' output to be fed back from: a deploy "
                           "file does not say which output is its next state (write a mapping file with its state "
                           "and import with --map)");
    state += "  - {input: " + in + ", output: " + out + "}\n";
  }
  if (!state.empty()) t += "state:\n" + state;
  const std::uint32_t h = *std::max_element(term_history_.begin(), term_history_.end());
  if (h > 1) t += "history: {length: " + std::to_string(h) + ", order: term-major, oldest: first}\n";
  t += "observations:\n";
  for (std::size_t k = 0; k < terms_.size(); ++k) {
    std::string names;
    for (std::size_t e : terms_[k]) names += (names.empty() ? "" : ", ") + obs_[e].signal;
    if (h > 1 && term_history_[k] != h) {
      t += "  - {term: [" + names + "], history: " + std::to_string(term_history_[k]) + "}\n";
    } else if (h > 1) {
      t += "  - [" + names + "]\n";
    } else {
      for (std::size_t e : terms_[k]) t += "  - " + obs_[e].signal + "\n";
    }
  }
  t += "actions:\n";
  for (const Act& a : act_) t += "  - " + a.joint + "\n";
  return t;
}

Result<DeployImport> Reader::Run(const YAML::Node& node, const std::string& format, const std::string& layout_path,
                                 const std::string& mapping_path) {
  if (!robot_.io) return MakeError(ErrorCode::kMismatch, robot_.path + ": files: no io_layout");
  const YAML::Node* root = &node;
  if (!root->IsMap()) return f_.Fail("", "not a map of fields (a deploy.yaml)");
  PBPPO_TRY(f_.Keys(*root, "",
                    {"joint_ids_map", "step_dt", "stiffness", "damping", "default_joint_pos", "commands", "actions",
                     "observations"}));
  double step = 0;
  PBPPO_TRY(f_.Number(*root, "step_dt", "", 1e-6, 10.0, &step));
  if (std::fabs(step - robot_.policy_period_s) > 1e-9)
    return f_.Fail("step_dt", YamlFields::Num(step) + " s, but robot '" + robot_.name + "' runs its policy every " +
                                  YamlFields::Num(robot_.policy_period_s) + " s (robot.yaml timing.policy_period_s)");
  PBPPO_TRY(Joints(*root));
  PBPPO_TRY(Gains(*root));
  PBPPO_TRY(Actions(*root));
  PBPPO_TRY(Observations(*root));
  if (const YAML::Node c = (*root)["commands"]; c && c.IsMap() && c["base_velocity"] && c["base_velocity"]["ranges"]) {
    std::string r;
    for (const auto& kv : c["base_velocity"]["ranges"])
      if (kv.second.IsSequence() && kv.second.size() == 2)
        r += (r.empty() ? "" : ", ") + YamlKey(kv.first) + " [" + kv.second[0].Scalar() + ", " + kv.second[1].Scalar() +
             "]";
    notes_.push_back("commands:    trained on " + r + " (the robot's operator limits apply, not these)");
  }
  DeployImport d;
  d.layout_text = Layout();
  auto mapping = Mapping();
  if (!mapping) return std::move(mapping).error();
  d.mapping_text = *mapping;
  auto layout = robot::ParseIoLayout(d.layout_text, layout_path);
  if (!layout) return std::move(layout).error();
  d.layout = std::move(*layout);
  if (auto signals = robot::SignalProgram::ForLayout(robot_, d.layout); !signals)
    return MakeError(signals.error().code, path_ + ": " + signals.error().message);
  auto map = ParseMapping(d.mapping_text, mapping_path, d.layout);
  if (!map) return std::move(map).error();
  d.mapping = std::move(*map);
  d.notes = notes_;
  d.notes.insert(d.notes.begin(), "deploy:      " + path_ + " (" + format + "): " + std::to_string(terms_.size()) +
                                      " observation terms, " + std::to_string(obs_.size()) + " layout observations, " +
                                      std::to_string(act_.size()) + " joint position actions");
  return d;
}

Result<DeployImport> ParseDeployText(const std::string& text, const std::string& origin, const robot::RobotModel& robot,
                                     const Model& model, const std::string& layout_path,
                                     const std::string& mapping_path, const std::vector<std::string>& joints,
                                     const AgentFile* agent) {
  auto root = robot::ParseYaml(text, origin);
  if (!root) return std::move(root).error();
  // An Isaac Lab env.yaml holds its simulation and scene; a deploy.yaml holds neither.
  const bool isaac = root->IsMap() && (*root)["scene"] && (*root)["decimation"];
  if (!isaac) {
    if (!joints.empty())
      return MakeError(ErrorCode::kInvalidValue,
                       "--joints: a deploy.yaml orders the joints itself (joint_ids_map); --joints is for an Isaac "
                       "Lab env.yaml");
    Reader r(origin, robot, model, agent);
    return r.Run(*root, "unitree_rl_lab deploy.yaml", layout_path, mapping_path);
  }
  std::vector<std::string> notes;
  auto converted = IsaacEnvAsDeploy(*root, origin, robot, joints, &notes);
  if (!converted) return std::move(converted).error();
  // Checked by the deploy.yaml reader: its messages name the deploy.yaml field the env.yaml gave.
  Reader r(origin + " (as deploy.yaml)", robot, model, agent);
  auto d = r.Run(*converted, "Isaac Lab env.yaml", layout_path, mapping_path);
  if (!d) return d;
  d->notes.insert(d->notes.begin() + 1, notes.begin(), notes.end());
  return d;
}

}  // namespace

Result<DeployImport> ParseDeployFile(const std::string& text, const std::string& origin, const robot::RobotModel& robot,
                                     const Model& model, const std::string& layout_path,
                                     const std::string& mapping_path, const std::vector<std::string>& joints,
                                     const AgentFile* agent) {
  // The readers look before they take (Null, IsMap, Key); a YAML node used in a way they did not
  // foresee still ends as a refusal naming the file, never as an exception out of the import.
  try {
    return ParseDeployText(text, origin, robot, model, layout_path, mapping_path, joints, agent);
  } catch (const YAML::Exception& e) {
    return MakeError(ErrorCode::kFormat, origin + ": " + e.what());
  }
}

Result<DeployImport> ReadDeployFile(const std::string& path, const robot::RobotModel& robot, const Model& model,
                                    const std::string& layout_path, const std::string& mapping_path,
                                    const std::vector<std::string>& joints, const AgentFile* agent) {
  auto text = robot::ReadTextFile(path);
  if (!text) return std::move(text).error();
  return ParseDeployFile(*text, path, robot, model, layout_path, mapping_path, joints, agent);
}

}  // namespace pbppo::onnx
