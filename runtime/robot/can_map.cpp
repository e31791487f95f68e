#include "runtime/robot/can_map.hpp"

#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "runtime/robot/text_file.hpp"
#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::robot {
namespace {

using Rule = YamlFields::TextRule;

Status ParseRange(const YamlFields& p, const YAML::Node& n, const std::string& where, MitRange* r) {
  struct Pair {
    const char* lo;
    const char* hi;
    double* lo_v;
    double* hi_v;
  };
  const Pair pairs[] = {{"p_min", "p_max", &r->p_min, &r->p_max},
                        {"v_min", "v_max", &r->v_min, &r->v_max},
                        {"kp_min", "kp_max", &r->kp_min, &r->kp_max},
                        {"kd_min", "kd_max", &r->kd_min, &r->kd_max},
                        {"t_min", "t_max", &r->t_min, &r->t_max}};
  for (const Pair& pr : pairs) {
    PBPPO_TRY(p.Number(n, pr.lo, where, -HUGE_VAL, HUGE_VAL, pr.lo_v));
    PBPPO_TRY(p.Number(n, pr.hi, where, -HUGE_VAL, HUGE_VAL, pr.hi_v));
    if (!(*pr.lo_v < *pr.hi_v)) {
      char b[160];
      std::snprintf(b, sizeof b, "%s %.9g is not below %s %.9g", pr.lo, *pr.lo_v, pr.hi, *pr.hi_v);
      return p.Fail(where + "." + pr.lo, b);
    }
  }
  if (r->kp_min < 0) return p.Fail(where + ".kp_min", "is negative");
  if (r->kd_min < 0) return p.Fail(where + ".kd_min", "is negative");
  return {};
}

}  // namespace

const char* ToString(ImuFormat format) noexcept {
  switch (format) {
    case ImuFormat::kClassic: return "classic";
    case ImuFormat::kFd: return "fd";
  }
  return "?";
}

namespace {

// ParseCanMap's sections in order, with what they share: the buses and actuators by name, and the
// identifiers in use on each bus (who uses them, for duplicate errors).
struct MapParser {
  const YamlFields& p;
  CanMap m;
  std::map<std::string, std::uint32_t> bus_index, actuator_index;
  std::vector<std::map<std::uint32_t, std::string>> used;

  Status Buses(const YAML::Node& buses) {
    if (buses.size() == 0) return p.Fail("buses", "is empty");
    for (std::size_t i = 0; i < buses.size(); ++i) {
      const std::string where = "buses[" + std::to_string(i) + "]";
      PBPPO_TRY(p.Keys(buses[i], where, {"name", "interface", "fd"}));
      CanBus b;
      PBPPO_TRY(p.Text(buses[i], "name", where, &b.name, Rule::kToken));
      PBPPO_TRY(p.Text(buses[i], "interface", where, &b.interface, Rule::kToken));
      PBPPO_TRY(p.Bool(buses[i], "fd", where, &b.fd));
      if (b.interface.size() > 15)
        return p.Fail(where + ".interface", "'" + b.interface + "' is longer than 15 characters");
      if (bus_index.count(b.name)) return p.Fail(where + ".name", "duplicate bus '" + b.name + "'");
      for (const CanBus& o : m.buses) {
        if (o.interface == b.interface)
          return p.Fail(where + ".interface", "'" + b.interface + "' is already used by bus '" + o.name + "'");
      }
      bus_index[b.name] = static_cast<std::uint32_t>(m.buses.size());
      m.buses.push_back(b);
    }
    used.resize(m.buses.size());
    return {};
  }

  Status Actuators(const YAML::Node& actuators) {
    for (std::size_t i = 0; i < actuators.size(); ++i) {
      const std::string where = "actuators[" + std::to_string(i) + "]";
      PBPPO_TRY(p.Keys(
          actuators[i], where,
          {"name", "p_min", "p_max", "v_min", "v_max", "kp_min", "kp_max", "kd_min", "kd_max", "t_min", "t_max"}));
      CanActuator a;
      PBPPO_TRY(p.Text(actuators[i], "name", where, &a.name, Rule::kToken));
      const std::string named = where + " '" + a.name + "'";
      PBPPO_TRY(ParseRange(p, actuators[i], named, &a.range));
      if (actuator_index.count(a.name)) return p.Fail(where + ".name", "duplicate actuator '" + a.name + "'");
      actuator_index[a.name] = static_cast<std::uint32_t>(m.actuators.size());
      m.actuators.push_back(a);
    }
    return {};
  }

  Status Claim(std::uint32_t bus, std::uint32_t id, const std::string& who, const std::string& field) {
    auto [it, fresh] = used[bus].emplace(id, who);
    if (!fresh)
      return p.Fail(field, "identifier " + YamlFields::Hex(id) + " on bus '" + m.buses[bus].name +
                               "' is already used by " + it->second);
    return {};
  }

