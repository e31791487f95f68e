#include "policies/onnx/rsl_rl_agent.hpp"

#include <cctype>
#include <filesystem>

#include "runtime/robot/text_file.hpp"
#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::onnx {
namespace {

using robot::YamlFields;

// A field the file gives a value: present, not null, not the configuration's unset marker.
bool Given(const YAML::Node& v) {
  if (!v || v.IsNull()) return false;
  return !(v.IsScalar() && (v.Scalar() == "???" || v.Scalar() == "MISSING"));
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

Status Word(const YamlFields& f, const YAML::Node& map, const char* key, const std::string& where, std::string* out) {
  const YAML::Node v = map[key];
  if (!Given(v)) return {};
  if (!v.IsScalar()) return f.Fail(YamlFields::Join(where, key), YamlFields::Quote(v) + " is not a name");
  *out = v.Scalar();
  return {};
}

Status Flag(const YamlFields& f, const YAML::Node& map, const char* key, const std::string& where, bool* out) {
  if (!Given(map[key])) return {};
  return f.Bool(map, key, where, out);
}

// rsl_rl's activation names onto the blob's (those the importer takes); false for the others.
bool BlobActivation(const std::string& name, policy::Activation* out) {
  const std::string n = Lower(name);
  if (n == "elu")
    *out = policy::Activation::kElu;
  else if (n == "relu")
    *out = policy::Activation::kRelu;
  else if (n == "lrelu")
    *out = policy::Activation::kLeakyRelu;
  else if (n == "tanh")
    *out = policy::Activation::kTanh;
  else if (n == "identity")
    *out = policy::Activation::kIdentity;
  else
    return false;
  return true;
}

std::string Dims(const std::vector<std::uint32_t>& d) {
  std::string s = "[";
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (i > 0) s += ", ";
    s += std::to_string(d[i]);
  }
  return s + "]";
}

Result<AgentFile> ParseAgentText(const std::string& text, const std::string& origin) {
  auto root = robot::ParseYaml(text, origin);
  if (!root) return std::move(root).error();
  YamlFields f(origin);
  if (!root->IsMap()) return f.Fail("", "not a map of fields (rsl_rl's agent.yaml)");
  AgentFile a;
  a.origin = origin;
  // rsl_rl >= 4 describes the actor as a model of its own; earlier versions as the policy.
  const bool model = Given((*root)["actor"]);
  a.section = model ? "actor" : "policy";
  const YAML::Node s = (*root)[a.section];
  if (!Given(s)) return f.Fail("", "neither actor (rsl_rl 4) nor policy (earlier): no actor described");
  if (!s.IsMap()) return f.Fail(a.section, YamlFields::Quote(s) + " is not a map");
  PBPPO_TRY(Word(f, s, "class_name", a.section, &a.class_name));
  const char* dims_key = model ? "hidden_dims" : "actor_hidden_dims";
  if (const YAML::Node d = s[dims_key]; Given(d)) {
    const std::string w = a.section + "." + dims_key;
    if (!d.IsSequence()) return f.Fail(w, YamlFields::Quote(d) + " is not a list of widths");
    for (std::size_t i = 0; i < d.size(); ++i) {
      double v = 0;
      PBPPO_TRY(f.Scalar(d[i], w + "[" + std::to_string(i) + "]", 1, 1 << 20, &v));
      if (v != static_cast<double>(static_cast<std::uint32_t>(v)))
        return f.Fail(w + "[" + std::to_string(i) + "]", YamlFields::Num(v) + " is not a whole number");
      a.hidden_dims.push_back(static_cast<std::uint32_t>(v));
    }
  }
  PBPPO_TRY(Word(f, s, "activation", a.section, &a.activation));
  // Observation normalisation: the actor's own switch, or (before rsl_rl 2.3) the runner's.
  bool norm = false;
  const char* norm_key = model ? "obs_normalization" : "actor_obs_normalization";
  PBPPO_TRY(Flag(f, s, norm_key, a.section, &norm));
  if (norm) a.normaliser_field = a.section + "." + norm_key;
  bool empirical = false;
  PBPPO_TRY(Flag(f, *root, "empirical_normalization", "", &empirical));
  if (empirical && a.normaliser_field.empty()) a.normaliser_field = "empirical_normalization";
  // A recurrent actor: its memory ahead of the MLP.
  const bool recurrent_class = a.class_name == "ActorCriticRecurrent" || a.class_name == "RNNModel";
  if (Given(s["rnn_type"]) || recurrent_class) {
    const std::string w = a.section + ".rnn_type";
    PBPPO_TRY(Word(f, s, "rnn_type", a.section, &a.rnn_type));
    if (a.rnn_type.empty()) return f.Fail(w, "missing: class " + a.class_name + " is recurrent");
    a.rnn_type = Lower(a.rnn_type);
    if (a.rnn_type != "lstm" && a.rnn_type != "gru") return f.Fail(w, "'" + a.rnn_type + "' is not lstm or gru");
    PBPPO_TRY(f.Count(s, "rnn_hidden_dim", a.section, 1, 1 << 16, &a.rnn_hidden_dim));
    PBPPO_TRY(f.Count(s, "rnn_num_layers", a.section, 1, 64, &a.rnn_num_layers));
  }
  if (Given((*root)["clip_actions"])) PBPPO_TRY(f.Number(*root, "clip_actions", "", 1e-9, 1e9, &a.clip_actions));
  return a;
}

}  // namespace

