#include "runtime/robot/robot_model.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include "runtime/robot/find_robot.hpp"
#include "runtime/robot/robot_model_parts.hpp"
#include "runtime/robot/text_file.hpp"

namespace pbppo::robot {
namespace {

constexpr double kInf = HUGE_VAL;
using Rule = YamlFields::TextRule;

class Files {
 public:
  explicit Files(std::string dir) : dir_(std::move(dir)) {}
  std::string PathOf(const std::string& rel) const { return (std::filesystem::path(dir_) / rel).string(); }
  Result<std::string> Read(const std::string& path) {
    auto text = ReadTextFile(path);
    if (!text) return std::move(text).error();
    for (char c : *text) {
      hash_ ^= static_cast<unsigned char>(c);
      hash_ *= 0x100000001b3ull;
    }
    hash_ ^= 0xff;  // file boundary
    hash_ *= 0x100000001b3ull;
    return text;
  }
  std::uint64_t hash() const noexcept { return hash_; }

 private:
  std::string dir_;
  std::uint64_t hash_ = 0xcbf29ce484222325ull;
};

struct Loader : detail::Builder {
  Files& files;

  // Reads `path` (counted) and parses it with parse(text, path) into *out.
  template <typename T>
  Status ParseFile(const std::string& path, Result<T> (*parse)(const std::string&, const std::string&),
                   std::optional<T>* out) {
    auto text = files.Read(path);
    if (!text) return std::move(text).error();
    auto parsed = parse(*text, path);
    if (!parsed) return std::move(parsed).error();
    *out = std::move(*parsed);
    return {};
  }

  Status FilesSection(const YAML::Node& root) {
    YAML::Node n;
    PBPPO_TRY(f.Map(root, "files", "", &n));
    for (const auto& kv : n) {
      const std::string role = kv.first.as<std::string>();
      const std::string where = "files." + role;
      if (kv.second.IsMap()) {
        for (const auto& sub : kv.second) {
          const std::string name = sub.first.as<std::string>();
          auto doc = Read(role + "." + name, sub.second);
          if (!doc) return std::move(doc).error();
          if (role == "trusted_keys") {
            m.trusted_keys.push_back({name, std::move(*doc)});
          } else {
            m.documents[role + "." + name] = std::move(*doc);
          }
        }
        continue;
      }
      if (!kv.second.IsScalar()) return f.Fail(where, "expected a file name or a mapping of names to files");
      const std::string path = files.PathOf(kv.second.as<std::string>());
      if (role == "io_layout") {
        PBPPO_TRY(ParseFile(path, ParseIoLayout, &m.io));
      } else if (role == "can_map") {
        PBPPO_TRY(ParseFile(path, ParseCanMap, &m.can));
      } else if (role == "description") {
        PBPPO_TRY(Description(path));
      } else {
        auto doc = Read(role, kv.second);
        if (!doc) return std::move(doc).error();
        if (role == "dds_profile") {
          m.dds_profile = std::move(*doc);
        } else if (role == "stand_trajectory") {
          m.stand_trajectory = std::move(*doc);
        } else if (role == "trusted_keys") {
          m.trusted_keys.push_back({role, std::move(*doc)});
        } else {
          m.documents[role] = std::move(*doc);
        }
      }
    }
    return {};
  }

  // The file `name` names (role: where robot.yaml names it), read and, for .yaml, parsed.
  Result<RobotDocument> Read(const std::string& role, const YAML::Node& name) {
    if (!name.IsScalar()) return f.Fail("files." + role, "expected a file name, got " + YamlFields::Quote(name));
    RobotDocument d;
    d.path = files.PathOf(name.as<std::string>());
    auto text = files.Read(d.path);
    if (!text) return std::move(text).error();
    d.text = std::move(*text);
    const std::string ext = std::filesystem::path(d.path).extension().string();
    if (ext == ".yaml" || ext == ".yml") {
      auto yaml = ParseYaml(d.text, d.path);
      if (!yaml) return std::move(yaml).error();
      d.yaml = *yaml;
    }
    return d;
  }

