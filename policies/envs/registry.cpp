#include "policies/envs/registry.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "policies/envs/auv_nav.hpp"
#include "policies/envs/mujoco_tasks.hpp"
#include "policies/envs/pendulum.hpp"
#include "policies/envs/quadruped_walk.hpp"

namespace pbppo::envs {
namespace {

Error Invalid(const std::string& flag, const std::string& what) {
  return MakeError(ErrorCode::kInvalidValue, "--" + flag + ": " + what);
}

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

bool ParseReal(const std::string& s, double* out) {
  char* end = nullptr;
  *out = std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size() && std::isfinite(*out);
}

bool ParseInteger(const std::string& s, long* out) {
  char* end = nullptr;
  *out = std::strtol(s.c_str(), &end, 10);
  return !s.empty() && end == s.c_str() + s.size();
}

// "a", "a and b", "a, b and c".
std::string JoinNames(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i) s += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
  return s;
}

bool Takes(const EnvFlag& f, EnvPurpose purpose) {
  return (f.use & (purpose == EnvPurpose::kTrain ? EnvFlag::kTrain : EnvFlag::kEval)) != 0;
}

const char* CommandOf(EnvPurpose purpose) {
  return purpose == EnvPurpose::kTrain ? "pbppo train" : "pbppo eval";
}

}  // namespace

// The environments: one registration each (a task family may register several).
const std::vector<EnvSpec>& Environments() {
  static const std::vector<EnvSpec> all = [] {
    std::vector<EnvSpec> v;
    v.push_back(PendulumEnv());
    v.push_back(AuvNavEnv());
    v.push_back(QuadrupedWalkEnv());
    for (EnvSpec& s : MujocoTaskEnvs()) v.push_back(std::move(s));
    return v;
  }();
  return all;
}

EnvFlag Flag(std::string name, EnvFlag::Use use, EnvFlag::Kind kind, std::string default_value, std::string only,
             std::string help, std::function<Status(const std::string&)> check, bool carried_to_eval) {
  EnvFlag f;
  f.name = std::move(name);
  f.use = use;
  f.kind = kind;
  f.default_value = std::move(default_value);
  f.only = std::move(only);
  f.help = std::move(help);
  f.check = std::move(check);
  f.carried_to_eval = carried_to_eval;
  return f;
}

std::function<Status(const std::string&)> OneOf(std::vector<std::string> values) {
  return [values = std::move(values)](const std::string& v) -> Status {
    if (std::find(values.begin(), values.end(), v) != values.end()) return {};
    std::string known;
    for (const auto& k : values) known += (known.empty() ? "" : ", ") + k;
    return MakeError(ErrorCode::kInvalidValue, "'" + v + "' unknown (" + known + ")");
  };
}

std::function<Status(const std::string&)> InRange(double low, double high) {
  return [low, high](const std::string& v) -> Status {
    double x = 0;
    if (ParseReal(v, &x) && x >= low && x <= high) return {};
    return MakeError(ErrorCode::kInvalidValue, v + " is not in [" + Number(low) + ", " + Number(high) + "]");
  };
}

const EnvSpec* FindEnv(const std::string& name) noexcept {
  for (const EnvSpec& s : Environments())
    if (s.name == name) return &s;
  return nullptr;
}

const EnvFlag* FindFlag(const EnvSpec& spec, const std::string& name) noexcept {
  for (const EnvFlag& f : spec.flags)
    if (f.name == name) return &f;
  return nullptr;
}

std::vector<SharedFlag> FlagsFor(EnvFlag::Use use) {
  std::vector<SharedFlag> out;
  for (const EnvSpec& s : Environments()) {
    for (const EnvFlag& f : s.flags) {
      if ((f.use & use) == 0) continue;
      auto it = std::find_if(out.begin(), out.end(), [&](const SharedFlag& x) { return x.flag->name == f.name; });
      if (it == out.end()) it = out.insert(out.end(), SharedFlag{&f, {}, {}});
      it->environments.push_back(s.name);
      it->declarations.push_back(&f);
    }
  }
  return out;
}

std::vector<std::string> EnvNames() {
  std::vector<std::string> names;
  for (const EnvSpec& s : Environments()) names.push_back(s.name);
  return names;
}