Result<AgentFile> ParseAgentFile(const std::string& text, const std::string& origin) {
  try {
    return ParseAgentText(text, origin);
  } catch (const YAML::Exception& e) {  // a node used in a way the reader did not foresee
    return MakeError(ErrorCode::kFormat, origin + ": " + e.what());
  }
}

Result<AgentFile> ReadAgentFile(const std::string& path) {
  auto text = robot::ReadTextFile(path);
  if (!text) return std::move(text).error();
  return ParseAgentFile(*text, path);
}

std::string AgentFileBeside(const std::string& deploy_path) {
  const std::filesystem::path p = std::filesystem::path(deploy_path).parent_path() / "agent.yaml";
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec) ? p.string() : std::string();
}

Result<std::vector<std::string>> CheckActor(const AgentFile& a, const policy::PolicySpec& spec, bool graph_normalises) {
  YamlFields f(a.origin);
  const std::string& s = a.section;
  // The graph's actor: its recurrent layers first, then the MLP (the last layer the output).
  std::size_t rec = 0;
  while (rec < spec.layers.size() && spec.layers[rec].kind != policy::LayerKind::kDense) ++rec;
  std::string graph = rec == 0 ? "an MLP" : std::string(policy::ToString(spec.layers[0].kind));
  std::vector<std::uint32_t> hidden;
  for (std::size_t l = rec; l + 1 < spec.layers.size(); ++l) hidden.push_back(spec.layers[l].out);
  std::vector<std::string> notes;
  if (a.rnn_type.empty()) {
    if (rec > 0)
      return f.Fail(s + (a.class_name.empty() ? "" : ".class_name"),
                    (a.class_name.empty() ? std::string("no rnn_type") : "'" + a.class_name + "'") +
                        ": a feed-forward actor, but the graph's starts with " + std::to_string(rec) + " " + graph +
                        " layer(s): the agent.yaml of another run?");
  } else {
    const policy::LayerKind want = a.rnn_type == "gru" ? policy::LayerKind::kGru : policy::LayerKind::kLstm;
    if (rec == 0)
      return f.Fail(s + ".rnn_type", "'" + a.rnn_type + "', but the graph's actor has no recurrent layer (" + graph +
                                         "): the agent.yaml of another run, or an export of the MLP alone?");
    if (spec.layers[0].kind != want)
      return f.Fail(s + ".rnn_type", "'" + a.rnn_type + "', but the graph's recurrent layers are " + graph);
    if (rec != a.rnn_num_layers)
      return f.Fail(s + ".rnn_num_layers", std::to_string(a.rnn_num_layers) + ", but the graph's actor has " +
                                               std::to_string(rec) + " " + graph + " layer(s)");
    for (std::size_t l = 0; l < rec; ++l)
      if (spec.layers[l].out != a.rnn_hidden_dim)
        return f.Fail(s + ".rnn_hidden_dim", std::to_string(a.rnn_hidden_dim) + ", but the graph's " + graph +
                                                 " layer " + std::to_string(l) + " holds " +
                                                 std::to_string(spec.layers[l].out));
    notes.push_back("agent.yaml:  " + a.rnn_type + " " + std::to_string(a.rnn_hidden_dim) + " x " +
                    std::to_string(a.rnn_num_layers) + ": the graph's memory");
  }
  const std::string dims_field = s + (s == "actor" ? ".hidden_dims" : ".actor_hidden_dims");
  if (a.hidden_dims.empty()) {
    notes.push_back("agent.yaml:  " + dims_field + " not given: the graph's hidden layers " + Dims(hidden) +
                    " not checked");
  } else if (a.hidden_dims != hidden) {
    return f.Fail(dims_field, Dims(a.hidden_dims) + ", but the graph's actor has hidden layers " + Dims(hidden) +
                                  ": the agent.yaml of another run?");
  }
  if (!a.activation.empty() && !hidden.empty()) {
    policy::Activation want{};
    const policy::Activation have = spec.layers[rec].activation;
    if (!BlobActivation(a.activation, &want) || want != have)
      return f.Fail(s + ".activation",
                    "'" + a.activation + "', but the graph's hidden layers use " + policy::ToString(have));
  }
  if (!a.hidden_dims.empty())
    notes.push_back("agent.yaml:  hidden layers " + Dims(hidden) + (a.activation.empty() ? "" : " " + a.activation) +
                    ": the graph's");
  if (!a.normaliser_field.empty() && !graph_normalises)
    return f.Fail(a.normaliser_field,
                  "true: the policy was trained on normalised observations, but the graph holds no normaliser "
                  "ahead of its first layer (exported without it, the policy would see raw observations): export "
                  "the actor with its observation normaliser");
  if (!a.normaliser_field.empty())
    notes.push_back("agent.yaml:  " + a.normaliser_field + ": the graph's normaliser");
  else if (graph_normalises)
    notes.push_back("agent.yaml:  no observation normalisation asked, yet the graph normalises its inputs (kept)");
  return notes;
}

}  // namespace pbppo::onnx
