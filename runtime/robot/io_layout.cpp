#include "runtime/robot/io_layout.hpp"

#include <cmath>
#include <cstdio>
#include <set>

#include "runtime/robot/text_file.hpp"
#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::robot {
namespace {

std::string Num(double v) {
  return YamlFields::Num(v);
}

std::string Hex(std::uint64_t v) {
  char b[24];
  std::snprintf(b, sizeof b, "0x%016llx", static_cast<unsigned long long>(v));
  return b;
}

}  // namespace

std::uint32_t IoLayout::observation_size() const noexcept {
  std::uint32_t n = 0;
  for (const auto& o : observations) n += o.history;
  return n;
}

std::uint32_t IoLayout::action_size() const noexcept {
  return static_cast<std::uint32_t>(actions.size());
}

std::vector<std::string> IoLayout::ObservationNames() const {
  std::vector<std::string> names;
  for (const auto& o : observations) {
    names.push_back(o.name);
    for (std::uint32_t h = 1; h < o.history; ++h) names.push_back(o.name + "@-" + std::to_string(h));
  }
  return names;
}

std::vector<std::string> IoLayout::ActionNames() const {
  std::vector<std::string> names;
  for (const auto& a : actions) names.push_back(a.name);
  return names;
}

std::string IoLayout::CanonicalText() const {
  std::string t = "pbppo-io-layout 1\nrobot " + robot + "\n";
  for (const auto& o : observations) {
    t += "obs " + o.name + " " + o.signal + " " + o.unit + " " + Num(o.scale) + " " + Num(o.offset) + " " +
         Num(o.clip) + " " + std::to_string(o.history) + "\n";
  }
  for (const auto& a : actions) {
    t += "act " + a.name + " " + a.command + " " + a.unit + " " + Num(a.scale) + " " + Num(a.offset) + " " +
         Num(a.low) + " " + Num(a.high) + "\n";
  }
  return t;
}

std::uint64_t IoLayout::Hash() const {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (char c : CanonicalText()) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ull;
  }
  return h;
}

Result<IoLayout> ParseIoLayout(const std::string& yaml_text, const std::string& origin) {
  auto doc = ParseYaml(yaml_text, origin);
  if (!doc) return std::move(doc).error();
  const YAML::Node root = *doc;
  const YamlFields f(origin);
  using Rule = YamlFields::TextRule;
  if (!root.IsMap()) return f.Fail("", "expected a mapping with robot, observations, actions");
  if (auto st = f.Keys(root, "", {"robot", "observations", "actions", "description"}); !st) return st.error();
  IoLayout l;
  if (auto st = f.Text(root, "robot", "", &l.robot, Rule::kToken); !st) return st.error();
  const YAML::Node obs = root["observations"], act = root["actions"];
  if (!obs || !obs.IsSequence() || obs.size() == 0) return f.Fail("observations", "expected a non-empty list");
  if (!act || !act.IsSequence() || act.size() == 0) return f.Fail("actions", "expected a non-empty list");
  constexpr double kInf = HUGE_VAL;
  std::set<std::string> names;
  for (std::size_t i = 0; i < obs.size(); ++i) {
    const std::string w = "observations[" + std::to_string(i) + "]";
    const YAML::Node n = obs[i];
    if (auto st = f.Keys(n, w, {"name", "signal", "unit", "scale", "offset", "clip", "history"}); !st)
      return st.error();
    ObservationElement e;
    if (auto st = f.Text(n, "name", w, &e.name, Rule::kToken); !st) return st.error();
    e.signal = e.name;
    e.unit = "1";
    double history = 1;
    for (const Status& st :
         {f.OptionalText(n, "signal", w, &e.signal, Rule::kToken), f.OptionalText(n, "unit", w, &e.unit, Rule::kToken),
          f.OptionalNumber(n, "scale", w, -kInf, kInf, &e.scale),
          f.OptionalNumber(n, "offset", w, -kInf, kInf, &e.offset),
          f.OptionalNumber(n, "clip", w, -kInf, kInf, &e.clip),
          f.OptionalNumber(n, "history", w, -kInf, kInf, &history)}) {
      if (!st) return st.error();
    }
    if (e.scale == 0.0) return f.Fail(w + ".scale", "0 would erase the signal");
    if (!(e.clip > 0.0)) return f.Fail(w + ".clip", Num(e.clip) + " is not positive");
    if (history < 1 || history > 64 || history != std::floor(history)) {
      return f.Fail(w + ".history", Num(history) + " is not an integer in 1..64");
    }
    e.history = static_cast<std::uint32_t>(history);
    if (!names.insert("obs:" + e.name).second) return f.Fail(w + ".name", "'" + e.name + "' appears twice");
    l.observations.push_back(std::move(e));
  }
  for (std::size_t i = 0; i < act.size(); ++i) {
    const std::string w = "actions[" + std::to_string(i) + "]";
    const YAML::Node n = act[i];
    if (auto st = f.Keys(n, w, {"name", "command", "unit", "scale", "offset", "low", "high"}); !st) return st.error();
    ActionElement e;
    if (auto st = f.Text(n, "name", w, &e.name, Rule::kToken); !st) return st.error();
    e.command = e.name;
    e.unit = "1";
    for (const Status& st :
         {f.OptionalText(n, "command", w, &e.command, Rule::kToken),
          f.OptionalText(n, "unit", w, &e.unit, Rule::kToken), f.OptionalNumber(n, "scale", w, -kInf, kInf, &e.scale),
          f.OptionalNumber(n, "offset", w, -kInf, kInf, &e.offset), f.OptionalNumber(n, "low", w, -kInf, kInf, &e.low),
          f.OptionalNumber(n, "high", w, -kInf, kInf, &e.high)}) {
      if (!st) return st.error();
    }
    if (!(e.low <= e.high)) return f.Fail(w, "low " + Num(e.low) + " is above high " + Num(e.high));
    if (e.scale == 0.0) return f.Fail(w + ".scale", "0 would make every command the offset");
    if (!names.insert("act:" + e.name).second) return f.Fail(w + ".name", "'" + e.name + "' appears twice");
    l.actions.push_back(std::move(e));
  }
  if (l.observation_size() > 1024) return f.Fail("observations", "more than 1024 inputs");
  return l;
}

