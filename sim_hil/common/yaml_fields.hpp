// Field-by-field reading of simulator YAML files (set-up time only). Every error names the file,
// the element path and the field, and quotes the offending value.
#pragma once

#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <set>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"

namespace pbppo::sim {

class YamlFields {
 public:
  explicit YamlFields(std::string origin) : origin_(std::move(origin)) {}

  const std::string& origin() const { return origin_; }

  Error Fail(const std::string& where, const std::string& what) const {
    return MakeError(ErrorCode::kInvalidValue, origin_ + ": " + where + ": " + what);
  }

  static std::string Join(const std::string& where, const std::string& key) {
    return where.empty() ? key : where + "." + key;
  }

  // Refuses keys outside `allowed` (typos must not fall back silently to defaults).
  Status Keys(const YAML::Node& map, const std::string& where, std::initializer_list<const char*> allowed) const {
    if (!map.IsMap()) return Fail(where.empty() ? "top level" : where, "expected a mapping");
    const std::set<std::string> ok(allowed.begin(), allowed.end());
    for (const auto& kv : map) {
      const std::string k = kv.first.as<std::string>();
      if (!ok.count(k)) return Fail(Join(where, k), "unknown field");
    }
    return {};
  }

  Status Map(const YAML::Node& parent, const char* key, const std::string& where, YAML::Node* out) const {
    const YAML::Node v = parent[key];
    if (!v) return Fail(where.empty() ? "top level" : where, std::string("missing field '") + key + "'");
    if (!v.IsMap()) return Fail(Join(where, key), "expected a mapping");
    *out = v;
    return {};
  }

  // A required finite number in [lo, hi].
  Status Number(const YAML::Node& map, const char* key, const std::string& where, double lo, double hi,
                double* out) const {
    const YAML::Node v = map[key];
    if (!v) return Fail(where.empty() ? "top level" : where, std::string("missing field '") + key + "'");
    return Scalar(v, Join(where, key), lo, hi, out);
  }

  // An optional number: absent keeps *out.
  Status OptionalNumber(const YAML::Node& map, const char* key, const std::string& where, double lo, double hi,
                        double* out) const {
    if (!map[key]) return {};
    return Number(map, key, where, lo, hi, out);
  }

  Status Integer(const YAML::Node& map, const char* key, const std::string& where, long lo, long hi, long* out) const {
    double d = 0.0;
    if (auto st = Number(map, key, where, static_cast<double>(lo), static_cast<double>(hi), &d); !st) return st;
    if (d != std::floor(d)) return Fail(Join(where, key), Quote(map[key]) + " is not an integer");
    *out = static_cast<long>(d);
    return {};
  }

  Status Text(const YAML::Node& map, const char* key, const std::string& where, std::string* out) const {
    const YAML::Node v = map[key];
    if (!v) return Fail(where.empty() ? "top level" : where, std::string("missing field '") + key + "'");
    if (!v.IsScalar() || v.as<std::string>().empty()) return Fail(Join(where, key), "expected a non-empty string");
    *out = v.as<std::string>();
    return {};
  }

  // A fixed-length list of numbers, each in [lo, hi].
  template <std::size_t N>
  Status Array(const YAML::Node& map, const char* key, const std::string& where, double lo, double hi,
               std::array<double, N>* out) const {
    const YAML::Node v = map[key];
    if (!v) return Fail(where.empty() ? "top level" : where, std::string("missing field '") + key + "'");
    const std::string w = Join(where, key);
    if (!v.IsSequence() || v.size() != N)
      return Fail(w, "expected a list of " + std::to_string(N) + " numbers, got " + Quote(v));
    for (std::size_t i = 0; i < N; ++i) {
      if (auto st = Scalar(v[i], w + "[" + std::to_string(i) + "]", lo, hi, &(*out)[i]); !st) return st;
    }
    return {};
  }

  // A range [low, high] with lo <= low <= high <= hi.
  Status Range(const YAML::Node& map, const char* key, const std::string& where, double lo, double hi,
               std::array<double, 2>* out) const {
    if (auto st = Array<2>(map, key, where, lo, hi, out); !st) return st;
    if ((*out)[0] > (*out)[1])
      return Fail(Join(where, key), "low " + Num((*out)[0]) + " is above high " + Num((*out)[1]));
    return {};
  }

  static std::string Num(double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.9g", v);
    return b;
  }

  static std::string Quote(const YAML::Node& v) {
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

 private:
  Status Scalar(const YAML::Node& v, const std::string& w, double lo, double hi, double* out) const {
    if (!v.IsScalar()) return Fail(w, "expected a number, got " + Quote(v));
    const std::string s = v.as<std::string>();
    char* end = nullptr;
    const double d = std::strtod(s.c_str(), &end);
    if (s.empty() || *end != '\0') return Fail(w, "'" + s + "' is not a number");
    if (!std::isfinite(d)) return Fail(w, "'" + s + "' is not finite");
    if (d < lo || d > hi) return Fail(w, "'" + s + "' is outside [" + Num(lo) + ", " + Num(hi) + "]");
    *out = d;
    return {};
  }

  std::string origin_;
};

// Reads a whole YAML file; errors name the file.
inline Result<YAML::Node> LoadYamlFile(const std::string& path) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    return MakeError(ErrorCode::kIo, path + ": cannot open");
  } catch (const YAML::Exception& e) {
    return MakeError(ErrorCode::kFormat,
                     path + ": YAML syntax error at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

}  // namespace pbppo::sim