  Status Description(const std::string& path) {
    auto text = files.Read(path);
    if (!text) return std::move(text).error();
    const std::string origin = std::filesystem::path(path).filename().string();
    auto doc = ParseYaml(*text, origin);
    if (!doc) return std::move(doc).error();
    std::string urdf_name;
    PBPPO_TRY(YamlFields(origin).Text(*doc, "urdf", "", &urdf_name));
    const std::string urdf_path = (std::filesystem::path(path).parent_path() / urdf_name).string();
    auto urdf_text = files.Read(urdf_path);
    if (!urdf_text) return std::move(urdf_text).error();
    auto urdf = ParseUrdf(*urdf_text, std::filesystem::path(urdf_path).filename().string());
    if (!urdf) return std::move(urdf).error();
    auto body = ParseRobotDescription(*text, origin, std::move(*urdf), urdf_path);
    if (!body) return std::move(body).error();
    m.body = std::move(*body);
    return {};
  }

  Status Timing(const YAML::Node& root) {
    YAML::Node n;
    PBPPO_TRY(f.Map(root, "timing", "", &n));
    PBPPO_TRY(f.Keys(n, "timing", {"tick_period_s", "policy_period_s", "policy_trigger", "lockstep"}));
    PBPPO_TRY(f.Number(n, "tick_period_s", "timing", 1e-6, 10.0, &m.tick_period_s));
    m.policy_period_s = m.tick_period_s;
    PBPPO_TRY(f.OptionalNumber(n, "policy_period_s", "timing", 1e-6, 100.0, &m.policy_period_s));
    return {};
  }

  Status DeclaredStreams(const YAML::Node& root) {
    return f.EachItem(root, "streams", "", false, [&](const YAML::Node& n, const std::string& w) -> Status {
      PBPPO_TRY(f.Keys(
          n, w,
          {"name", "transport", "period_s", "stale_after", "zero_after", "invalid_safe_stop", "required", "fields"}));
      StreamSpec s;
      PBPPO_TRY(f.Text(n, "name", w, &s.name, Rule::kToken));
      PBPPO_TRY(f.Text(n, "transport", w, &s.transport, Rule::kToken));
      PBPPO_TRY(f.Number(n, "period_s", w, 1e-6, 100.0, &s.period_s));
      if (n["zero_after"]) {
        // A command source: its silence stops the command, it is no fault.
        for (const char* k : {"stale_after", "required"})
          if (n[k])
            return f.Fail(YamlFields::Join(w, k),
                          "goes with stale limits; with zero_after the stream's silence is no fault (its fields "
                          "read 0)");
        PBPPO_TRY(f.Number(n, "zero_after", w, 1e-6, 1e6, &s.zero_after));
        s.required = false;
      } else {
        PBPPO_TRY(ReadStale(n, w, &s.stale_after));
      }
      PBPPO_TRY(f.Count(n, "invalid_safe_stop", w, 1, 1000000, &s.invalid_safe_stop));
      PBPPO_TRY(f.Bool(n, "required", w, &s.required));
      const bool zero = s.zero_after > 0;
      PBPPO_TRY(StartStream(std::move(s), w));
      return f.EachItem(n, "fields", w, true, [&](const YAML::Node& field, const std::string& fw) -> Status {
        PBPPO_TRY(f.Keys(field, fw, {"name", "min", "max", "count"}));
        std::string name;
        double lo = -kInf, hi = kInf;
        std::uint32_t count = 0;
        PBPPO_TRY(f.Text(field, "name", fw, &name, Rule::kToken));
        PBPPO_TRY(f.OptionalNumber(field, "min", fw, -kInf, kInf, &lo));
        PBPPO_TRY(f.OptionalNumber(field, "max", fw, -kInf, kInf, &hi));
        if (zero && !(lo <= 0 && 0 <= hi))
          return f.Fail(fw, "'" + name + "': [" + YamlFields::Num(lo) + ", " + YamlFields::Num(hi) +
                                "] does not hold 0, what the stream's fields read after zero_after");
        if (!field["count"]) return AddField(name, lo, hi, fw);
        PBPPO_TRY(f.Count(field, "count", fw, 1, 4096, &count));
        if (name.find("{i}") == std::string::npos) return f.Fail(fw + ".name", "'" + name + "' has no {i}");
        for (std::uint32_t j = 0; j < count; ++j) PBPPO_TRY(AddField(ExpandIndex(name, j), lo, hi, fw));
        return {};
      });
    });
  }

