#include "runtime/robot/yaml_fields.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unordered_map>

#include "runtime/robot/text_file.hpp"

namespace pbppo::robot {

namespace {

// Every reader takes a mapping's keys as names: a key that is a list, a mapping or empty
// ("? [a, b]: c", "{[a]: b}", "{: b}") is refused here, where the document is read, with its
// line, so that no reader meets one; so is a key given twice in one mapping (a reader would see
// only the first, the second silently lost).
Status CheckKeys(const YAML::Node& n, const std::string& origin, int depth) {
  auto fail = [&](const YAML::Node& at, const std::string& what) {
    return MakeError(ErrorCode::kFormat,
                     origin + ": YAML error at line " + std::to_string(at.Mark().line + 1) + ": " + what);
  };
  if (depth > 256) return fail(n, "nested more than 256 levels deep");
  if (n.IsMap()) {
    std::unordered_map<std::string, int> line_of;  // key -> its line (1-based)
    for (const auto& kv : n) {
      if (!kv.first.IsScalar()) return fail(kv.first, "a mapping key that is not a name (a list, a mapping or empty)");
      const auto [at, first] = line_of.emplace(kv.first.Scalar(), kv.first.Mark().line + 1);
      if (!first)
        return fail(kv.first, "key '" + kv.first.Scalar() + "' given twice in one mapping (first at line " +
                                  std::to_string(at->second) + ")");
      if (auto st = CheckKeys(kv.second, origin, depth + 1); !st) return st;
    }
  } else if (n.IsSequence()) {
    for (const auto& e : n)
      if (auto st = CheckKeys(e, origin, depth + 1); !st) return st;
  }
  return {};
}

}  // namespace

Result<YAML::Node> ParseYaml(const std::string& text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    return MakeError(ErrorCode::kFormat,
                     origin + ": YAML error at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (auto st = CheckKeys(root, origin, 0); !st) return st.error();
  return root;
}

Result<YAML::Node> LoadYamlFile(const std::string& path) {
  auto text = ReadTextFile(path);
  if (!text) return std::move(text).error();
  return ParseYaml(*text, path);
}

Error YamlFields::Fail(const std::string& where, const std::string& what) const {
  return MakeError(ErrorCode::kInvalidValue, origin_ + ": " + Place(where) + ": " + what);
}

std::string YamlFields::Join(const std::string& where, const std::string& key) {
  return where.empty() ? key : where + "." + key;
}

Status YamlFields::Keys(const YAML::Node& map, const std::string& where,
                        std::initializer_list<const char*> allowed) const {
  if (!map.IsMap()) return Fail(where, "expected a mapping");
  for (const auto& kv : map) {
    const std::string k = kv.first.as<std::string>();
    bool ok = false;
    for (const char* a : allowed) ok = ok || k == a;
    if (!ok) return Fail(Join(where, k), "unknown field");
  }
  return {};
}

Status YamlFields::Map(const YAML::Node& parent, const char* key, const std::string& where, YAML::Node* out) const {
  const YAML::Node v = parent[key];
  if (!v) return Fail(where, std::string("missing field '") + key + "'");
  if (!v.IsMap()) return Fail(Join(where, key), "expected a mapping, got " + Quote(v));
  out->reset(v);  // rebinds: assigning would write into the node *out referred to
  return {};
}

Status YamlFields::List(const YAML::Node& parent, const char* key, const std::string& where, bool required,
                        YAML::Node* out) const {
  const YAML::Node v = parent[key];
  if (!v) {
    if (required) return Fail(where, std::string("missing field '") + key + "'");
    out->reset(YAML::Node(YAML::NodeType::Sequence));
    return {};
  }
  if (!v.IsSequence()) return Fail(Join(where, key), "expected a list, got " + Quote(v));
  out->reset(v);  // rebinds: assigning would write into the node *out referred to
  return {};
}

Status YamlFields::Scalar(const YAML::Node& v, const std::string& field, double lo, double hi, double* out) const {
  if (!v.IsScalar()) return Fail(field, "expected a number, got " + Quote(v));
  const std::string s = v.as<std::string>();
  char* end = nullptr;
  const double d = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0') return Fail(field, "'" + s + "' is not a number");
  if (!std::isfinite(d)) return Fail(field, "'" + s + "' is not finite");
  if (d < lo || d > hi) return Fail(field, "'" + s + "' is outside [" + Num(lo) + ", " + Num(hi) + "]");
  *out = d;
  return {};
}

Status YamlFields::Number(const YAML::Node& map, const char* key, const std::string& where, double lo, double hi,
                          double* out) const {
  const YAML::Node v = map[key];
  if (!v) return Fail(where, std::string("missing field '") + key + "'");
  return Scalar(v, Join(where, key), lo, hi, out);
}

Status YamlFields::OptionalNumber(const YAML::Node& map, const char* key, const std::string& where, double lo,
                                  double hi, double* out) const {
  if (!map[key]) return {};
  return Number(map, key, where, lo, hi, out);
}

Status YamlFields::Integer(const YAML::Node& map, const char* key, const std::string& where, long lo, long hi,
                           long* out) const {
  double d = 0.0;
  if (auto st = Number(map, key, where, static_cast<double>(lo), static_cast<double>(hi), &d); !st) return st;
  if (d != std::floor(d)) return Fail(Join(where, key), Quote(map[key]) + " is not an integer");
  *out = static_cast<long>(d);
  return {};
}

Status YamlFields::Count(const YAML::Node& map, const char* key, const std::string& where, std::uint32_t lo,
                         std::uint32_t hi, std::uint32_t* out) const {
  long v = 0;
  if (auto st = Integer(map, key, where, static_cast<long>(lo), static_cast<long>(hi), &v); !st) return st;
  *out = static_cast<std::uint32_t>(v);
  return {};
}

Status YamlFields::Id(const YAML::Node& map, const char* key, const std::string& where, std::uint32_t lo,
                      std::uint32_t hi, std::uint32_t* out) const {
  const YAML::Node v = map[key];
  const std::string field = Join(where, key);
  if (!v) return Fail(where, std::string("missing field '") + key + "'");
  if (!v.IsScalar()) return Fail(field, "expected an integer, got " + Quote(v));
  const std::string s = v.as<std::string>();
  char* end = nullptr;
  const unsigned long long d = std::strtoull(s.c_str(), &end, 0);
  if (s.empty() || s[0] == '-' || *end != '\0') return Fail(field, "'" + s + "' is not an integer");
  if (d < lo || d > hi) return Fail(field, "'" + s + "' is outside [" + Hex(lo) + ", " + Hex(hi) + "]");
  *out = static_cast<std::uint32_t>(d);
  return {};
}

Status YamlFields::Bool(const YAML::Node& map, const char* key, const std::string& where, bool* out) const {
  const YAML::Node v = map[key];
  if (!v) return {};
  const std::string s = v.IsScalar() ? v.as<std::string>() : Quote(v);
  if (s == "true") {
    *out = true;
  } else if (s == "false") {
    *out = false;
  } else {
    return Fail(Join(where, key), "'" + s + "' is not true or false");
  }
  return {};
}

Status YamlFields::Text(const YAML::Node& map, const char* key, const std::string& where, std::string* out,
                        TextRule rule) const {
  const YAML::Node v = map[key];
  const std::string field = Join(where, key);
  if (!v) return Fail(where, std::string("missing field '") + key + "'");
  if (!v.IsScalar()) return Fail(field, "expected a string, got " + Quote(v));
  std::string s = v.as<std::string>();
  if (s.empty()) return Fail(field, "is empty");
  if (rule == TextRule::kToken) {
    for (char ch : s) {
      const auto c = static_cast<unsigned char>(ch);
      if (c < 0x21 || c > 0x7E) return Fail(field, "'" + s + "' has a character outside printable ASCII or a space");
    }
  }
  *out = std::move(s);
  return {};
}

Status YamlFields::OptionalText(const YAML::Node& map, const char* key, const std::string& where, std::string* out,
                                TextRule rule) const {
  if (!map[key]) return {};
  return Text(map, key, where, out, rule);
}

Status YamlFields::Sequence(const YAML::Node& map, const char* key, const std::string& where, std::size_t n,
                            YAML::Node* out) const {
  const YAML::Node v = map[key];
  if (!v) return Fail(where, std::string("missing field '") + key + "'");
  if (!v.IsSequence() || v.size() != n)
    return Fail(Join(where, key), "expected a list of " + std::to_string(n) + " numbers, got " + Quote(v));
  out->reset(v);  // rebinds: assigning would write into the node *out referred to
  return {};
}

Status YamlFields::Range(const YAML::Node& map, const char* key, const std::string& where, double lo, double hi,
                         std::array<double, 2>* out) const {
  if (auto st = Array<2>(map, key, where, lo, hi, out); !st) return st;
  if ((*out)[0] > (*out)[1])
    return Fail(Join(where, key), "low " + Num((*out)[0]) + " is above high " + Num((*out)[1]));
  return {};
}

std::string YamlFields::Num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.9g", v);
  return b;
}

std::string YamlFields::Hex(std::uint32_t v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%03X", v);
  return b;
}

std::string YamlFields::Quote(const YAML::Node& v) {
  if (!v) return "nothing";  // an absent key's node: asking its type would throw
  std::string q(1, '\'');
  if (v.IsScalar()) {
    q.append(v.as<std::string>());
  } else {
    YAML::Emitter e;
    e << YAML::Flow << v;
    q.append(e.c_str());
  }
  q.push_back('\'');
  return q;
}

}  // namespace pbppo::robot
