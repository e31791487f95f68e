#include "policies/envs/quadruped_walk_config.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <span>
#include <string_view>
#include <utility>

#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::envs {

namespace {

constexpr double kBig = 1e6;                                  // the largest reward scale or value walk.yaml takes
constexpr double kSigmaMin = 1e-6, kSigmaMax = 100;           // rewards.tracking_sigma, walk.yaml's and the flag's
constexpr double kResampleMinS = 0.02, kResampleMaxS = 3600;  // commands.resample_s, walk.yaml's and the flag's

// walk.yaml's rewards.scales, by name.
constexpr std::pair<const char*, double WalkRewardScales::*> kRewardScales[] = {
    {"tracking_lin_vel", &WalkRewardScales::tracking_lin_vel},
    {"tracking_ang_vel", &WalkRewardScales::tracking_ang_vel},
    {"lin_vel_z", &WalkRewardScales::lin_vel_z},
    {"ang_vel_xy", &WalkRewardScales::ang_vel_xy},
    {"orientation", &WalkRewardScales::orientation},
    {"torques", &WalkRewardScales::torques},
    {"dof_acc", &WalkRewardScales::dof_acc},
    {"action_rate", &WalkRewardScales::action_rate},
    {"collision", &WalkRewardScales::collision},
    {"feet_air_time", &WalkRewardScales::feet_air_time},
    {"dof_pos_limits", &WalkRewardScales::dof_pos_limits},
    {"base_height", &WalkRewardScales::base_height},
    {"termination", &WalkRewardScales::termination},
};

}  // namespace

int QuadrupedWalkParams::episode_steps() const noexcept {
  return static_cast<int>(std::lround(episode_s / policy_dt_s()));
}