  Status DeclaredCommands(const YAML::Node& root) {
    const Status commands =
        f.EachItem(root, "commands", "", false, [&](const YAML::Node& n, const std::string& w) -> Status {
          PBPPO_TRY(f.Keys(n, w, {"name", "unit", "range", "degraded_range", "rate_per_s", "stop", "neutral"}));
          CommandSpec c;
          std::array<double, 2> range{}, degraded{};
          PBPPO_TRY(f.Text(n, "name", w, &c.name, Rule::kToken));
          c.unit = "1";
          PBPPO_TRY(f.OptionalText(n, "unit", w, &c.unit, Rule::kToken));
          PBPPO_TRY(f.Range(n, "range", w, -kInf, kInf, &range));
          c.min = range[0];
          c.max = range[1];
          degraded = range;
          if (n["degraded_range"]) PBPPO_TRY(f.Range(n, "degraded_range", w, c.min, c.max, &degraded));
          c.degraded_min = degraded[0];
          c.degraded_max = degraded[1];
          PBPPO_TRY(f.OptionalNumber(n, "rate_per_s", w, 1e-9, kInf, &c.rate_per_s));
          PBPPO_TRY(f.OptionalNumber(n, "neutral", w, c.min, c.max, &c.neutral));
          YAML::Node stop;
          PBPPO_TRY(f.Map(n, "stop", w, &stop));
          const std::string sw = w + ".stop";
          PBPPO_TRY(f.Keys(stop, sw, {"ramp_per_s", "value"}));
          if (stop["ramp_per_s"]) {
            c.stop = safety::StopKind::kRamp;
            PBPPO_TRY(f.Number(stop, "ramp_per_s", sw, 1e-9, kInf, &c.stop_ramp_per_s));
          } else {
            c.stop = safety::StopKind::kValue;
            PBPPO_TRY(f.Number(stop, "value", sw, c.min, c.max, &c.stop_value));
          }
          return AddCommand(std::move(c), w);
        });
    if (!commands) return commands;
    if (m.commands.empty()) return f.Fail("commands", "the robot has no command (declare some, or a can_map)");
    return {};
  }

  Status Phases(const YAML::Node& root) {
    PhaseSpec& p = m.phases;
    p.enable_motors = !m.motors.empty();
    if (!root["phases"]) {
      if (p.enable_motors) return f.Fail("", "missing field 'phases' (the robot has motors to switch on and off)");
      return {};
    }
    YAML::Node n;
    PBPPO_TRY(f.Map(root, "phases", "", &n));
    PBPPO_TRY(f.Keys(n, "phases",
                     {"arming_timeout_s", "stand_up_s", "hold_s", "damping_s", "motor_off_timeout_s", "sit_down_s"}));
    for (const Status& st : {f.Number(n, "arming_timeout_s", "phases", 1e-6, 3600.0, &p.arming_timeout_s),
                             f.OptionalNumber(n, "stand_up_s", "phases", 0.0, 3600.0, &p.stand_up_s),
                             f.OptionalNumber(n, "hold_s", "phases", 0.0, 3600.0, &p.hold_s),
                             f.OptionalNumber(n, "damping_s", "phases", 0.0, 3600.0, &p.damping_s),
                             f.OptionalNumber(n, "sit_down_s", "phases", 0.0, 3600.0, &p.sit_down_s),
                             f.Number(n, "motor_off_timeout_s", "phases", 1e-6, 3600.0, &p.motor_off_timeout_s)}) {
      PBPPO_TRY(st);
    }
    return {};
  }

