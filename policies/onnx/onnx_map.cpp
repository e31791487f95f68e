#include "policies/onnx/onnx_map.hpp"

#include <map>

#include "runtime/robot/text_file.hpp"
#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::onnx {

using robot::YamlFields;

namespace {

// One model input element: a layout observation (name) or a constant (name empty); `where` names
// the mapping entry it comes from.
struct Entry {
  std::string where;
  std::string name;
  double constant = 0;
};

// One term of the observations list: its components (each as one frame of it: the entry of "now")
// and how many frames of it the model takes.
struct Term {
  std::vector<Entry> parts;
  std::uint32_t frames = 1;
};

// Reads `history` and `observations` and expands them into one entry per model input element.
Status ExpandObservations(const YamlFields& f, const YAML::Node& root, const robot::IoLayout& layout, Mapping* m,
                          std::vector<Entry>* entries) {
  const bool has_history = static_cast<bool>(root["history"]);
  m->stacked = has_history;
  if (has_history) {
    YAML::Node h;
    PBPPO_TRY(f.Map(root, "history", "", &h));
    PBPPO_TRY(f.Keys(h, "history", {"length", "order", "oldest"}));
    PBPPO_TRY(f.Count(h, "length", "history", 1, 4096, &m->history_length));
    std::string order, oldest;
    PBPPO_TRY(f.Text(h, "order", "history", &order));
    if (order != "frame-major" && order != "term-major")
      return f.Fail("history.order", "'" + order +
                                         "' is neither frame-major (every term of one frame, then the next frame) "
                                         "nor term-major (every frame of one term, then the next term)");
    PBPPO_TRY(f.Text(h, "oldest", "history", &oldest));
    if (oldest != "first" && oldest != "last")
      return f.Fail("history.oldest", "'" + oldest + "' is neither first nor last (where the oldest frame sits)");
    m->frame_major = order == "frame-major";
    m->oldest_first = oldest == "first";
  }
  std::map<std::string, std::uint32_t> history_of;  // the layout's history per element name
  for (const robot::ObservationElement& o : layout.observations) history_of[o.name] = o.history;

  YAML::Node obs;
  PBPPO_TRY(f.List(root, "observations", "", true, &obs));
  std::vector<Term> terms;
  for (std::size_t i = 0; i < obs.size(); ++i) {
    const std::string where = "observations[" + std::to_string(i) + "]";
    Term t;
    t.frames = m->history_length;
    auto component = [&](const YAML::Node& c, const std::string& w) -> Status {
      if (c.IsMap()) {
        PBPPO_TRY(f.Keys(c, w, {"constant"}));
        double v = 0;
        PBPPO_TRY(f.Number(c, "constant", w, -1e30, 1e30, &v));
        t.parts.push_back({w, "", v});
        return {};
      }
      if (!c.IsScalar())
        return f.Fail(w, YamlFields::Quote(c) + " is neither a layout observation name nor {constant: VALUE}");
      const std::string name = c.Scalar();
      if (has_history && name.find('@') != std::string::npos)
        return f.Fail(
            w, "'" + name + "': with a history the mapping names each term once (its frames follow from history)");
      t.parts.push_back({w, name, 0.0});
      return {};
    };
    auto components = [&](const YAML::Node& c, const std::string& w) -> Status {
      if (!c.IsSequence()) return component(c, w);
      if (c.size() == 0) return f.Fail(w, "an empty term");
      for (std::size_t j = 0; j < c.size(); ++j) PBPPO_TRY(component(c[j], w + "[" + std::to_string(j) + "]"));
      return {};
    };
    const YAML::Node e = obs[i];
    if (e.IsMap() && e["term"]) {
      PBPPO_TRY(f.Keys(e, where, {"term", "history"}));
      if (!has_history || m->frame_major)
        return f.Fail(where,
                      "a term's own history needs the mapping's history with order term-major (a "
                      "frame-major frame holds every term)");
      PBPPO_TRY(f.Count(e, "history", where, 1, 4096, &t.frames));
      PBPPO_TRY(components(e["term"], where + ".term"));
    } else {
      PBPPO_TRY(components(e, where));
    }
    terms.push_back(std::move(t));
  }

  // The entry of a term's part at frame position p (0: the first of its frames in the input).
  auto emit = [&](const Term& t, const Entry& part, std::uint32_t p) -> Status {
    Entry en = part;
    if (!part.name.empty()) {
      const std::uint32_t lag = m->oldest_first ? t.frames - 1 - p : p;  // policy steps before now
      auto h = history_of.find(part.name);
      if (has_history && h == history_of.end())
        return f.Fail(part.where, "'" + part.name + "' is not an observation of the '" + layout.robot + "' layout");
      if (has_history && lag >= h->second)
        return f.Fail(part.where, "'" + part.name + "' has a history of " + std::to_string(h->second) + " in the '" +
                                      layout.robot + "' layout, but the mapping takes " + std::to_string(t.frames) +
                                      " frames of it (no '" + part.name + "@-" + std::to_string(lag) + "')");
      if (lag > 0) en.name += "@-" + std::to_string(lag);
    }
    entries->push_back(std::move(en));
    return {};
  };
  if (m->frame_major) {
    for (std::uint32_t p = 0; p < m->history_length; ++p)
      for (const Term& t : terms)
        for (const Entry& part : t.parts) PBPPO_TRY(emit(t, part, p));
  } else {
    for (const Term& t : terms)
      for (std::uint32_t p = 0; p < t.frames; ++p)
        for (const Entry& part : t.parts) PBPPO_TRY(emit(t, part, p));
  }
  return {};
}

}  // namespace