Result<QuadrupedWalkParams> ParseQuadrupedWalkParams(const YAML::Node& node, const std::string& path) {
  const YAML::Node* root = &node;
  const robot::YamlFields f(path);
  QuadrupedWalkParams p;
  if (auto st =
          f.Keys(*root, "", {"simulation", "commands", "rewards", "termination", "noise", "randomization", "terrain"});
      !st)
    return st.error();
  YAML::Node sim, cmd, rew, sc, term, noise, rnd, ter;
  for (auto [key, n] : {std::pair{"simulation", &sim}, std::pair{"commands", &cmd}, std::pair{"rewards", &rew},
                        std::pair{"termination", &term}, std::pair{"noise", &noise}, std::pair{"randomization", &rnd},
                        std::pair{"terrain", &ter}})
    if (auto st = f.Map(*root, key, "", n); !st) return st.error();
  if (auto st = f.Map(rew, "scales", "rewards", &sc); !st) return st.error();
  long decimation = 0, blocks = 0, pool = 0;
  double only_positive = 1, base_contact = 1;
  auto flag = [&](const YAML::Node& n, const char* key, const std::string& where, double* out) -> Status {
    const YAML::Node v = n[key];
    if (!v) return f.Fail(where, std::string("missing field '") + key + "'");
    const std::string s = v.IsScalar() ? v.as<std::string>() : "";
    if (s != "true" && s != "false") return f.Fail(where + "." + key, "'" + s + "' is not true or false");
    *out = s == "true" ? 1 : 0;
    return {};
  };
  WalkRewardScales& s = p.scales;
  for (const Status& st : {
           f.Keys(sim, "simulation",
                  {"timestep_s", "decimation", "episode_s", "init_base_height_m", "init_joint_scale",
                   "init_base_velocity"}),
           f.Number(sim, "timestep_s", "simulation", 1e-4, 0.02, &p.timestep_s),
           f.Integer(sim, "decimation", "simulation", 1, 100, &decimation),
           f.Number(sim, "episode_s", "simulation", 0.1, 3600, &p.episode_s),
           f.Number(sim, "init_base_height_m", "simulation", 0.05, 5, &p.init_base_height_m),
           f.Range(sim, "init_joint_scale", "simulation", 0, 3, &p.init_joint_scale),
           f.Number(sim, "init_base_velocity", "simulation", 0, 10, &p.init_base_velocity),
           f.Keys(cmd, "commands",
                  {"resample_s", "vx_mps", "vy_mps", "yaw_rate_radps", "heading_rad", "heading_share", "heading_gain",
                   "zero_planar_share", "single_axis_share", "zero_below_mps"}),
           f.Number(cmd, "resample_s", "commands", kResampleMinS, kResampleMaxS, &p.resample_s),
           f.Range(cmd, "vx_mps", "commands", -10, 10, &p.vx_mps),
           f.Range(cmd, "vy_mps", "commands", -10, 10, &p.vy_mps),
           f.Range(cmd, "yaw_rate_radps", "commands", -10, 10, &p.yaw_rate_radps),
           f.Range(cmd, "heading_rad", "commands", -3.1416, 3.1416, &p.heading_rad),
           f.Number(cmd, "heading_share", "commands", 0, 1, &p.heading_share),
           f.Number(cmd, "heading_gain", "commands", 0, 100, &p.heading_gain),
           f.Number(cmd, "zero_planar_share", "commands", 0, 1, &p.zero_planar_share),
           f.Number(cmd, "single_axis_share", "commands", 0, 1, &p.single_axis_share),
           f.Number(cmd, "zero_below_mps", "commands", 0, 10, &p.zero_below_mps),
           f.Keys(rew, "rewards",
                  {"tracking_sigma", "only_positive", "feet_air_time_target_s", "soft_dof_pos_limit", "contact_force_n",
                   "base_height_target_m", "scales"}),
           f.Number(rew, "tracking_sigma", "rewards", kSigmaMin, kSigmaMax, &p.tracking_sigma),
           flag(rew, "only_positive", "rewards", &only_positive),
           f.Number(rew, "feet_air_time_target_s", "rewards", 0, 10, &p.feet_air_time_target_s),
           f.Number(rew, "soft_dof_pos_limit", "rewards", 0.1, 1, &p.soft_dof_pos_limit),
           f.Number(rew, "contact_force_n", "rewards", 0, 1000, &p.contact_force_n),
           f.OptionalNumber(rew, "base_height_target_m", "rewards", 0, 10, &p.base_height_target_m),
           f.Keys(
               sc, "rewards.scales",
               {"tracking_lin_vel", "tracking_ang_vel", "lin_vel_z", "ang_vel_xy", "orientation", "torques", "dof_acc",
                "action_rate", "collision", "feet_air_time", "dof_pos_limits", "base_height", "termination"}),
           f.Keys(term, "termination", {"base_contact", "max_tilt_rad"}),
           flag(term, "base_contact", "termination", &base_contact),
           f.Number(term, "max_tilt_rad", "termination", 0.05, 3.2, &p.max_tilt_rad),
           f.Keys(noise, "noise", {"level", "ang_vel_radps", "gravity", "dof_pos_rad", "dof_vel_radps"}),
           f.Number(noise, "level", "noise", 0, 10, &p.noise_level),
           f.Number(noise, "ang_vel_radps", "noise", 0, 100, &p.noise_ang_vel_radps),
           f.Number(noise, "gravity", "noise", 0, 1, &p.noise_gravity),
           f.Number(noise, "dof_pos_rad", "noise", 0, 1, &p.noise_dof_pos_rad),
           f.Number(noise, "dof_vel_radps", "noise", 0, 100, &p.noise_dof_vel_radps),
           f.Keys(
               rnd, "randomization",
               {"friction", "added_mass_kg", "gain_scale", "latency_periods", "push_interval_s", "push_velocity_mps"}),
           f.Range(rnd, "friction", "randomization", 0.01, 5, &p.friction),
           f.Range(rnd, "added_mass_kg", "randomization", -100, 100, &p.added_mass_kg),
           f.Range(rnd, "gain_scale", "randomization", 0.1, 10, &p.gain_scale),
           f.Range(rnd, "latency_periods", "randomization", 0, 1, &p.latency_periods),
           f.Number(rnd, "push_interval_s", "randomization", 0, 3600, &p.push_interval_s),
           f.Number(rnd, "push_velocity_mps", "randomization", 0, 10, &p.push_velocity_mps),
           f.Keys(
               ter, "terrain",
               {"field_half_size_m", "blocks", "block_size_m", "block_height_m", "clear_radius_m", "near_m", "pool"}),
           f.Number(ter, "field_half_size_m", "terrain", 1, 100, &p.field_half_size_m),
           f.Integer(ter, "blocks", "terrain", 0, 100000, &blocks),
           f.Range(ter, "block_size_m", "terrain", 0.05, 20, &p.block_size_m),
           f.Range(ter, "block_height_m", "terrain", 0, 1, &p.block_height_m),
           f.Number(ter, "clear_radius_m", "terrain", 0, 100, &p.clear_radius_m),
           f.Number(ter, "near_m", "terrain", 0.1, 10, &p.near_m),
           f.Integer(ter, "pool", "terrain", 1, 256, &pool),
       }) {
    if (!st) return st.error();
  }
  // legged_gym's reward scales, each any number (0: the term off); base_height and termination may
  // be left out.
  for (const auto& [key, member] : kRewardScales) {
    const bool optional = std::string_view(key) == "termination" || std::string_view(key) == "base_height";
    if (auto st = optional ? f.OptionalNumber(sc, key, "rewards.scales", -kBig, kBig, &(s.*member))
                           : f.Number(sc, key, "rewards.scales", -kBig, kBig, &(s.*member));
        !st)
      return st.error();
  }
  p.decimation = static_cast<int>(decimation);
  p.blocks = static_cast<int>(blocks);
  p.pool = static_cast<int>(pool);
  p.only_positive = only_positive != 0;
  p.terminate_on_base_contact = base_contact != 0;
  if (p.episode_steps() < 1) return f.Fail("simulation.episode_s", "is shorter than one policy period");
  if (s.base_height != 0 && !(p.base_height_target_m > 0))
    return f.Fail("rewards", "missing field 'base_height_target_m': rewards.scales.base_height is not 0");
  return p;
}

