#include "runtime/robot/io_layout.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>

namespace pbppo::robot {
namespace {

std::string Num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.9g", v);
  return b;
}

std::string Hex(std::uint64_t v) {
  char b[24];
  std::snprintf(b, sizeof b, "0x%016llx", static_cast<unsigned long long>(v));
  return b;
}

class Parser {
 public:
  explicit Parser(std::string origin) : origin_(std::move(origin)) {}

  Error Fail(const std::string& where, const std::string& what) const {
    return MakeError(ErrorCode::kInvalidValue, origin_ + ": " + where + ": " + what);
  }

  Status Text(const YAML::Node& n, const char* key, const std::string& where, bool required, std::string* out) {
    const YAML::Node v = n[key];
    if (!v) {
      if (required) return Fail(where, std::string("missing field '") + key + "'");
      return {};
    }
    if (!v.IsScalar()) return Fail(where + "." + key, "is not a string");
    *out = v.as<std::string>();
    if (required && out->empty()) return Fail(where + "." + key, "is empty");
    for (char ch : *out) {
      const auto c = static_cast<unsigned char>(ch);
      if (c < 0x21 || c > 0x7E)
        return Fail(where + "." + key, "'" + *out + "' has a character outside printable ASCII or a space");
    }
    return {};
  }

  Status Number(const YAML::Node& n, const char* key, const std::string& where, double* out) {
    const YAML::Node v = n[key];
    if (!v) return {};  // default stays
    if (!v.IsScalar()) return Fail(where + "." + key, "is not a number");
    const std::string s = v.as<std::string>();
    char* end = nullptr;
    const double d = std::strtod(s.c_str(), &end);
    if (s.empty() || *end != '\0') return Fail(where + "." + key, "'" + s + "' is not a number");
    if (!std::isfinite(d)) return Fail(where + "." + key, "'" + s + "' is not finite");
    *out = d;
    return {};
  }

  Status CheckKeys(const YAML::Node& n, const std::string& where, std::initializer_list<const char*> allowed) {
    for (const auto& kv : n) {
      const std::string k = kv.first.as<std::string>();
      bool ok = false;
      for (const char* a : allowed) ok |= k == a;
      if (!ok) return Fail(where, "unknown field '" + k + "'");
    }
    return {};
  }

 private:
  std::string origin_;
};

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
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    return MakeError(ErrorCode::kFormat,
                     origin + ": YAML error at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  Parser p(origin);
  if (!root.IsMap()) return p.Fail("top level", "expected a mapping with robot, observations, actions");
  if (auto st = p.CheckKeys(root, "top level", {"robot", "observations", "actions", "description"}); !st)
    return st.error();
  IoLayout l;
  if (auto st = p.Text(root, "robot", "top level", true, &l.robot); !st) return st.error();
  const YAML::Node obs = root["observations"], act = root["actions"];
  if (!obs || !obs.IsSequence() || obs.size() == 0) return p.Fail("observations", "expected a non-empty list");
  if (!act || !act.IsSequence() || act.size() == 0) return p.Fail("actions", "expected a non-empty list");
  std::set<std::string> names;
  for (std::size_t i = 0; i < obs.size(); ++i) {
    const std::string w = "observations[" + std::to_string(i) + "]";
    const YAML::Node n = obs[i];
    if (!n.IsMap()) return p.Fail(w, "expected a mapping");
    if (auto st = p.CheckKeys(n, w, {"name", "signal", "unit", "scale", "offset", "clip", "history"}); !st)
      return st.error();
    ObservationElement e;
    if (auto st = p.Text(n, "name", w, true, &e.name); !st) return st.error();
    e.signal = e.name;
    if (auto st = p.Text(n, "signal", w, false, &e.signal); !st) return st.error();
    e.unit = "1";
    if (auto st = p.Text(n, "unit", w, false, &e.unit); !st) return st.error();
    if (auto st = p.Number(n, "scale", w, &e.scale); !st) return st.error();
    if (auto st = p.Number(n, "offset", w, &e.offset); !st) return st.error();
    if (auto st = p.Number(n, "clip", w, &e.clip); !st) return st.error();
    double history = 1;
    if (auto st = p.Number(n, "history", w, &history); !st) return st.error();
    if (e.scale == 0.0) return p.Fail(w + ".scale", "0 would erase the signal");
    if (!(e.clip > 0.0)) return p.Fail(w + ".clip", Num(e.clip) + " is not positive");
    if (history < 1 || history > 64 || history != std::floor(history)) {
      return p.Fail(w + ".history", Num(history) + " is not an integer in 1..64");
    }
    e.history = static_cast<std::uint32_t>(history);
    if (!names.insert("obs:" + e.name).second) return p.Fail(w + ".name", "'" + e.name + "' appears twice");
    l.observations.push_back(std::move(e));
  }
  for (std::size_t i = 0; i < act.size(); ++i) {
    const std::string w = "actions[" + std::to_string(i) + "]";
    const YAML::Node n = act[i];
    if (!n.IsMap()) return p.Fail(w, "expected a mapping");
    if (auto st = p.CheckKeys(n, w, {"name", "command", "unit", "scale", "offset", "low", "high"}); !st)
      return st.error();
    ActionElement e;
    if (auto st = p.Text(n, "name", w, true, &e.name); !st) return st.error();
    e.command = e.name;
    if (auto st = p.Text(n, "command", w, false, &e.command); !st) return st.error();
    e.unit = "1";
    if (auto st = p.Text(n, "unit", w, false, &e.unit); !st) return st.error();
    if (auto st = p.Number(n, "scale", w, &e.scale); !st) return st.error();
    if (auto st = p.Number(n, "offset", w, &e.offset); !st) return st.error();
    if (auto st = p.Number(n, "low", w, &e.low); !st) return st.error();
    if (auto st = p.Number(n, "high", w, &e.high); !st) return st.error();
    if (!(e.low <= e.high)) return p.Fail(w, "low " + Num(e.low) + " is above high " + Num(e.high));
    if (!names.insert("act:" + e.name).second) return p.Fail(w + ".name", "'" + e.name + "' appears twice");
    l.actions.push_back(std::move(e));
  }
  if (l.observation_size() > 1024) return p.Fail("observations", "more than 1024 inputs");
  return l;
}

Result<IoLayout> LoadIoLayout(const std::string& path) {
  std::ifstream f(path);
  if (!f) return MakeError(ErrorCode::kIo, path + ": cannot open");
  std::stringstream ss;
  ss << f.rdbuf();
  return ParseIoLayout(ss.str(), path);
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
    spec.action_low.push_back(static_cast<float>(a.low));
    spec.action_high.push_back(static_cast<float>(a.high));
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