std::string DefaultModelsDir() {
  if (const char* env = std::getenv("PBPPO_MODELS_DIR"); env != nullptr && env[0] != '\0') return env;
  return PBPPO_DEFAULT_MODELS_DIR;
}

std::string ModelsDir(const EnvOptions& options) {
  return options.models_dir.empty() ? DefaultModelsDir() : options.models_dir;
}

Result<EnvOptions> ResolveEnvOptions(const EnvOptions& options) {
  const EnvSpec* spec = FindEnv(options.name);
  if (spec == nullptr) {
    std::string known;
    for (const auto& n : EnvNames()) known += (known.empty() ? "" : ", ") + n;
    return MakeError(ErrorCode::kInvalidValue, "--env: '" + options.name + "' unknown (known: " + known + ")");
  }
  EnvOptions r = options;
  for (const auto& [name, value] : options.flags) {
    const EnvFlag* f = FindFlag(*spec, name);
    if (f == nullptr || !Takes(*f, options.purpose)) {
      // Refused naming the environments that have it.
      std::vector<std::string> owners;
      const EnvFlag* first = nullptr;
      for (const EnvSpec& s : Environments()) {
        const EnvFlag* g = FindFlag(s, name);
        if (g == nullptr || !Takes(*g, options.purpose)) continue;
        owners.push_back(s.name);
        if (first == nullptr) first = g;
      }
      if (first != nullptr)
        return Invalid(name, "only " + JoinNames(owners) + " " + first->only + ", not '" + options.name + "'");
      if (f != nullptr)
        return Invalid(name, "'" + options.name + "' does not take it in " + CommandOf(options.purpose));
      return Invalid(name, "no environment has this flag");
    }
    double real = 0;
    long integer = 0;
    switch (f->kind) {
      case EnvFlag::Kind::kText: break;
      case EnvFlag::Kind::kReal:
        if (!ParseReal(value, &real)) return Invalid(name, "'" + value + "' is not a number");
        break;
      case EnvFlag::Kind::kInteger:
        if (!ParseInteger(value, &integer)) return Invalid(name, "'" + value + "' is not a whole number");
        break;
      case EnvFlag::Kind::kSwitch:
        if (value != "true") return Invalid(name, "a switch takes no value ('" + value + "')");
        break;
    }
    if (f->check)
      if (auto st = f->check(value); !st) return Invalid(name, st.error().message);
  }
  for (const EnvFlag& f : spec->flags)
    if (Takes(f, options.purpose) && !f.default_value.empty() && !r.flags.contains(f.name))
      r.flags[f.name] = f.default_value;
  return r;
}

Result<std::unique_ptr<Env>> MakeEnv(const EnvOptions& options) {
  auto resolved = ResolveEnvOptions(options);
  if (!resolved) return std::move(resolved).error();
  return FindEnv(options.name)->make(*resolved);
}

std::string FlagText(const EnvOptions& o, const std::string& name) {
  const auto it = o.flags.find(name);
  return it == o.flags.end() ? std::string() : it->second;
}

double FlagReal(const EnvOptions& o, const std::string& name) {
  double v = 0;
  return ParseReal(FlagText(o, name), &v) ? v : 0.0;
}

long FlagInteger(const EnvOptions& o, const std::string& name) {
  long v = 0;
  return ParseInteger(FlagText(o, name), &v) ? v : 0;
}

bool FlagSet(const EnvOptions& o, const std::string& name) {
  return FlagText(o, name) == "true";
}

nlohmann::json FlagsJson(const EnvOptions& o, EnvFlag::Use use) {
  nlohmann::json j = nlohmann::json::object();
  const EnvSpec* spec = FindEnv(o.name);
  if (spec == nullptr) return j;
  for (const EnvFlag& f : spec->flags) {
    if ((f.use & use) == 0) continue;
    std::string key = f.name;
    std::replace(key.begin(), key.end(), '-', '_');
    switch (f.kind) {
      case EnvFlag::Kind::kText: j[key] = FlagText(o, f.name); break;
      case EnvFlag::Kind::kReal: j[key] = FlagReal(o, f.name); break;
      case EnvFlag::Kind::kInteger: j[key] = FlagInteger(o, f.name); break;
      case EnvFlag::Kind::kSwitch: j[key] = FlagSet(o, f.name); break;
    }
  }
  return j;
}

}  // namespace pbppo::envs