namespace {

// `text` as a finite number, all of it (the command-line specs' numbers).
bool WholeNumber(const std::string& text, double& out) {
  char* stop = nullptr;
  out = std::strtod(text.c_str(), &stop);
  return !text.empty() && stop == text.c_str() + text.size() && std::isfinite(out);
}

// "A:B[:C]": parts.size() numbers separated by ':', each in [0, max]; errors name the part.
Status ParseSpec(const std::string& spec, const char* form, double max, std::span<const char* const> names,
                 std::span<double> out) {
  std::size_t start = 0;
  for (std::size_t k = 0; k < names.size(); ++k) {
    const std::size_t end = k + 1 < names.size() ? spec.find(':', start) : spec.size();
    if (end == std::string::npos) return MakeError(ErrorCode::kInvalidValue, "'" + spec + "' is not " + form);
    const std::string part = spec.substr(start, end - start);
    if (!WholeNumber(part, out[k]) || !(out[k] >= 0 && out[k] <= max)) {
      char range[32];
      std::snprintf(range, sizeof range, "[0, %g]", max);
      return MakeError(ErrorCode::kInvalidValue,
                       "'" + spec + "': " + names[k] + " '" + part + "' is not a number in " + range);
    }
    start = end + 1;
  }
  return {};
}

}  // namespace

