// The operator's hands in robot.yaml: the axes and buttons of evdev transports (gamepads) mapped
// onto a stream's fields, and the operator section's requests from fields (runtime/robot/
// transport_spec.hpp, robot_model.hpp say what each means).
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>

#include "runtime/robot/input_codes.hpp"
#include "runtime/robot/robot_model_parts.hpp"

namespace pbppo::robot::detail {
namespace {

using Rule = YamlFields::TextRule;

// The field `name` of stream `stream`, or an error at `where`.
Status StreamField(const RobotModel& m, const YamlFields& f, std::uint32_t stream, const std::string& name,
                   const std::string& where, std::uint32_t* out) {
  const int field = m.FieldIndex(name);
  if (field < 0 || m.fields[static_cast<std::size_t>(field)].stream != stream)
    return f.Fail(where, "'" + name + "' is not a field of stream '" + m.streams[stream].name + "'");
  *out = static_cast<std::uint32_t>(field);
  return {};
}

// The field's range must hold [lo, hi] (every value the device can give in range), at `where`.
Status Holds(const RobotModel& m, const YamlFields& f, std::uint32_t field, double lo, double hi,
             const std::string& where) {
  const FieldSpec& s = m.fields[field];
  if (s.min > lo || s.max < hi)
    return f.Fail(where, "field '" + s.name + "' has range [" + YamlFields::Num(s.min) + ", " + YamlFields::Num(s.max) +
                             "], which does not hold [" + YamlFields::Num(lo) + ", " + YamlFields::Num(hi) +
                             "] that it can take");
  return {};
}

}  // namespace

Status ReadAxisShape(const RobotModel& m, const YamlFields& f, const YAML::Node& a, const std::string& wa,
                     std::uint32_t field, bool device_range, AxisShape* out) {
  std::array<double, 2> range{-1.0, 1.0};
  if (device_range || a["range"]) {
    PBPPO_TRY(f.Range(a, "range", wa, -2147483648.0, 2147483647.0, &range));
    const bool whole = range[0] == std::floor(range[0]) && range[1] == std::floor(range[1]);
    if (!(range[1] > range[0]) || (device_range && !whole)) {
      std::string what(1, '[');
      what += YamlFields::Num(range[0]);
      what += ", ";
      what += YamlFields::Num(range[1]);
      what += device_range ? "] is not two whole numbers" : "] is not two numbers";
      return f.Fail(wa + ".range", what + ", the first below the second");
    }
  }
  out->raw_min = range[0];
  out->raw_max = range[1];
  PBPPO_TRY(f.Number(a, "scale", wa, -1e6, 1e6, &out->scale));
  if (out->scale == 0) return f.Fail(wa + ".scale", "0 gives nothing");
  PBPPO_TRY(f.OptionalNumber(a, "dead_zone", wa, 0.0, 0.9, &out->dead_zone));
  return Holds(m, f, field, -std::abs(out->scale), std::abs(out->scale), wa + ".scale");
}

Status Builder::EvdevMappings(const YAML::Node& root) {
  const YAML::Node list = root["transports"];
  for (std::uint32_t t = 0; t < m.transports.size(); ++t) {
    TransportSpec& spec = m.transports[t];
    if (spec.kind != "evdev") continue;
    const std::string w = "transports[" + std::to_string(t) + "]";
    const YAML::Node& n = list[t];
    EvdevTransportSpec& e = spec.evdev;
    if (!e.device.empty() && e.device[0] != '/') e.device = (std::filesystem::path(m.dir) / e.device).string();
    std::string stream;
    PBPPO_TRY(f.Text(n, "stream", w, &stream, Rule::kToken));
    const int s = m.StreamIndex(stream);
    if (s < 0) return f.Fail(w + ".stream", "'" + stream + "' is not a stream of the robot");
    e.stream = static_cast<std::uint32_t>(s);
    if (m.streams[e.stream].transport != spec.name)
      return f.Fail(w + ".stream", "stream '" + stream + "' is delivered by transport '" +
                                       m.streams[e.stream].transport + "', not '" + spec.name + "'");
    for (std::uint32_t other = 0; other < m.streams.size(); ++other)
      if (other != e.stream && m.streams[other].transport == spec.name)
        return f.Fail(w + ".stream", "transport '" + spec.name + "' delivers one stream; '" + m.streams[other].name +
                                         "' names it too");
    std::vector<int> filled(m.streams[e.stream].field_count, 0);
    std::vector<int> axis_codes, button_codes;
    if (const YAML::Node axes = n["axes"]) {
      if (!axes.IsMap()) return f.Fail(w + ".axes", "expected a mapping field: {code, range, ...}");
      for (const auto& kv : axes) {
        const std::string field = kv.first.as<std::string>();
        const std::string wa = w + ".axes." + field;
        const YAML::Node& a = kv.second;
        if (!a.IsMap()) return f.Fail(wa, "expected a mapping {code, range, scale, dead_zone, rate_per_s}");
        PBPPO_TRY(f.Keys(a, wa, {"code", "range", "scale", "dead_zone", "rate_per_s"}));
        EvdevAxisSpec x;
        PBPPO_TRY(StreamField(m, f, e.stream, field, wa, &x.field));
        std::string code;
        PBPPO_TRY(f.Text(a, "code", wa, &code, Rule::kToken));
        x.code = InputCode(InputCodeKind::kAxis, code);
        if (x.code < 0)
          return f.Fail(wa + ".code", "'" + code + "' is not an axis (" + InputCodeNames(InputCodeKind::kAxis) + ")");
        if (std::count(axis_codes.begin(), axis_codes.end(), x.code) > 0)
          return f.Fail(wa + ".code", code + " drives two fields");
        PBPPO_TRY(ReadAxisShape(m, f, a, wa, x.field, true, &x.shape));
        PBPPO_TRY(f.OptionalNumber(a, "rate_per_s", wa, 1e-6, 1e9, &x.rate_per_s));
        axis_codes.push_back(x.code);
        ++filled[x.field - m.streams[e.stream].first_field];
        e.axes.push_back(x);
      }
    }
    if (const YAML::Node buttons = n["buttons"]) {
      if (!buttons.IsMap()) return f.Fail(w + ".buttons", "expected a mapping field: code");
      for (const auto& kv : buttons) {
        const std::string field = kv.first.as<std::string>();
        const std::string wb = w + ".buttons." + field;
        EvdevButtonSpec b;
        PBPPO_TRY(StreamField(m, f, e.stream, field, wb, &b.field));
        std::string code;
        PBPPO_TRY(f.Text(buttons, field.c_str(), w + ".buttons", &code, Rule::kToken));
        b.code = InputCode(InputCodeKind::kButton, code);
        if (b.code < 0)
          return f.Fail(wb, "'" + code + "' is not a button (" + InputCodeNames(InputCodeKind::kButton) + ")");
        if (std::count(button_codes.begin(), button_codes.end(), b.code) > 0)
          return f.Fail(wb, code + " drives two fields");
        PBPPO_TRY(Holds(m, f, b.field, 0.0, 1.0, wb));
        button_codes.push_back(b.code);
        ++filled[b.field - m.streams[e.stream].first_field];
        e.buttons.push_back(b);
      }
    }
    for (std::size_t k = 0; k < filled.size(); ++k) {
      const std::string& name = m.fields[m.streams[e.stream].first_field + k].name;
      if (filled[k] == 0) return f.Fail(w, "field '" + name + "' of stream '" + stream + "' is no axis or button");
      if (filled[k] > 1) return f.Fail(w, "field '" + name + "' is both an axis and a button");
    }
  }
  return {};
}

Status Builder::From(const YAML::Node& n) {
  // operator.from: {request: [phase, ...]}: the phases, among the controller's, a request is taken in.
  if (!n.IsMap()) return f.Fail("operator.from", "expected a mapping of requests to lists of phases");
  PBPPO_TRY(f.Keys(n, "operator.from", {"arm", "sit", "switch_policy"}));
  OperatorSpec& op = m.op;
  const struct {
    const char* key;
    std::int32_t field;
    PhaseSet controller;
    PhaseSet* out;
  } narrowed[] = {{"arm", op.arm, kArmPhases, &op.from_arm},
                  {"sit", op.sit, kSitPhases, &op.from_sit},
                  {"switch_policy", op.switch_policy, kSwitchPhases, &op.from_switch}};
  const auto names = [](PhaseSet set) {
    std::string out;
    for (std::size_t k = 0; k < kPhaseCount; ++k)
      if (InPhases(set, static_cast<Phase>(k))) {
        if (!out.empty()) out += ", ";
        out += ToString(static_cast<Phase>(k));
      }
    return out;
  };
  for (const auto& r : narrowed) {
    if (!n[r.key]) continue;
    const std::string w = std::string("operator.from.") + r.key;
    if (r.field < 0) return f.Fail(w, std::string("operator.") + r.key + " is not given: no request to take");
    YAML::Node list;
    PBPPO_TRY(f.List(n, r.key, "operator.from", true, &list));
    if (list.size() == 0) return f.Fail(w, "empty: the request would never be taken (leave it out of operator)");
    PhaseSet set = 0;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string at = w + "[" + std::to_string(i) + "]";
      const std::string name = list[i].IsScalar() ? list[i].Scalar() : YamlFields::Quote(list[i]);
      const int p = PhaseIndex(name);
      if (p < 0) return f.Fail(at, "'" + name + "' is not a phase (" + names(kAllPhases) + ")");
      if (!InPhases(r.controller, static_cast<Phase>(p)))
        return f.Fail(at, "the controller does not take " + std::string(r.key) + " in " + name + " (it does in " +
                              names(r.controller) + ")");
      set = static_cast<PhaseSet>(set | (1u << static_cast<unsigned>(p)));
    }
    *r.out = set;
  }
  return {};
}