  // An entry's name (`key`, unique among its kind: `seen`) and its bus; `named` ("where 'name'")
  // prefixes the entry's later errors.
  Status NameAndBus(const YAML::Node& n, const char* key, const std::string& where, const char* kind,
                    std::set<std::string>* seen, std::string* name, std::string* named, std::uint32_t* bus) {
    PBPPO_TRY(p.Text(n, key, where, name, Rule::kToken));
    *named = where + " '" + *name + "'";
    if (!seen->insert(*name).second)
      return p.Fail(*named + "." + key, std::string("duplicate ") + kind + " '" + *name + "'");
    std::string bus_name;
    PBPPO_TRY(p.Text(n, "bus", *named, &bus_name, Rule::kToken));
    const auto it = bus_index.find(bus_name);
    if (it == bus_index.end()) return p.Fail(*named + ".bus", "unknown bus '" + bus_name + "'");
    *bus = it->second;
    return {};
  }

  Status Motors(const YAML::Node& motors) {
    std::set<std::string> joints;
    for (std::size_t i = 0; i < motors.size(); ++i) {
      const std::string where = "motors[" + std::to_string(i) + "]";
      PBPPO_TRY(p.Keys(motors[i], where, {"joint", "bus", "id", "reply_id", "actuator"}));
      CanMotor mo;
      std::string named;
      PBPPO_TRY(NameAndBus(motors[i], "joint", where, "joint", &joints, &mo.joint, &named, &mo.bus));
      // The reply carries the motor id in one byte, and 0 is the broadcast/master id of most drivers.
      PBPPO_TRY(p.Id(motors[i], "id", named, 1, 0xFF, &mo.id));
      PBPPO_TRY(p.Id(motors[i], "reply_id", named, 0, kCanMaxStandardId, &mo.reply_id));
      std::string act;
      PBPPO_TRY(p.Text(motors[i], "actuator", named, &act, Rule::kToken));
      auto ai = actuator_index.find(act);
      if (ai == actuator_index.end()) return p.Fail(named + ".actuator", "unknown actuator '" + act + "'");
      mo.actuator = ai->second;
      PBPPO_TRY(Claim(mo.bus, mo.id, "motor '" + mo.joint + "' (id)", named + ".id"));
      PBPPO_TRY(Claim(mo.bus, mo.reply_id, "motor '" + mo.joint + "' (reply_id)", named + ".reply_id"));
      m.motors.push_back(mo);
    }
    if (m.motors.empty()) return p.Fail("motors", "is empty");
    return {};
  }

  Status Imus(const YAML::Node& imus) {
    std::set<std::string> imu_names;
    for (std::size_t i = 0; i < imus.size(); ++i) {
      const std::string where = "imus[" + std::to_string(i) + "]";
      PBPPO_TRY(p.Keys(imus[i], where, {"name", "bus", "format", "id"}));
      CanImu u;
      std::string named;
      PBPPO_TRY(NameAndBus(imus[i], "name", where, "IMU", &imu_names, &u.name, &named, &u.bus));
      std::string fmt;
      PBPPO_TRY(p.Text(imus[i], "format", named, &fmt, Rule::kToken));
      if (fmt == "classic") {
        u.format = ImuFormat::kClassic;
      } else if (fmt == "fd") {
        u.format = ImuFormat::kFd;
        if (!m.buses[u.bus].fd)
          return p.Fail(named + ".format", "'fd' on bus '" + m.buses[u.bus].name + "', which is not an fd bus");
      } else {
        return p.Fail(named + ".format", "'" + fmt + "' is not classic or fd");
      }
      const std::uint32_t frames = u.format == ImuFormat::kClassic ? 3 : 1;
      PBPPO_TRY(p.Id(imus[i], "id", named, 0, kCanMaxStandardId + 1 - frames, &u.id));
      for (std::uint32_t k = 0; k < frames; ++k)
        PBPPO_TRY(Claim(u.bus, u.id + k, "IMU '" + u.name + "' (frame " + std::to_string(k) + ")", named + ".id"));
      m.imus.push_back(u);
    }
    return {};
  }
};

}  // namespace

Result<CanMap> ParseCanMap(const std::string& yaml_text, const std::string& origin) {
  auto doc = ParseYaml(yaml_text, origin);
  if (!doc) return std::move(doc).error();
  const YAML::Node root = *doc;
  const YamlFields p(origin);
  if (!root.IsMap()) return p.Fail("", "expected a mapping with robot, buses, actuators, motors, imus");
  PBPPO_TRY(p.Keys(root, "", {"robot", "buses", "actuators", "motors", "imus"}));
  MapParser mp{p, {}, {}, {}, {}};
  PBPPO_TRY(p.Text(root, "robot", "", &mp.m.robot, Rule::kToken));
  YAML::Node buses, actuators, motors, imus;
  PBPPO_TRY(p.List(root, "buses", "", true, &buses));
  PBPPO_TRY(p.List(root, "actuators", "", true, &actuators));
  PBPPO_TRY(p.List(root, "motors", "", true, &motors));
  PBPPO_TRY(p.List(root, "imus", "", false, &imus));
  PBPPO_TRY(mp.Buses(buses));
  PBPPO_TRY(mp.Actuators(actuators));
  PBPPO_TRY(mp.Motors(motors));
  PBPPO_TRY(mp.Imus(imus));
  return std::move(mp.m);
}

Result<CanMap> LoadCanMap(const std::string& path) {
  auto text = ReadTextFile(path);
  if (!text) return std::move(text).error();
  return ParseCanMap(*text, path);
}

}  // namespace pbppo::robot