Status ApplyCommandSpec(const std::string& spec, QuadrupedWalkParams& p) {
  if (spec.empty()) return {};
  static constexpr const char* kNames[] = {"vx", "vy", "yaw rate"};
  double v[3] = {0, 0, 0};
  if (auto st = ParseSpec(spec, "VX_MAX:VY_MAX:YAW_RATE_MAX (e.g. 1:1:1)", 5, kNames, v); !st) return st;
  p.vx_mps = {-v[0], v[0]};
  p.vy_mps = {-v[1], v[1]};
  p.yaw_rate_radps = {-v[2], v[2]};
  return {};
}

Status ApplyCommandShares(const std::string& spec, QuadrupedWalkParams& p) {
  if (spec.empty()) return {};
  static constexpr const char* kNames[] = {"heading share", "zero planar share", "single axis share"};
  double v[3] = {0, 0, 0};
  // The third share is optional: HEADING:ZERO_PLANAR keeps walk.yaml's single-axis share.
  const std::size_t parts = std::count(spec.begin(), spec.end(), ':') >= 2 ? 3 : 2;
  if (auto st = ParseSpec(spec, "HEADING_SHARE:ZERO_PLANAR_SHARE[:SINGLE_AXIS_SHARE] (e.g. 0.5:0.2)", 1,
                          std::span(kNames, parts), std::span(v, parts));
      !st)
    return st;
  p.heading_share = v[0];
  p.zero_planar_share = v[1];
  if (parts == 3) p.single_axis_share = v[2];
  return {};
}

Status ApplyCommandResample(const std::string& spec, QuadrupedWalkParams& p) {
  if (spec.empty()) return {};
  double v = 0;
  if (!WholeNumber(spec, v) || !(v >= kResampleMinS && v <= kResampleMaxS)) {
    char range[48];
    std::snprintf(range, sizeof range, "[%g, %g]", kResampleMinS, kResampleMaxS);
    return MakeError(ErrorCode::kInvalidValue, "'" + spec + "' is not a period in " + range + " s");
  }
  p.resample_s = v;
  return {};
}

Status ApplyRewardScales(const std::string& spec, QuadrupedWalkParams& p) {
  std::size_t start = 0;
  while (start < spec.size()) {
    const std::size_t end = std::min(spec.find(',', start), spec.size());
    const std::string item = spec.substr(start, end - start);
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos)
      return MakeError(ErrorCode::kInvalidValue, "'" + item + "' is not NAME=VALUE (e.g. tracking_ang_vel=1.0)");
    const std::string name = item.substr(0, eq), value = item.substr(eq + 1);
    const auto* it = std::find_if(std::begin(kRewardScales), std::end(kRewardScales),
                                  [&](const auto& e) { return name == e.first; });
    const bool sigma = name == "tracking_sigma";  // the tracking terms' width, beside the scales
    if (it == std::end(kRewardScales) && !sigma) {
      std::string known;
      for (const auto& e : kRewardScales) known += std::string(known.empty() ? "" : ", ") + e.first;
      return MakeError(ErrorCode::kInvalidValue,
                       "'" + name + "' is not a reward term (" + known + ") or tracking_sigma");
    }
    double v = 0;
    if (!WholeNumber(value, v) || std::fabs(v) > kBig)
      return MakeError(ErrorCode::kInvalidValue, name + ": '" + value + "' is not a number");
    if (sigma) {
      if (!(v >= kSigmaMin && v <= kSigmaMax)) {
        char range[48];
        std::snprintf(range, sizeof range, "[%g, %g]", kSigmaMin, kSigmaMax);
        return MakeError(ErrorCode::kInvalidValue, "tracking_sigma: '" + value + "' is not in " + range);
      }
      p.tracking_sigma = v;
    } else {
      p.scales.*(it->second) = v;
      if (name == "base_height" && v != 0 && !(p.base_height_target_m > 0))
        return MakeError(ErrorCode::kInvalidValue,
                         "base_height=" + value + ": the task sets no rewards.base_height_target_m (walk.yaml)");
    }
    start = end + 1;
  }
  return {};
}

}  // namespace pbppo::envs