  // supervisor.recovery (optional): {rule: request | automatic, healthy_s, causes, max_automatic}.
  Status Recovery(const YAML::Node& sup) {
    RecoverySpec& r = m.supervisor.recovery;
    if (!sup["recovery"]) return {};
    YAML::Node n;
    const std::string w = "supervisor.recovery";
    PBPPO_TRY(f.Map(sup, "recovery", "supervisor", &n));
    PBPPO_TRY(f.Keys(n, w, {"rule", "healthy_s", "causes", "max_automatic"}));
    std::string rule;
    PBPPO_TRY(f.Text(n, "rule", w, &rule));
    if (rule != "request" && rule != "automatic")
      return f.Fail(w + ".rule", "'" + rule + "' is not request or automatic");
    r.automatic = rule == "automatic";
    PBPPO_TRY(f.OptionalNumber(n, "healthy_s", w, 0.0, 3600.0, &r.healthy_s));
    if (!r.automatic) {
      for (const char* k : {"causes", "max_automatic"})
        if (n[k]) return f.Fail(w + "." + k, "only with rule: automatic");
      return {};
    }
    if (n["max_automatic"]) PBPPO_TRY(f.Count(n, "max_automatic", w, 1, 1000000, &r.max_automatic));
    YAML::Node list;
    PBPPO_TRY(f.List(n, "causes", w, true, &list));
    if (list.size() == 0) return f.Fail(w + ".causes", "empty: name the causes that may recover automatically");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string at = w + ".causes[" + std::to_string(i) + "]";
      const std::string name = list[i].IsScalar() ? list[i].Scalar() : YamlFields::Quote(list[i]);
      std::size_t c = 0;
      while (c < safety::kCauseCount && name != safety::ToString(static_cast<safety::Cause>(c))) ++c;
      if (c == safety::kCauseCount) {
        std::string known;
        for (std::size_t k = 0; k < safety::kCauseCount; ++k)
          known += std::string(k ? ", " : "") + safety::ToString(static_cast<safety::Cause>(k));
        return f.Fail(at, "'" + name + "' is not a cause (known: " + known + ")");
      }
      const auto cause = static_cast<safety::Cause>(c);
      if (cause == safety::Cause::kEStopRequest || cause == safety::Cause::kCommandLimit ||
          cause == safety::Cause::kRateLimit)
        return f.Fail(at, "'" + name + "' cannot recover automatically (" +
                              (cause == safety::Cause::kEStopRequest
                                   ? std::string("an e-stop request is released by disarming and a reset")
                                   : std::string("it never stops the robot")) +
                              ")");
      r.causes |= 1u << c;
    }
    return {};
  }