Status Builder::Operator(const YAML::Node& root) {
  if (!root["operator"]) return {};
  YAML::Node n;
  PBPPO_TRY(f.Map(root, "operator", "", &n));
  PBPPO_TRY(f.Keys(n, "operator",
                   {"arm", "walk", "sit", "stop", "estop", "rearm", "deadman", "switch_policy", "switch",
                    "deadman_sit_after_s", "from", "rearm_to"}));
  OperatorSpec& op = m.op;
  const std::pair<const char*, std::int32_t*> requests[] = {
      {"arm", &op.arm},     {"walk", &op.walk},   {"sit", &op.sit},         {"stop", &op.stop},
      {"estop", &op.estop}, {"rearm", &op.rearm}, {"deadman", &op.deadman}, {"switch_policy", &op.switch_policy}};
  std::vector<std::string> used;
  for (const auto& [key, out] : requests) {
    std::string name;
    PBPPO_TRY(f.OptionalText(n, key, "operator", &name, Rule::kToken));
    if (name.empty()) continue;
    const std::string w = std::string("operator.") + key;
    *out = m.FieldIndex(name);
    if (*out < 0) return f.Fail(w, "'" + name + "' is not a field of the robot");
    if (std::find(used.begin(), used.end(), name) != used.end())
      return f.Fail(w, "field '" + name + "' makes another request already");
    used.push_back(name);
    PBPPO_TRY(Holds(m, f, static_cast<std::uint32_t>(*out), 0.0, 1.0, w));
  }
  if (n["switch"]) {
    YAML::Node sw;
    PBPPO_TRY(f.Map(n, "switch", "operator", &sw));
    PBPPO_TRY(f.Keys(sw, "operator.switch", {"rule", "duration_s"}));
    std::string rule;
    PBPPO_TRY(f.Text(sw, "rule", "operator.switch", &rule, Rule::kToken));
    if (rule != "blend" && rule != "hold") return f.Fail("operator.switch.rule", "'" + rule + "' is not blend or hold");
    op.switch_rule = rule == "blend" ? SwitchRule::kBlend : SwitchRule::kHold;
    PBPPO_TRY(f.Number(sw, "duration_s", "operator.switch", 0.0, 60.0, &op.switch_s));
  }
  if (op.walk >= 0 && m.phases.enable_motors == false)
    return f.Fail("operator.walk", "the robot has no motors, so no hold to walk from (arm runs it)");
  if (op.sit >= 0 && m.phases.sit_down_s <= 0)
    return f.Fail("operator.sit",
                  "the robot does not sit: phases.sit_down_s is not given (nor, for a robot "
                  "without motors, anything to sit with)");
  if (n["from"]) PBPPO_TRY(From(n["from"]));
  if (n["rearm_to"]) {
    std::string to;
    PBPPO_TRY(f.Text(n, "rearm_to", "operator", &to, Rule::kToken));
    if (to != "stand" && to != "passive") return f.Fail("operator.rearm_to", "'" + to + "' is not stand or passive");
    if (to == "passive" && !m.phases.enable_motors)
      return f.Fail("operator.rearm_to", "the robot has no motors to leave passive (it runs again when re-armed)");
    op.rearm_to_passive = to == "passive";
  }
  if (n["deadman_sit_after_s"]) {
    const char* w = "operator.deadman_sit_after_s";
    PBPPO_TRY(f.Number(n, "deadman_sit_after_s", "operator", 0.001, 3600.0, &op.deadman_sit_after_s));
    if (op.deadman < 0) return f.Fail(w, "no dead-man to release (operator.deadman is not given)");
    if (m.phases.sit_down_s <= 0) return f.Fail(w, "the robot does not sit: phases.sit_down_s is not given");
  }
  return {};
}

}  // namespace pbppo::robot::detail