Result<IoLayout> LoadIoLayout(const std::string& path) {
  auto text = ReadTextFile(path);
  if (!text) return std::move(text).error();
  return ParseIoLayout(*text, path);
}

void ApplyLayoutToSpec(const IoLayout& layout, policy::PolicySpec& spec) {
  spec.io_layout_hash = layout.Hash();
  spec.observation_names = layout.ObservationNames();
  spec.action_names = layout.ActionNames();
  spec.action_scale.clear();
  spec.action_offset.clear();
  spec.action_low.clear();
  spec.action_high.clear();
  for (const auto& a : layout.actions) {
    spec.action_scale.push_back(static_cast<float>(a.scale));
    spec.action_offset.push_back(static_cast<float>(a.offset));
    spec.action_low.push_back(policy::FloatNotBelow(a.low));
    spec.action_high.push_back(policy::FloatNotAbove(a.high));
  }
}

void ToPolicyUnits(const IoLayout& layout, std::span<const float> commands, std::span<float> actions) {
  for (std::size_t j = 0; j < actions.size() && j < layout.actions.size(); ++j) {
    const ActionElement& a = layout.actions[j];
    // In float, as the blob's own float32 action map rounds them (a trained blob's equal these).
    actions[j] = (commands[j] - static_cast<float>(a.offset)) / static_cast<float>(a.scale);
  }
}

Status CheckPolicyMatchesLayout(const policy::PolicySpec& policy, const IoLayout& layout) {
  auto fail = [&](const std::string& what) {
    return MakeError(ErrorCode::kMismatch, "policy does not fit robot layout '" + layout.robot + "': " + what);
  };
  const auto obs = layout.ObservationNames();
  const auto act = layout.ActionNames();
  if (policy.input_size != obs.size()) {
    return fail("the policy takes " + std::to_string(policy.input_size) + " observations, the layout gives " +
                std::to_string(obs.size()));
  }
  if (policy.output_size != act.size()) {
    return fail("the policy gives " + std::to_string(policy.output_size) + " actions, the layout takes " +
                std::to_string(act.size()));
  }
  for (std::size_t i = 0; i < obs.size(); ++i) {
    if (policy.observation_names[i] != obs[i]) {
      return fail("observation " + std::to_string(i) + " is '" + policy.observation_names[i] + "' in the policy, '" +
                  obs[i] + "' in the layout");
    }
  }
  for (std::size_t i = 0; i < act.size(); ++i) {
    if (policy.action_names[i] != act[i]) {
      return fail("action " + std::to_string(i) + " is '" + policy.action_names[i] + "' in the policy, '" + act[i] +
                  "' in the layout");
    }
  }
  if (policy.io_layout_hash != layout.Hash()) {
    return fail("same names, but scales, offsets, clips, units or limits differ (layout hash " +
                Hex(policy.io_layout_hash) + " in the policy, " + Hex(layout.Hash()) + " in the layout)");
  }
  return {};
}

}  // namespace pbppo::robot