  Status Supervisor(const YAML::Node& root) {
    YAML::Node n;
    PBPPO_TRY(f.Map(root, "supervisor", "", &n));
    PBPPO_TRY(f.Keys(n, "supervisor", {"command_limit", "overrun", "signal_limits", "recovery", "estop"}));
    PBPPO_TRY(Recovery(n));
    SupervisorSpec& s = m.supervisor;
    std::string limit;
    PBPPO_TRY(f.Text(n, "command_limit", "supervisor", &limit));
    if (limit != "count" && limit != "degraded")
      return f.Fail("supervisor.command_limit", "'" + limit + "' is not count or degraded");
    s.command_limit_degrades = limit == "degraded";
    std::string estop = "motors_off";
    PBPPO_TRY(f.OptionalText(n, "estop", "supervisor", &estop, Rule::kToken));
    if (estop != "motors_off" && estop != "damping")
      return f.Fail("supervisor.estop", "'" + estop + "' is not motors_off or damping");
    s.estop_damps = estop == "damping";
    YAML::Node o;
    PBPPO_TRY(f.Map(n, "overrun", "supervisor", &o));
    PBPPO_TRY(f.Keys(o, "supervisor.overrun", {"degraded", "safe_stop"}));
    PBPPO_TRY(f.Count(o, "degraded", "supervisor.overrun", 1, 1000000, &s.overrun_degraded));
    PBPPO_TRY(f.Count(o, "safe_stop", "supervisor.overrun", 1, 1000000, &s.overrun_safe_stop));
    if (s.overrun_safe_stop <= s.overrun_degraded)
      return f.Fail("supervisor.overrun.safe_stop", std::to_string(s.overrun_safe_stop) + " is not above degraded " +
                                                        std::to_string(s.overrun_degraded));
    return f.EachItem(n, "signal_limits", "supervisor", false,
                      [&](const YAML::Node& e, const std::string& w) -> Status {
                        PBPPO_TRY(f.Keys(e, w, {"signal", "range"}));
                        SignalLimitSpec l;
                        std::array<double, 2> r{};
                        PBPPO_TRY(f.Text(e, "signal", w, &l.signal, Rule::kToken));
                        PBPPO_TRY(f.Range(e, "range", w, -kInf, kInf, &r));
                        l.min = r[0];
                        l.max = r[1];
                        s.signal_limits.push_back(std::move(l));
                        return {};
                      });
  }
};

std::uint32_t Ticks(double seconds, double tick_s) {
  return static_cast<std::uint32_t>(std::min(4e9, std::round(seconds / tick_s)));
}

Status Derive(RobotModel& m, double tick_s) {
  auto fail = [&](const std::string& what) { return MakeError(ErrorCode::kInvalidValue, m.path + ": " + what); };
  if (!(tick_s > 0) || !std::isfinite(tick_s)) return fail("tick period " + YamlFields::Num(tick_s) + " s");
  m.tick_period_s = tick_s;
  const double ratio = m.policy_period_s / tick_s;
  if (std::abs(ratio - std::round(ratio)) > 1e-9 * ratio || ratio < 0.5)
    return fail("timing.policy_period_s " + YamlFields::Num(m.policy_period_s) + " is not a whole number of ticks of " +
                YamlFields::Num(tick_s) + " s");
  m.policy_period_ticks = static_cast<std::uint32_t>(std::llround(ratio));
  for (StreamSpec& s : m.streams) {
    // Ticks per sample period 1/k: "older than n periods" is n periods and a half, so that a
    // sample a tick or two late is not taken for a missed one (n at k = 1); lost after n whole ones.
    const double k = tick_s / s.period_s;
    auto missed = [&](double n) { return static_cast<std::uint32_t>(std::min(1e6, std::floor((n + 0.5) / k + 1e-9))); };
    auto periods = [&](double n) { return static_cast<std::uint32_t>(std::min(1e6, std::ceil(n / k - 1e-9))); };
    s.stale_degraded_ticks = missed(s.stale_after.degraded);
    s.stale_safe_stop_ticks = missed(s.stale_after.safe_stop);
    s.lost_ticks = periods(s.stale_after.lost);
    s.zero_after_ticks = s.zero_after > 0 ? std::max<std::uint32_t>(1, missed(s.zero_after)) : 0;
  }
  for (CommandSpec& c : m.commands) {
    c.rate = c.rate_per_s * tick_s;
    c.stop_rate = c.stop_ramp_per_s * tick_s;
  }
  safety::SupervisorModel& sm = m.supervisor_model;
  sm = safety::SupervisorModel{};
  for (const CommandSpec& c : m.commands)
    sm.commands.push_back({c.name, c.min, c.max, c.degraded_min, c.degraded_max, c.rate, c.stop, c.stop_rate,
                           c.stop_value, c.hold_input});
  for (const StreamSpec& s : m.streams)
    sm.streams.push_back({s.name, s.stale_degraded_ticks, s.stale_safe_stop_ticks, s.lost_ticks, s.invalid_safe_stop,
                          s.required, s.zero_after <= 0});
  for (const FieldSpec& f : m.fields) sm.input_names.push_back(f.name);
  for (TransportSpec& t : m.transports) {
    t.first_link = static_cast<std::uint32_t>(sm.transport_names.size());
    if (t.kind == "can" && m.can) {
      for (const CanBus& b : m.can->buses) sm.transport_names.push_back(t.name + "/" + b.name);
    } else {
      sm.transport_names.push_back(t.name);
    }
    t.link_count = static_cast<std::uint32_t>(sm.transport_names.size()) - t.first_link;
  }
  for (std::size_t k = 0; k < m.supervisor.signal_limits.size(); ++k) {
    const SignalLimitSpec& l = m.supervisor.signal_limits[k];
    sm.signal_limits.push_back({l.signal, static_cast<std::uint32_t>(k), l.stream, l.min, l.max});
  }
  sm.command_limit_degrades = m.supervisor.command_limit_degrades;
  sm.estop_damps = m.supervisor.estop_damps;
  sm.overrun_degraded = m.supervisor.overrun_degraded;
  sm.overrun_safe_stop = m.supervisor.overrun_safe_stop;
  if (auto st = safety::ValidateSupervisorModel(sm); !st) return fail(st.error().message);
  PhaseSpec& p = m.phases;
  p.arming_timeout_ticks = Ticks(p.arming_timeout_s, tick_s);
  p.stand_up_ticks = Ticks(p.stand_up_s, tick_s);
  p.hold_ticks = Ticks(p.hold_s, tick_s);
  p.damping_ticks = Ticks(p.damping_s, tick_s);
  p.motor_off_timeout_ticks = Ticks(p.motor_off_timeout_s, tick_s);
  p.sit_down_ticks = Ticks(p.sit_down_s, tick_s);
  if (p.sit_down_s > 0 && p.sit_down_ticks == 0)
    return fail("phases.sit_down_s: " + YamlFields::Num(p.sit_down_s) + " s is shorter than half a tick (" +
                YamlFields::Num(tick_s) + " s): a sit-down takes at least one");
  if (p.sit_down_s > 0) {
    if (m.motors.empty()) return fail("phases.sit_down_s: the robot has no motors to sit with");
    for (const MotorSpec& mo : m.motors)
      if (!mo.velocity_commanded() && !std::isfinite(mo.sit_q_rad))
        return fail("phases.sit_down_s: the robot's description gives no sit_pose (joint " + mo.joint +
                    ") to sit down to");
  }
  m.supervisor.recovery.healthy_ticks = std::max<std::uint32_t>(1, Ticks(m.supervisor.recovery.healthy_s, tick_s));
  m.op.switch_ticks = Ticks(m.op.switch_s, tick_s);
  m.op.deadman_sit_after_ticks =
      m.op.deadman_sit_after_s > 0 ? std::max<std::uint32_t>(1, Ticks(m.op.deadman_sit_after_s, tick_s)) : 0;
  return {};
}

}  // namespace

