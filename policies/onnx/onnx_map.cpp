#include "policies/onnx/onnx_map.hpp"

#include <map>

#include "runtime/robot/text_file.hpp"
#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::onnx {

using robot::YamlFields;

Result<Mapping> ParseMapping(const std::string& yaml_text, const std::string& origin, const robot::IoLayout& layout) {
  auto root = robot::ParseYaml(yaml_text, origin);
  if (!root) return std::move(root).error();
  const YamlFields f(origin);
  PBPPO_TRY(f.Keys(*root, "", {"robot", "input", "output", "observations", "actions"}));
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

  const std::vector<std::string> obs_names = layout.ObservationNames();
  const std::vector<std::string> act_names = layout.ActionNames();
  std::map<std::string, std::size_t> obs_index, act_index;
  for (std::size_t i = 0; i < obs_names.size(); ++i) obs_index[obs_names[i]] = i;
  for (std::size_t i = 0; i < act_names.size(); ++i) act_index[act_names[i]] = i;

  YAML::Node obs;
  PBPPO_TRY(f.List(*root, "observations", "", true, &obs));
  if (obs.size() != m.input_size)
    return f.Fail("observations", std::to_string(obs.size()) + " entries, but input.size is " +
                                      std::to_string(m.input_size) + " (one entry per input element)");
  std::vector<std::int64_t> fed_by(obs_names.size(), -1);
  for (std::size_t k = 0; k < obs.size(); ++k) {
    const std::string w = "observations[" + std::to_string(k) + "]";
    const YAML::Node e = obs[k];
    if (e.IsMap()) {
      PBPPO_TRY(f.Keys(e, w, {"constant"}));
      double c = 0;
      PBPPO_TRY(f.Number(e, "constant", w, -1e30, 1e30, &c));
      m.input_source.push_back(-1);
      m.input_constant.push_back(c);
      continue;
    }
    if (!e.IsScalar())
      return f.Fail(w, YamlFields::Quote(e) + " is neither a layout observation name nor {constant: VALUE}");
    const std::string name = e.Scalar();
    auto it = obs_index.find(name);
    if (it == obs_index.end())
      return f.Fail(w, "'" + name + "' is not an observation of the '" + layout.robot + "' layout");
    if (fed_by[it->second] >= 0)
      return f.Fail(w, "'" + name + "' already feeds input element " + std::to_string(fed_by[it->second]));
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
