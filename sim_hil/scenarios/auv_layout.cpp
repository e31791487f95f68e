#include "sim_hil/scenarios/auv_layout.hpp"

#include <cmath>

#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::sim {
namespace {

using robot::LoadYamlFile;
using robot::YamlFields;

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
constexpr double kBig = 1e6;

Result<AuvLayout> ParseLayout(const YAML::Node& root, const std::string& origin) {
  YamlFields f(origin);
  if (auto st = f.Keys(root, "", {"name", "description", "arena", "start", "targets", "obstacles", "random_obstacles"});
      !st)
    return st.error();
  AuvLayout l;
  if (auto st = f.Text(root, "name", "", &l.name); !st) return st.error();

  YAML::Node n;
  if (auto st = f.Map(root, "arena", "", &n); !st) return st.error();
  if (auto st = f.Keys(n, "arena", {"x_min_m", "x_max_m", "y_min_m", "y_max_m"}); !st) return st.error();
  Arena& a = l.world.arena;
  if (auto st = f.Number(n, "x_min_m", "arena", -kBig, kBig, &a.x_min_m); !st) return st.error();
  if (auto st = f.Number(n, "x_max_m", "arena", a.x_min_m + 1.0, kBig, &a.x_max_m); !st) return st.error();
  if (auto st = f.Number(n, "y_min_m", "arena", -kBig, kBig, &a.y_min_m); !st) return st.error();
  if (auto st = f.Number(n, "y_max_m", "arena", a.y_min_m + 1.0, kBig, &a.y_max_m); !st) return st.error();

  if (auto st = f.Map(root, "start", "", &n); !st) return st.error();
  if (auto st = f.Keys(n, "start", {"x_m", "y_m", "yaw_deg"}); !st) return st.error();
  if (auto st = f.Range(n, "x_m", "start", a.x_min_m, a.x_max_m, &l.start.x_m); !st) return st.error();
  if (auto st = f.Range(n, "y_m", "start", a.y_min_m, a.y_max_m, &l.start.y_m); !st) return st.error();
  std::array<double, 2> yaw_deg{};
  if (auto st = f.Range(n, "yaw_deg", "start", -360.0, 360.0, &yaw_deg); !st) return st.error();
  l.start.yaw_rad = {yaw_deg[0] * kDegToRad, yaw_deg[1] * kDegToRad};

  const YAML::Node obstacles = root["obstacles"];
  if (obstacles && !obstacles.IsSequence()) return f.Fail("obstacles", "expected a list");
  for (std::size_t i = 0; obstacles && i < obstacles.size(); ++i) {
    const YAML::Node o = obstacles[i];
    const std::string w = "obstacles[" + std::to_string(i) + "]";
    if (!o.IsMap()) return f.Fail(w, "expected a mapping");
    std::string type;
    if (auto st = f.Text(o, "type", w, &type); !st) return st.error();
    if (type == "circle") {
      if (auto st = f.Keys(o, w, {"type", "x_m", "y_m", "radius_m"}); !st) return st.error();
      Circle c;
      if (auto st = f.Number(o, "x_m", w, a.x_min_m, a.x_max_m, &c.x_m); !st) return st.error();
      if (auto st = f.Number(o, "y_m", w, a.y_min_m, a.y_max_m, &c.y_m); !st) return st.error();
      if (auto st = f.Number(o, "radius_m", w, 0.01, kBig, &c.radius_m); !st) return st.error();
      l.world.circles.push_back(c);
    } else if (type == "box") {
      if (auto st = f.Keys(o, w, {"type", "x_min_m", "x_max_m", "y_min_m", "y_max_m"}); !st) return st.error();
      Box b;
      if (auto st = f.Number(o, "x_min_m", w, a.x_min_m, a.x_max_m, &b.x_min_m); !st) return st.error();
      if (auto st = f.Number(o, "x_max_m", w, b.x_min_m + 0.01, a.x_max_m, &b.x_max_m); !st) return st.error();
      if (auto st = f.Number(o, "y_min_m", w, a.y_min_m, a.y_max_m, &b.y_min_m); !st) return st.error();
      if (auto st = f.Number(o, "y_max_m", w, b.y_min_m + 0.01, a.y_max_m, &b.y_max_m); !st) return st.error();
      l.world.boxes.push_back(b);
    } else {
      return f.Fail(w + ".type", "'" + type + "' is not one of circle, box");
    }
  }

  const YAML::Node targets = root["targets"];
  if (!targets) return f.Fail("top level", "missing field 'targets'");
  if (!targets.IsSequence() || targets.size() == 0) return f.Fail("targets", "expected a non-empty list of [x, y]");
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const std::string w = "targets[" + std::to_string(i) + "]";
    YAML::Node holder;
    holder["xy"] = targets[i];
    std::array<double, 2> t{};
    if (auto st = f.Array<2>(holder, "xy", "", -kBig, kBig, &t); !st)
      return f.Fail(w, "expected [x_m, y_m] numbers, got " + YamlFields::Quote(targets[i]));
    if (Clearance(l.world, t[0], t[1]) <= 0.0)
      return f.Fail(w, "(" + YamlFields::Num(t[0]) + ", " + YamlFields::Num(t[1]) +
                           ") lies inside an obstacle or outside the arena");
    l.targets.push_back(t);
  }

  const double cx = 0.5 * (l.start.x_m[0] + l.start.x_m[1]), cy = 0.5 * (l.start.y_m[0] + l.start.y_m[1]);
  if (Clearance(l.world, cx, cy) <= 0.0)
    return f.Fail("start", "the centre of the start region (" + YamlFields::Num(cx) + ", " + YamlFields::Num(cy) +
                               ") lies inside an obstacle");

  if (const YAML::Node r = root["random_obstacles"]) {
    const std::string w = "random_obstacles";
    if (auto st = f.Keys(r, w, {"count", "radius_m", "clearance_m"}); !st) return st.error();
    std::array<double, 2> count{};
    if (auto st = f.Range(r, "count", w, 0.0, 64.0, &count); !st) return st.error();
    if (count[0] != std::floor(count[0]) || count[1] != std::floor(count[1]))
      return f.Fail(w + ".count", "expected whole numbers, got [" + YamlFields::Num(count[0]) + ", " +
                                      YamlFields::Num(count[1]) + "]");
    l.random_obstacles.count = {static_cast<int>(count[0]), static_cast<int>(count[1])};
    if (auto st = f.Range(r, "radius_m", w, 0.01, 20.0, &l.random_obstacles.radius_m); !st) return st.error();
    if (auto st = f.Number(r, "clearance_m", w, 0.0, 40.0, &l.random_obstacles.clearance_m); !st) return st.error();
  }
  return l;
}

}  // namespace

Result<AuvLayout> ParseAuvLayout(const std::string& yaml_text, const std::string& origin) {
  auto root = robot::ParseYaml(yaml_text, origin);
  if (!root) return std::move(root).error();
  return ParseLayout(*root, origin);
}

Result<AuvLayout> ParseAuvLayout(const YAML::Node& root, const std::string& origin) {
  return ParseLayout(root, origin);
}

Result<AuvLayout> LoadAuvLayout(const std::string& path) {
  auto doc = LoadYamlFile(path);
  if (!doc) return std::move(doc).error();
  return ParseLayout(*doc, path);
}

}  // namespace pbppo::sim