std::string ExpandIndex(const std::string& pattern, std::uint32_t i) {
  const auto at = pattern.find("{i}");
  if (at == std::string::npos) return pattern;
  return pattern.substr(0, at) + std::to_string(i) + pattern.substr(at + 3);
}

namespace {

// The index of the entry named `n` in `entries`; -1 when there is none.
template <typename Entry>
int IndexByName(const std::vector<Entry>& entries, std::string_view n) noexcept {
  for (std::size_t i = 0; i < entries.size(); ++i)
    if (entries[i].name == n) return static_cast<int>(i);
  return -1;
}

}  // namespace

int RobotModel::FieldIndex(std::string_view n) const noexcept {
  return IndexByName(fields, n);
}
int RobotModel::CommandIndex(std::string_view n) const noexcept {
  return IndexByName(commands, n);
}
int RobotModel::StreamIndex(std::string_view n) const noexcept {
  return IndexByName(streams, n);
}
int RobotModel::TransportIndex(std::string_view n) const noexcept {
  return IndexByName(transports, n);
}

Result<const RobotDocument*> RobotModel::Document(const std::string& role) const {
  const auto it = documents.find(role);
  if (it == documents.end()) return MakeError(ErrorCode::kMismatch, path + ": files: no file for '" + role + "'");
  return &it->second;
}

std::vector<std::string> RobotModel::DocumentGroup(const std::string& group) const {
  std::vector<std::string> names;
  for (const auto& [role, doc] : documents)
    if (role.rfind(group + ".", 0) == 0) names.push_back(role.substr(group.size() + 1));
  return names;
}

Result<double> RobotModel::Parameter(const std::string& n) const {
  const auto it = parameters.find(n);
  if (it == parameters.end()) return MakeError(ErrorCode::kMismatch, path + ": parameters: no '" + n + "'");
  return it->second;
}

