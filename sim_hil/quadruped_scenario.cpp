#include "sim_hil/quadruped_scenario.hpp"

#include <algorithm>
#include <cmath>

#include "runtime/robot/text_file.hpp"
#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::sim {

using robot::YamlFields;

Result<QuadrupedScenario> ParseQuadrupedScenario(const std::string& text, const std::string& origin,
                                                 const robot::RobotModel& model, double tick_s) {
  auto parsed = robot::ParseYaml(text, origin);
  if (!parsed) return std::move(parsed).error();
  const YAML::Node& root = *parsed;
  const YamlFields y(origin);
  if (!root.IsMap()) return y.Fail("", "a scenario is a mapping");
  PBPPO_TRY(y.Keys(root, "", {"mount", "terrain", "contact", "start", "events"}));
  QuadrupedScenario sc;
  sc.path = origin;
  QuadrupedHilOptions& o = sc.hil;
  std::string mount = "ground";
  PBPPO_TRY(y.OptionalText(root, "mount", "", &mount));
  if (mount != "ground" && mount != "stand") return y.Fail("mount", "'" + mount + "' is neither ground nor stand");
  o.plant.mount = mount == "ground" ? Mount::kGround : Mount::kStand;
  if (root["terrain"]) {
    YAML::Node t;
    PBPPO_TRY(y.Map(root, "terrain", "", &t));
    PBPPO_TRY(y.Keys(t, "terrain", {"kind", "seed", "blocks", "half_size_m", "size_m", "height_m", "clear_radius_m"}));
    std::string kind;
    PBPPO_TRY(y.Text(t, "kind", "terrain", &kind));
    if (kind != "flat" && kind != "blocks") return y.Fail("terrain.kind", "'" + kind + "' is neither flat nor blocks");
    if (kind == "blocks") {
      if (o.plant.mount != Mount::kGround) return y.Fail("terrain", "blocks need mount: ground");
      BlockField f;
      long seed = 1, blocks = f.blocks;
      std::array<double, 2> size{f.size_m[0], f.size_m[1]}, height{f.height_m[0], f.height_m[1]};
      PBPPO_TRY(y.Integer(t, "seed", "terrain", 0, 1L << 40, &seed));
      if (t["blocks"]) PBPPO_TRY(y.Integer(t, "blocks", "terrain", 0, 100000, &blocks));
      PBPPO_TRY(y.OptionalNumber(t, "half_size_m", "terrain", 0.1, 1000, &f.half_size_m));
      if (t["size_m"]) PBPPO_TRY(y.Range(t, "size_m", "terrain", 0.01, 100, &size));
      if (t["height_m"]) PBPPO_TRY(y.Range(t, "height_m", "terrain", 0.001, 10, &height));
      PBPPO_TRY(y.OptionalNumber(t, "clear_radius_m", "terrain", 0, 1000, &f.clear_radius_m));
      f.blocks = static_cast<int>(blocks);
      f.size_m[0] = size[0];
      f.size_m[1] = size[1];
      f.height_m[0] = height[0];
      f.height_m[1] = height[1];
      Rng rng(static_cast<std::uint64_t>(seed));
      GenerateBlocks(f, rng, o.plant.terrain);
    }
  }
  if (root["contact"]) {
    YAML::Node c;
    PBPPO_TRY(y.Map(root, "contact", "", &c));
    PBPPO_TRY(y.Keys(c, "contact", {"friction", "stiffness", "dissipation", "transition_mps"}));
    ContactParams& p = o.plant.contact;
    PBPPO_TRY(y.OptionalNumber(c, "friction", "contact", 0, 10, &p.friction));
    PBPPO_TRY(y.OptionalNumber(c, "stiffness", "contact", 1e3, 1e9, &p.stiffness));
    PBPPO_TRY(y.OptionalNumber(c, "dissipation", "contact", 0, 100, &p.dissipation));
    PBPPO_TRY(y.OptionalNumber(c, "transition_mps", "contact", 1e-4, 10, &p.transition_mps));
  }
  if (root["start"]) {
    YAML::Node s;
    PBPPO_TRY(y.Map(root, "start", "", &s));
    PBPPO_TRY(y.Keys(s, "start", {"x_m", "y_m", "height_m", "yaw_rad"}));
    PBPPO_TRY(y.OptionalNumber(s, "x_m", "start", -1e4, 1e4, &o.base_xyz[0]));
    PBPPO_TRY(y.OptionalNumber(s, "y_m", "start", -1e4, 1e4, &o.base_xyz[1]));
    PBPPO_TRY(y.OptionalNumber(s, "height_m", "start", 0.05, 10, &o.base_xyz[2]));
    PBPPO_TRY(y.OptionalNumber(s, "yaw_rad", "start", -M_PI, M_PI, &o.base_yaw_rad));
  }
  o.base_xyz[2] += TerrainHeight(o.plant.terrain, o.base_xyz[0], o.base_xyz[1]);
  YAML::Node events;
  PBPPO_TRY(y.List(root, "events", "", false, &events));
  const robot::CanMap& map = *model.can;
  for (std::size_t i = 0; i < events.size(); ++i) {
    const YAML::Node& e = events[i];
    const std::string where = "events[" + std::to_string(i) + "]";
    if (!e.IsMap()) return y.Fail(where, "an event is a mapping");
    PBPPO_TRY(y.Keys(e, where,
                     {"at_s", "push", "silent_motor", "imu_silent", "drop_frames", "max_burst", "bus_off",
                      "bus_restored", "motor_back", "bad_replies", "good_replies"}));
    double at_s = 0;
    PBPPO_TRY(y.Number(e, "at_s", where, 0, 1e6, &at_s));
    HilFault f;
    f.tick = static_cast<std::uint64_t>(std::llround(at_s / tick_s));
    const int kinds = (e["push"] ? 1 : 0) + (e["silent_motor"] ? 1 : 0) + (e["imu_silent"] ? 1 : 0) +
                      (e["drop_frames"] ? 1 : 0) + (e["bus_off"] ? 1 : 0) + (e["bus_restored"] ? 1 : 0) +
                      (e["motor_back"] ? 1 : 0) + (e["bad_replies"] ? 1 : 0) + (e["good_replies"] ? 1 : 0);
    if (kinds != 1)
      return y.Fail(where,
                    "needs exactly one of push, silent_motor, motor_back, bad_replies, good_replies, imu_silent, "
                    "drop_frames, bus_off, bus_restored");
    const char* motor_key = e["silent_motor"]   ? "silent_motor"
                            : e["motor_back"]   ? "motor_back"
                            : e["bad_replies"]  ? "bad_replies"
                            : e["good_replies"] ? "good_replies"
                                                : nullptr;
    if (e["push"]) {
      if (o.plant.mount != Mount::kGround) return y.Fail(YamlFields::Join(where, "push"), "a push needs mount: ground");
      std::array<double, 3> v{};
      PBPPO_TRY(y.Array<3>(e, "push", where, -10, 10, &v));
      f.kind = HilFaultKind::kPush;
      std::copy(v.begin(), v.end(), f.velocity_mps);
    } else if (motor_key != nullptr) {
      std::string joint;
      PBPPO_TRY(y.Text(e, motor_key, where, &joint));
      const std::string key = motor_key;
      f.kind = key == "silent_motor"  ? HilFaultKind::kSilentMotor
               : key == "motor_back"  ? HilFaultKind::kMotorBack
               : key == "bad_replies" ? HilFaultKind::kBadReplies
                                      : HilFaultKind::kGoodReplies;
      for (std::size_t m = 0; m < map.motors.size(); ++m)
        if (map.motors[m].joint == joint) f.motor = static_cast<int>(m);
      if (f.motor < 0)
        return y.Fail(YamlFields::Join(where, motor_key), "'" + joint + "' is not a motor of the CAN map");
    } else if (e["imu_silent"]) {
      bool on = false;
      PBPPO_TRY(y.Bool(e, "imu_silent", where, &on));
      f.kind = on ? HilFaultKind::kImuSilent : HilFaultKind::kImuBack;  // false: the IMU comes back
    } else if (e["drop_frames"]) {
      f.kind = HilFaultKind::kDropFrames;
      PBPPO_TRY(y.Number(e, "drop_frames", where, 0, 1, &f.probability));
      std::uint32_t burst = 0;
      if (e["max_burst"]) PBPPO_TRY(y.Count(e, "max_burst", where, 0, 1000000, &burst));
      f.max_burst = burst;
    } else {
      const char* key = e["bus_off"] ? "bus_off" : "bus_restored";
      std::string bus;
      PBPPO_TRY(y.Text(e, key, where, &bus));
      f.kind = e["bus_off"] ? HilFaultKind::kBusOff : HilFaultKind::kBusRestored;
      for (std::size_t b = 0; b < map.buses.size(); ++b)
        if (map.buses[b].name == bus) f.bus = static_cast<int>(b);
      if (f.bus < 0) return y.Fail(YamlFields::Join(where, key), "'" + bus + "' is not a bus of the CAN map");
    }
    if (f.kind != HilFaultKind::kDropFrames && e["max_burst"])
      return y.Fail(YamlFields::Join(where, "max_burst"), "belongs to drop_frames");
    // Kept sorted by tick; events at the same tick in file order.
    const auto at = std::upper_bound(o.faults.begin(), o.faults.end(), f.tick,
                                     [](std::uint64_t t, const HilFault& g) { return t < g.tick; });
    o.faults.insert(at, f);
  }
  return sc;
}

Result<QuadrupedScenario> LoadQuadrupedScenario(const std::string& path, const robot::RobotModel& model,
                                                double tick_s) {
  auto text = robot::ReadTextFile(path);
  if (!text) return std::move(text).error();
  return ParseQuadrupedScenario(*text, path, model, tick_s);
}

}  // namespace pbppo::sim
