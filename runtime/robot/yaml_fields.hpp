// The one field reader for every YAML file of the project (robot files, IO layouts, CAN maps,
// robot descriptions, the AUV's plant, task and layouts, trajectories). Set-up time only. Every
// error names the file, the element path and the field, and quotes the offending value:
//
//   can_map.yaml: motors[1] 'LF_HFE'.bus: unknown bus 'rear'
//   auv.yaml: hull.mass_kg: '-3' is outside [1e-06, 1e+09]
//   io_layout.yaml: observations[2].gain: unknown field
//
// `where` is the path of the mapping that holds the field ("" at the top level); fields are
// joined to it with '.'.
#pragma once

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdint>
#include <initializer_list>
#include <string>

#include "runtime/core/result.hpp"

// Returns the error of a Status (or Result) expression from the function it is in (the readers'
// long lists of fields).
#define PBPPO_TRY(expr)            \
  do {                             \
    if (auto st_ = (expr); !st_) { \
      return st_.error();          \
    }                              \
  } while (false)

namespace pbppo::robot {

// Parses YAML text; syntax errors name the origin and the line.
Result<YAML::Node> ParseYaml(const std::string& text, const std::string& origin);
// Reads (ReadTextFile: counted) and parses a file; errors name the path.
Result<YAML::Node> LoadYamlFile(const std::string& path);

class YamlFields {
 public:
  explicit YamlFields(std::string origin) : origin_(std::move(origin)) {}

  const std::string& origin() const noexcept { return origin_; }
  // "origin: where: what" (kInvalidValue).
  Error Fail(const std::string& where, const std::string& what) const;
  // where.key ("key" at the top level).
  static std::string Join(const std::string& where, const std::string& key);
  // The name of a mapping in messages: `where`, or "top level".
  static std::string Place(const std::string& where) { return where.empty() ? "top level" : where; }

  // Refuses keys outside `allowed` (a typo must not fall back silently to a default).
  Status Keys(const YAML::Node& map, const std::string& where, std::initializer_list<const char*> allowed) const;
  // A required mapping.
  Status Map(const YAML::Node& parent, const char* key, const std::string& where, YAML::Node* out) const;
  // A list; absent: an error when required, else an empty list.
  Status List(const YAML::Node& parent, const char* key, const std::string& where, bool required,
              YAML::Node* out) const;

  // Calls each(item, where) on every item of the list `key` (as List), `where` naming the item
  // ("key[i]" under the parent's place); the first error stops the walk and is returned.
  template <typename Each>
  Status EachItem(const YAML::Node& parent, const char* key, const std::string& where, bool required, Each each) const {
    YAML::Node list;
    if (auto st = List(parent, key, where, required, &list); !st) return st;
    for (std::size_t i = 0; i < list.size(); ++i)
      if (auto st = each(list[i], Join(where, key) + "[" + std::to_string(i) + "]"); !st) return st;
    return {};
  }

  // A required finite number in [lo, hi].
  Status Number(const YAML::Node& map, const char* key, const std::string& where, double lo, double hi,
                double* out) const;
  // An optional number: absent keeps *out.
  Status OptionalNumber(const YAML::Node& map, const char* key, const std::string& where, double lo, double hi,
                        double* out) const;
  // A required whole number in [lo, hi].
  Status Integer(const YAML::Node& map, const char* key, const std::string& where, long lo, long hi, long* out) const;
  Status Count(const YAML::Node& map, const char* key, const std::string& where, std::uint32_t lo, std::uint32_t hi,
               std::uint32_t* out) const;
  // A decimal or 0x-hexadecimal identifier in [lo, hi] (CAN identifiers).
  Status Id(const YAML::Node& map, const char* key, const std::string& where, std::uint32_t lo, std::uint32_t hi,
            std::uint32_t* out) const;
  // An optional true/false: absent keeps *out.
  Status Bool(const YAML::Node& map, const char* key, const std::string& where, bool* out) const;

  enum class TextRule : std::uint8_t {
    kAny,    // any non-empty string
    kToken,  // printable ASCII, no space (names that go into hashes and file formats)
  };
  // A required non-empty string.
  Status Text(const YAML::Node& map, const char* key, const std::string& where, std::string* out,
              TextRule rule = TextRule::kAny) const;
  // An optional string: absent keeps *out.
  Status OptionalText(const YAML::Node& map, const char* key, const std::string& where, std::string* out,
                      TextRule rule = TextRule::kAny) const;

  // A fixed-length list of numbers, each in [lo, hi].
  template <std::size_t N>
  Status Array(const YAML::Node& map, const char* key, const std::string& where, double lo, double hi,
               std::array<double, N>* out) const {
    YAML::Node v;
    if (auto st = Sequence(map, key, where, N, &v); !st) return st;
    for (std::size_t i = 0; i < N; ++i) {
      if (auto st = Scalar(v[i], Join(where, key) + "[" + std::to_string(i) + "]", lo, hi, &(*out)[i]); !st) return st;
    }
    return {};
  }
  // A range [low, high] with lo <= low <= high <= hi.
  Status Range(const YAML::Node& map, const char* key, const std::string& where, double lo, double hi,
               std::array<double, 2>* out) const;

  // One scalar node as a finite number in [lo, hi]; `field` names it in errors.
  Status Scalar(const YAML::Node& v, const std::string& field, double lo, double hi, double* out) const;

  static std::string Num(double v);
  static std::string Hex(std::uint32_t v);
  // The node as the file spells it, in quotes ('1.5', '[1, 2]').
  static std::string Quote(const YAML::Node& v);

 private:
  Status Sequence(const YAML::Node& map, const char* key, const std::string& where, std::size_t n,
                  YAML::Node* out) const;
  std::string origin_;
};

}  // namespace pbppo::robot