Result<RobotModel> LoadRobotModel(const std::string& name_or_path) {
  auto found = FindRobot(name_or_path);
  if (!found) return std::move(found).error();
  const std::string& robot_yaml = *found;
  RobotModel m;
  m.path = robot_yaml;
  m.dir = std::filesystem::path(robot_yaml).parent_path().string();
  Files files(m.dir);
  auto text = files.Read(robot_yaml);
  if (!text) return std::move(text).error();
  auto doc = ParseYaml(*text, robot_yaml);
  if (!doc) return std::move(doc).error();
  const YAML::Node root = *doc;
  const YamlFields f(robot_yaml);
  PBPPO_TRY(f.Keys(root, "",
                   {"robot", "description", "files", "timing", "parameters", "transports", "streams", "motors", "imus",
                    "phases", "signals", "commands", "supervisor", "service", "operator"}));
  PBPPO_TRY(f.Text(root, "robot", "", &m.name, Rule::kToken));
  PBPPO_TRY(f.OptionalText(root, "description", "", &m.description));
  Loader l{{m, f}, files};
  PBPPO_TRY(l.Timing(root));
  if (root["parameters"]) {
    YAML::Node n;
    PBPPO_TRY(f.Map(root, "parameters", "", &n));
    for (const auto& kv : n) {
      const std::string k = kv.first.as<std::string>();
      PBPPO_TRY(f.Number(n, k.c_str(), "parameters", -kInf, kInf, &m.parameters[k]));
    }
  }
  PBPPO_TRY(l.FilesSection(root));
  if (m.io && m.io->robot != m.name)
    return f.Fail("files.io_layout", "the layout is for robot '" + m.io->robot + "', not '" + m.name + "'");
  if (m.can && m.can->robot != m.name)
    return f.Fail("files.can_map", "the CAN map is for robot '" + m.can->robot + "', not '" + m.name + "'");
  PBPPO_TRY(l.Transports(root));
  PBPPO_TRY(l.DeclaredStreams(root));
  PBPPO_TRY(l.Devices(root));
  PBPPO_TRY(l.DeclaredCommands(root));
  PBPPO_TRY(l.Signals(root));
  PBPPO_TRY(l.DdsMessages(root, [&files](const std::string& path) { return files.Read(path); }, m.dir));
  PBPPO_TRY(l.EvdevMappings(root));
  PBPPO_TRY(l.Lockstep(root));
  PBPPO_TRY(l.Phases(root));
  PBPPO_TRY(l.Operator(root));
  PBPPO_TRY(l.Supervisor(root));
  if (root["service"]) {
    YAML::Node n;
    PBPPO_TRY(f.Map(root, "service", "", &n));
    PBPPO_TRY(f.Keys(n, "service", {"rearm_after_failure"}));
    PBPPO_TRY(f.Bool(n, "rearm_after_failure", "service", &m.service.rearm_after_failure));
  }
  for (SignalLimitSpec& limit : m.supervisor.signal_limits) {
    int field = m.FieldIndex(limit.signal);
    for (const SignalSpec& s : m.signals)
      if (s.name == limit.signal) field = static_cast<int>(s.fields[0]);
    if (field < 0) return f.Fail("supervisor.signal_limits", "'" + limit.signal + "' is not a signal of the robot");
    limit.stream = m.fields[static_cast<std::size_t>(field)].stream;
  }
  if (const YAML::Node t = root["timing"]["policy_trigger"]) {
    std::string s;
    PBPPO_TRY(f.Text(root["timing"], "policy_trigger", "timing", &s, Rule::kToken));
    m.policy_trigger = m.StreamIndex(s);
    if (m.policy_trigger < 0) return f.Fail("timing.policy_trigger", "'" + s + "' is not a stream of the robot");
  }
  if (m.streams.empty()) return f.Fail("streams", "the robot has no input (declare a stream, or a can_map)");
  m.hash = files.hash();
  PBPPO_TRY(Derive(m, m.tick_period_s));
  return m;
}

Result<RobotModel> WithTickPeriod(const RobotModel& model, double tick_period_s) {
  RobotModel m = model;
  PBPPO_TRY(Derive(m, tick_period_s));
  return m;
}

}  // namespace pbppo::robot