Result<Mapping> ParseMapping(const std::string& yaml_text, const std::string& origin, const robot::IoLayout& layout) {
  auto root = robot::ParseYaml(yaml_text, origin);
  if (!root) return std::move(root).error();
  const YamlFields f(origin);
  PBPPO_TRY(f.Keys(*root, "", {"robot", "input", "output", "state", "history", "observations", "actions"}));
  Mapping m;
  m.origin = origin;
  PBPPO_TRY(f.Text(*root, "robot", "", &m.robot, YamlFields::TextRule::kToken));
  if (m.robot != layout.robot)
    return f.Fail("robot", "'" + m.robot + "', but the robot's IO layout is for '" + layout.robot + "'");
  YAML::Node in, out;
  PBPPO_TRY(f.Map(*root, "input", "", &in));
  PBPPO_TRY(f.Keys(in, "input", {"name", "size"}));
  PBPPO_TRY(f.Text(in, "name", "input", &m.input_name));
  PBPPO_TRY(f.Count(in, "size", "input", 1, 65536, &m.input_size));
  PBPPO_TRY(f.Map(*root, "output", "", &out));
  PBPPO_TRY(f.Keys(out, "output", {"name", "size"}));
  PBPPO_TRY(f.Text(out, "name", "output", &m.output_name));
  PBPPO_TRY(f.Count(out, "size", "output", 1, 65536, &m.output_size));
  if (root->operator[]("state")) {
    YAML::Node st;
    PBPPO_TRY(f.List(*root, "state", "", true, &st));
    for (std::size_t i = 0; i < st.size(); ++i) {
      const std::string where = "state[" + std::to_string(i) + "]";
      if (!st[i].IsMap()) return f.Fail(where, YamlFields::Quote(st[i]) + " is not {input: NAME, output: NAME}");
      PBPPO_TRY(f.Keys(st[i], where, {"input", "output"}));
      StatePair pair;
      PBPPO_TRY(f.Text(st[i], "input", where, &pair.input));
      PBPPO_TRY(f.Text(st[i], "output", where, &pair.output));
      for (const StatePair& q : m.state) {
        if (q.input == pair.input) return f.Fail(where + ".input", "'" + pair.input + "' is already a state input");
        if (q.output == pair.output)
          return f.Fail(where + ".output", "'" + pair.output + "' is already a state output");
      }
      if (pair.input == m.input_name) return f.Fail(where + ".input", "'" + pair.input + "' is the observation input");
      if (pair.output == m.output_name) return f.Fail(where + ".output", "'" + pair.output + "' is the action output");
      m.state.push_back(std::move(pair));
    }
  }

  const std::vector<std::string> obs_names = layout.ObservationNames();
  const std::vector<std::string> act_names = layout.ActionNames();
  std::map<std::string, std::size_t> obs_index, act_index;
  for (std::size_t i = 0; i < obs_names.size(); ++i) obs_index[obs_names[i]] = i;
  for (std::size_t i = 0; i < act_names.size(); ++i) act_index[act_names[i]] = i;

  std::vector<Entry> entries;
  PBPPO_TRY(ExpandObservations(f, *root, layout, &m, &entries));
  if (entries.size() != m.input_size) {
    const std::string count = !m.stacked ? std::to_string(entries.size()) + " entries"
                                         : std::to_string(entries.size()) +
                                               " input elements (every term's frames, history.length " +
                                               std::to_string(m.history_length) + ")";
    return f.Fail("observations",
                  count + ", but input.size is " + std::to_string(m.input_size) + " (one entry per input element)");
  }
  std::vector<std::int64_t> fed_by(obs_names.size(), -1);
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const Entry& e = entries[k];
    if (e.name.empty()) {
      m.input_source.push_back(-1);
      m.input_constant.push_back(e.constant);
      continue;
    }
    auto it = obs_index.find(e.name);
    if (it == obs_index.end())
      return f.Fail(e.where, "'" + e.name + "' is not an observation of the '" + layout.robot + "' layout");
    if (fed_by[it->second] >= 0)
      return f.Fail(e.where, "'" + e.name + "' already feeds input element " + std::to_string(fed_by[it->second]));
    fed_by[it->second] = static_cast<std::int64_t>(k);
    m.input_source.push_back(static_cast<std::int32_t>(it->second));
    m.input_constant.push_back(0.0);
  }
  for (std::size_t i = 0; i < obs_names.size(); ++i)
    if (fed_by[i] < 0)
      return f.Fail("observations",
                    "layout observation '" + obs_names[i] + "' feeds no input element (the policy would not see it)");

  YAML::Node act;
  PBPPO_TRY(f.List(*root, "actions", "", true, &act));
  if (act.size() != m.output_size)
    return f.Fail("actions", std::to_string(act.size()) + " entries, but output.size is " +
                                 std::to_string(m.output_size) + " (one entry per output element)");
  if (act.size() != act_names.size())
    return f.Fail("actions", std::to_string(act.size()) + " entries, but the '" + layout.robot + "' layout has " +
                                 std::to_string(act_names.size()) + " actions (each given by one output element)");
  m.output_of_action.assign(act_names.size(), 0);
  std::vector<bool> given(act_names.size(), false);
  for (std::size_t k = 0; k < act.size(); ++k) {
    const std::string w = "actions[" + std::to_string(k) + "]";
    if (!act[k].IsScalar()) return f.Fail(w, YamlFields::Quote(act[k]) + " is not a layout action name");
    const std::string name = act[k].Scalar();
    auto it = act_index.find(name);
    if (it == act_index.end()) return f.Fail(w, "'" + name + "' is not an action of the '" + layout.robot + "' layout");
    if (given[it->second])
      return f.Fail(
          w, "'" + name + "' is already given by output element " + std::to_string(m.output_of_action[it->second]));
    given[it->second] = true;
    m.output_of_action[it->second] = static_cast<std::uint32_t>(k);
  }
  return m;
}

Result<Mapping> LoadMapping(const std::string& path, const robot::IoLayout& layout) {
  auto text = robot::ReadTextFile(path);
  if (!text) return std::move(text).error();
  return ParseMapping(*text, path, layout);
}

}  // namespace pbppo::onnx
