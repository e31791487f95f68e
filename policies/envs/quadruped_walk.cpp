#include "policies/envs/quadruped_walk.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <numbers>

#include "policies/envs/mjcf.hpp"
#include "runtime/robot/can_map.hpp"
#include "runtime/robot/signals.hpp"
#include "runtime/transport/can/imu_codec.hpp"
#include "runtime/transport/can/mit_codec.hpp"

namespace pbppo::envs {
namespace {

constexpr float kActionClip = 100.0f;  // legged_gym's clip_actions
constexpr int kFeet = 4;

double Wrap(double a) noexcept {
  a = std::fmod(a + std::numbers::pi, 2 * std::numbers::pi);
  if (a < 0) a += 2 * std::numbers::pi;
  return a - std::numbers::pi;
}

enum class GeomKind : std::uint8_t { kGround, kBase, kFoot, kLeg };

}  // namespace

struct QuadrupedWalk::Shared {
  std::string name = "quadruped-walk";
  QuadrupedWalkOptions options;
  // The controller's robot: its description, IO layout, CAN map, fields and signals.
  std::shared_ptr<const robot::RobotModel> robot_model;
  const robot::RobotDescription& robot() const noexcept { return *robot_model->body; }
  const robot::IoLayout& layout() const noexcept { return *robot_model->io; }
  QuadrupedWalkParams params;
  robot::ActionMapper mapper;
  // The layout's signals from the robot's fields (the controller's PolicySource computes the same),
  // the training noise of each (walk.yaml noise; 0: none), and the order the noise is drawn in:
  // the IMU's signals, then joint by joint its position and velocity (the order the shipped
  // policies were trained and are tested with).
  robot::SignalProgram signals;
  std::vector<double> noise;
  std::vector<std::size_t> noise_order;
  // The devices: per motor of the CAN map (robot_model->motors) its joint (robot order), reply
  // range and id; the base IMU's codec format and first field (qw qx qy qz, gyro, accel); the
  // operator's command fields (vx, vy, yaw rate).
  std::vector<std::size_t> motor_joint;
  std::vector<can::MitRange> motor_range;
  std::vector<std::uint8_t> motor_id;
  robot::ImuFormat imu_format = robot::ImuFormat::kClassic;
  std::uint32_t imu_field = 0;
  bool float_devices = false;  // no CAN map: the devices report float32 (a DDS robot's messages)
  std::array<std::uint32_t, 3> command_field{};
  mjModel* model = nullptr;
  std::vector<int> qpos_adr, dof_adr;  // per actuated joint
  std::vector<GeomKind> geom_kind;     // per geom
  std::vector<int> geom_foot;          // per geom: foot index or -1
  std::vector<double> soft_lower, soft_upper, effort;
  std::vector<float> low, high;
  int base_body = 0, floor_geom = -1;
  std::vector<int> block_geom;  // the pool of box geoms for blocks
  sim::BlockField block_field;  // the terrain's parameters (walk.yaml terrain)
  double base_mass = 0;
  ~Shared() {
    if (model != nullptr) mj_deleteModel(model);
  }
};

Result<std::unique_ptr<QuadrupedWalk>> QuadrupedWalk::Make(const QuadrupedWalkOptions& options) {
  auto sh = std::make_shared<Shared>();
  sh->options = options;
  if (options.terrain != "flat" && options.terrain != "mixed")
    return MakeError(ErrorCode::kInvalidValue, "--terrain: '" + options.terrain + "' unknown (flat, mixed)");
  if (!(options.blocks_fraction >= 0 && options.blocks_fraction <= 1))
    return MakeError(ErrorCode::kInvalidValue,
                     "blocks fraction: " + std::to_string(options.blocks_fraction) + " is not in [0, 1]");
  // The robot as the controller and the HIL read it (robot.yaml: the URDF description, the IO
  // layout, its motors and IMU, the policy's PD gains), and the training task it names (walk.yaml).
  const bool path = options.robot.find('/') != std::string::npos || options.robot.ends_with(".yaml");
  const std::string file = path ? options.robot
                                : (options.models_dir.empty() ? DefaultModelsDir() : options.models_dir) + "/" +
                                      options.robot + "/robot.yaml";
  std::shared_ptr<const robot::RobotModel> robot_model = options.robot_model;
  if (!robot_model) {
    auto loaded = robot::LoadRobotModel(file);
    if (!loaded) return std::move(loaded).error();
    robot_model = std::make_shared<const robot::RobotModel>(std::move(loaded).value());
  }
  if (!robot_model->body || !robot_model->io || robot_model->motors.empty())
    return MakeError(ErrorCode::kMismatch, robot_model->path +
                                               ": quadruped-walk needs files.description, files.io_layout, "
                                               "motors and their policy_gains");
  sh->robot_model = robot_model;
  auto task = robot_model->Document("walk_task");
  if (!task) return std::move(task).error();
  auto params = ParseQuadrupedWalkParams((*task)->yaml, (*task)->path);
  if (!params) return std::move(params).error();
  sh->params = *params;
  const robot::MotorSpec& gains = robot_model->motors.front();
  for (const auto& mo : robot_model->motors)
    if (mo.policy_kp != gains.policy_kp || mo.policy_kd != gains.policy_kd || mo.policy_kp < 0 || mo.policy_kd < 0)
      return MakeError(ErrorCode::kMismatch, robot_model->path +
                                                 ": motors.policy_gains must give every joint the same "
                                                 "non-negative kp and kd (joint '" +
                                                 mo.joint + "')");
  sh->params.kp_nm_rad = gains.policy_kp;
  sh->params.kd_nm_s_rad = gains.policy_kd;
  if (auto st = ApplyCommandSpec(options.commands, sh->params); !st)
    return MakeError(ErrorCode::kInvalidValue, "--commands: " + st.error().message);
  if (auto st = ApplyCommandShares(options.command_shares, sh->params); !st)
    return MakeError(ErrorCode::kInvalidValue, "--command-shares: " + st.error().message);
  if (auto st = ApplyCommandResample(options.command_resample, sh->params); !st)
    return MakeError(ErrorCode::kInvalidValue, "--command-resample: " + st.error().message);
  if (auto st = ApplyRewardScales(options.reward_scales, sh->params); !st)
    return MakeError(ErrorCode::kInvalidValue, "--reward-scales: " + st.error().message);
  if (options.paper_test) {
    sh->params.resample_s = kWalkEvalResampleS;
    sh->params.heading_share = 1.0;
    sh->params.zero_planar_share = 0.0;
    sh->params.single_axis_share = 0.0;
  }
  // A CAN map's motors and IMU report through their codecs; other devices (DDS) as float32.
  const robot::CanMap* map = robot_model->can ? &*robot_model->can : nullptr;

  const robot::RobotDescription& r = sh->robot();
  const robot::IoLayout& l = sh->layout();
  const std::size_t n = r.joint_count();
  if (l.actions.size() != n)
    return MakeError(ErrorCode::kMismatch, "io_layout.yaml: " + std::to_string(l.actions.size()) +
                                               " actions, the robot has " + std::to_string(n) + " joints");
  for (std::size_t i = 0; i < n; ++i) {
    const robot::ActionElement& a = l.actions[i];
    const robot::UrdfJoint& j = r.joint_at(i);
    const std::string where = "io_layout.yaml: actions[" + std::to_string(i) + "] '" + a.name + "'";
    if (a.command != "q_des_" + r.joint_names[i])
      return MakeError(ErrorCode::kMismatch, where + ": command '" + a.command + "' is not q_des_" + r.joint_names[i] +
                                                 " (joint " + std::to_string(i) + " of the description's joint order)");
    if (!(std::fabs(a.scale) > 0))
      return MakeError(ErrorCode::kInvalidValue, where + ": scale 0 leaves the joint at its default pose");
    if (std::fabs(a.offset - r.default_q_rad[i]) > 1e-9)
      return MakeError(ErrorCode::kMismatch, where + ": offset " + std::to_string(a.offset) +
                                                 " is not the default pose " + std::to_string(r.default_q_rad[i]) +
                                                 " of the description");
    if (a.low < j.lower_rad - 1e-9 || a.high > j.upper_rad + 1e-9)
      return MakeError(ErrorCode::kMismatch, where + ": [" + std::to_string(a.low) + ", " + std::to_string(a.high) +
                                                 "] leaves the URDF limits [" + std::to_string(j.lower_rad) + ", " +
                                                 std::to_string(j.upper_rad) + "]");
  }
  // The controller's observation path over the robot's fields; the noise by signal.
  auto signals = robot::SignalProgram::ForLayout(*robot_model, l);
  if (!signals) return std::move(signals).error();
  sh->signals = std::move(signals).value();
  if (auto probe = robot::ObservationBuilder::Create(l, sh->signals.names()); !probe) return std::move(probe).error();
  const std::vector<std::string>& names = sh->signals.names();
  for (std::size_t k = 0; k < names.size(); ++k) {
    const auto starts = [&](const char* prefix) { return names[k].rfind(prefix, 0) == 0; };
    const QuadrupedWalkParams& p = sh->params;
    const bool imu = starts("base_ang_vel_") || starts("projected_gravity_");
    sh->noise.push_back(starts("base_ang_vel_")        ? p.noise_ang_vel_radps
                        : starts("projected_gravity_") ? p.noise_gravity
                        : starts("q_")                 ? p.noise_dof_pos_rad
                        : starts("dq_")                ? p.noise_dof_vel_radps
                                                       : 0.0);
    if (imu) sh->noise_order.push_back(k);
  }
  for (const std::string& joint : r.joint_names)
    for (const char* prefix : {"q_", "dq_"}) {
      const auto it = std::find(names.begin(), names.end(), prefix + joint);
      if (it != names.end()) sh->noise_order.push_back(static_cast<std::size_t>(it - names.begin()));
    }
  sh->mapper = robot::ActionMapper::Create(l);
  // The motors (in the robot model's order) and their joints.
  std::vector<bool> have(n, false);
  for (std::size_t k = 0; k < robot_model->motors.size(); ++k) {
    const robot::MotorSpec& mo = robot_model->motors[k];
    const auto it = std::find(r.joint_names.begin(), r.joint_names.end(), mo.joint);
    if (it == r.joint_names.end())
      return MakeError(ErrorCode::kMismatch,
                       robot_model->path + ": motor '" + mo.joint + "' is not a joint of the description");
    const auto j = static_cast<std::size_t>(it - r.joint_names.begin());
    sh->motor_joint.push_back(j);
    if (map != nullptr) {
      sh->motor_range.push_back(map->range_of(map->motors[k]));
      sh->motor_id.push_back(static_cast<std::uint8_t>(map->motors[k].id));
    }
    have[j] = true;
  }
  for (std::size_t j = 0; j < n; ++j)
    if (!have[j])
      return MakeError(ErrorCode::kMismatch, robot_model->path + ": no motor for joint '" + r.joint_names[j] + "'");
  // The base IMU: the robot's first IMU stream.
  const auto imu = std::find_if(robot_model->streams.begin(), robot_model->streams.end(),
                                [](const robot::StreamSpec& st) { return st.kind == robot::StreamKind::kImu; });
  if (imu == robot_model->streams.end())
    return MakeError(ErrorCode::kMismatch, robot_model->path + ": quadruped-walk needs the base IMU");
  sh->imu_field = imu->first_field;
  if (map != nullptr && !map->imus.empty()) sh->imu_format = map->imus[0].format;
  sh->float_devices = map == nullptr;
  const char* command_names[3] = {"command_vx", "command_vy", "command_yaw_rate"};
  for (std::size_t k = 0; k < 3; ++k) {
    const int f = robot_model->FieldIndex(command_names[k]);
    if (f < 0)
      return MakeError(ErrorCode::kMismatch, robot_model->path + ": no field " + command_names[k] +
                                                 " (the operator's velocity command quadruped-walk draws)");
    sh->command_field[k] = static_cast<std::uint32_t>(f);
  }

  const QuadrupedWalkParams& p = sh->params;
  sh->block_field = {p.field_half_size_m,
                     p.blocks,
                     {p.block_size_m[0], p.block_size_m[1]},
                     {p.block_height_m[0], p.block_height_m[1]},
                     p.clear_radius_m};
  MjcfOptions mo;
  mo.timestep_s = p.timestep_s;
  mo.base_height_m = p.init_base_height_m;
  if (options.terrain == "mixed") mo.block_geoms = p.pool;
  auto xml = GenerateMjcf(r, mo);
  if (!xml) return std::move(xml).error();
  auto model = CompileMjcf(*xml, "quadruped");
  if (!model) return std::move(model).error();
  sh->model = *model;
  mjModel* m = sh->model;
  for (std::size_t i = 0; i < n; ++i) {
    const int id = mj_name2id(m, mjOBJ_JOINT, r.joint_names[i].c_str());
    sh->qpos_adr.push_back(m->jnt_qposadr[id]);
    sh->dof_adr.push_back(m->jnt_dofadr[id]);
    const robot::UrdfJoint& j = r.joint_at(i);
    const double mid = 0.5 * (j.lower_rad + j.upper_rad), half = 0.5 * (j.upper_rad - j.lower_rad);
    sh->soft_lower.push_back(mid - half * p.soft_dof_pos_limit);
    sh->soft_upper.push_back(mid + half * p.soft_dof_pos_limit);
    sh->effort.push_back(j.effort_nm);
  }
  sh->base_body = mj_name2id(m, mjOBJ_BODY, r.urdf.links[r.urdf.root].name.c_str());
  sh->base_mass = m->body_mass[sh->base_body];
  sh->floor_geom = mj_name2id(m, mjOBJ_GEOM, "floor");
  for (int k = 0; k < mo.block_geoms; ++k)
    sh->block_geom.push_back(mj_name2id(m, mjOBJ_GEOM, ("block_" + std::to_string(k)).c_str()));
  int feet = 0;
  for (int g = 0; g < m->ngeom; ++g) {
    GeomKind kind = GeomKind::kGround;
    int foot = -1;
    if (m->geom_contype[g] != 0) {
      const int b = m->geom_bodyid[g];
      if (b == sh->base_body) {
        kind = GeomKind::kBase;
      } else if (m->geom_type[g] == mjGEOM_SPHERE) {
        kind = GeomKind::kFoot;
        foot = feet++;
      } else {
        kind = GeomKind::kLeg;
      }
    }
    sh->geom_kind.push_back(kind);
    sh->geom_foot.push_back(foot);
  }
  if (feet != kFeet)
    return MakeError(ErrorCode::kMismatch, "quadruped.urdf: " + std::to_string(feet) +
                                               " foot spheres, the task needs " + std::to_string(kFeet));
  sh->low.assign(n, -kActionClip);
  sh->high.assign(n, kActionClip);
  return std::unique_ptr<QuadrupedWalk>(new QuadrupedWalk(std::move(sh)));
}

QuadrupedWalk::QuadrupedWalk(std::shared_ptr<const Shared> shared) : shared_(std::move(shared)) {
  const Shared& s = *shared_;
  m_ = mj_copyModel(nullptr, s.model);
  d_ = mj_makeData(m_);
  builder_ = *robot::ObservationBuilder::Create(s.layout(), s.signals.names());
  clean_builder_ = *robot::ObservationBuilder::Create(s.layout(), s.signals.names());
  fields_.assign(s.robot_model->fields.size(), 0.0);
  signals_.assign(s.signals.size(), 0.0);
  clean_signals_.assign(s.signals.size(), 0.0);
  clean_obs_.assign(builder_.observation_size(), 0.0f);
  const std::size_t n = s.robot().joint_count();
  observed_action_.assign(n, 0.0f);
  for (auto* v : {&kp_, &kd_, &target_, &prev_target_, &action_, &last_action_, &last_dq_, &torque_}) v->assign(n, 0.0);
  air_time_.assign(kFeet, 0.0);
  blocks_.reserve(static_cast<std::size_t>(s.params.blocks));
  block_slot_.reserve(static_cast<std::size_t>(s.params.blocks));
  slot_block_.assign(s.block_geom.size(), -1);
}

QuadrupedWalk::~QuadrupedWalk() {
  mj_deleteData(d_);
  mj_deleteModel(m_);
}

const std::string& QuadrupedWalk::name() const noexcept {
  return shared_->name;
}
std::string QuadrupedWalk::provenance() const {
  // A blob's provenance holds 256 bytes of this (cut with "...", summary.json has it whole): the
  // run's choices first (robot, terrain, command mix, reward scales changed for the run), then
  // walk.yaml's noise and randomisation.
  const QuadrupedWalkParams& p = shared_->params;
  char text[256];
  int n = std::snprintf(text, sizeof text, "%s, robot %s, terrain %s, commands every %g s (%g heading, %g zero planar",
                        name().c_str(), shared_->robot_model->name.c_str(), shared_->options.terrain.c_str(),
                        p.resample_s, p.heading_share, p.zero_planar_share);
  std::string out(text, static_cast<std::size_t>(std::clamp(n, 0, static_cast<int>(sizeof text) - 1)));
  if (p.single_axis_share > 0) {
    n = std::snprintf(text, sizeof text, ", %g single axis", p.single_axis_share);
    out.append(text, static_cast<std::size_t>(std::clamp(n, 0, static_cast<int>(sizeof text) - 1)));
  }
  out += ")";
  if (!shared_->options.reward_scales.empty()) out += "; rewards " + shared_->options.reward_scales;
  n = std::snprintf(text, sizeof text, "; noise x%g (ang vel %g, gravity %g, q %g, dq %g)", p.noise_level,
                    p.noise_ang_vel_radps, p.noise_gravity, p.noise_dof_pos_rad, p.noise_dof_vel_radps);
  out.append(text, static_cast<std::size_t>(std::clamp(n, 0, static_cast<int>(sizeof text) - 1)));
  if (!shared_->options.randomize) return out + "; nominal robot";
  std::snprintf(text, sizeof text,
                "; friction %g..%g, mass %+g..%+g kg, gains x%g..%g, latency %g..%g, pushes %g m/s/%g s", p.friction[0],
                p.friction[1], p.added_mass_kg[0], p.added_mass_kg[1], p.gain_scale[0], p.gain_scale[1],
                p.latency_periods[0], p.latency_periods[1], p.push_velocity_mps, p.push_interval_s);
  return out + text;
}
std::span<const float> QuadrupedWalk::action_low() const noexcept {
  return shared_->low;
}
std::span<const float> QuadrupedWalk::action_high() const noexcept {
  return shared_->high;
}
std::uint32_t QuadrupedWalk::max_episode_steps() const noexcept {
  return static_cast<std::uint32_t>(shared_->params.episode_steps());
}
const robot::IoLayout& QuadrupedWalk::layout() const noexcept {
  return shared_->layout();
}
const QuadrupedWalkParams& QuadrupedWalk::params() const noexcept {
  return shared_->params;
}
const QuadrupedWalkOptions& QuadrupedWalk::options() const noexcept {
  return shared_->options;
}
const robot::RobotDescription& QuadrupedWalk::robot() const noexcept {
  return shared_->robot();
}
const robot::RobotModel& QuadrupedWalk::robot_model() const noexcept {
  return *shared_->robot_model;
}
// The policy's observation without noise, then: base linear velocity (base frame) x 2, base height
// over the ground, foot contacts, friction, added base mass, actuation latency in policy periods.
std::uint32_t QuadrupedWalk::critic_observation_size() const noexcept {
  return observation_size() + 3 + 1 + kFeet + 3;
}

std::unique_ptr<Env> QuadrupedWalk::Clone() const {
  return std::unique_ptr<Env>(new QuadrupedWalk(shared_));
}

EpisodeInfo QuadrupedWalk::episode_info() const noexcept {
  EpisodeInfo e;
  e.available = true;
  e.failure = fell_;
  e.success = !fell_;
  e.time_s = static_cast<double>(step_) * shared_->params.policy_dt_s();
  for (std::size_t k = 0; k < 3; ++k) e.tracking_error[k] = step_ > 0 ? error_sum_[k] / step_ : EpisodeInfo::kNoValue;
  return e;
}

void QuadrupedWalk::BuildTerrain(bool blocks) noexcept {
  const Shared& s = *shared_;
  on_blocks_ = blocks && !s.block_geom.empty();
  blocks_.clear();
  block_slot_.clear();
  for (std::size_t k = 0; k < s.block_geom.size(); ++k) {
    const int g = s.block_geom[k];
    m_->geom_conaffinity[g] = 0;
    m_->geom_pos[3 * g + 2] = -10.0;
    slot_block_[k] = -1;
  }
  if (!on_blocks_) return;
  GenerateBlocks(s.block_field, rng_, blocks_);
  block_slot_.assign(blocks_.size(), -1);
}

// The blocks within near_m of the base (in x and y) go into the pool's geoms and stay in the same
// geom while they are near; blocks that are no longer near leave it. Where more blocks are near
// than the pool holds, the later ones wait (the pool is sized so that this does not happen).
void QuadrupedWalk::UpdateBlockPool() noexcept {
  if (!on_blocks_) return;
  const Shared& s = *shared_;
  const double r = s.params.near_m, x = d_->qpos[0], y = d_->qpos[1];
  auto near = [&](const sim::TerrainBlock& b) { return b.x1 > x - r && b.x0 < x + r && b.y1 > y - r && b.y0 < y + r; };
  for (std::size_t k = 0; k < slot_block_.size(); ++k) {
    const int b = slot_block_[k];
    if (b < 0 || near(blocks_[static_cast<std::size_t>(b)])) continue;
    const int g = s.block_geom[k];
    m_->geom_conaffinity[g] = 0;
    m_->geom_pos[3 * g + 2] = -10.0;
    block_slot_[static_cast<std::size_t>(b)] = -1;
    slot_block_[k] = -1;
  }
  std::size_t free_slot = 0;
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    if (block_slot_[b] >= 0 || !near(blocks_[b])) continue;
    while (free_slot < slot_block_.size() && slot_block_[free_slot] >= 0) ++free_slot;
    if (free_slot == slot_block_.size()) break;
    const sim::TerrainBlock& k = blocks_[b];
    const int g = s.block_geom[free_slot];
    const double hx = (k.x1 - k.x0) / 2, hy = (k.y1 - k.y0) / 2, hz = k.height / 2;
    m_->geom_pos[3 * g] = k.x0 + hx;
    m_->geom_pos[3 * g + 1] = k.y0 + hy;
    m_->geom_pos[3 * g + 2] = hz;
    m_->geom_size[3 * g] = hx;
    m_->geom_size[3 * g + 1] = hy;
    m_->geom_size[3 * g + 2] = hz;
    m_->geom_rbound[g] = std::sqrt(hx * hx + hy * hy + hz * hz);
    m_->geom_conaffinity[g] = 1;
    slot_block_[free_slot] = static_cast<int>(b);
    block_slot_[b] = static_cast<int>(free_slot);
  }
}

double QuadrupedWalk::GroundHeight(double x, double y) const noexcept {
  return sim::TerrainHeight(blocks_, x, y);
}

void QuadrupedWalk::HoldCommand(const std::array<double, 3>& c) noexcept {
  held_ = true;
  command_ = {c[0], c[1], c[2], 0.0};
}

void QuadrupedWalk::ResampleCommand() noexcept {
  if (held_) return;
  const QuadrupedWalkParams& p = shared_->params;
  // A share of 1 or 0 draws nothing for its choice, so the paper's test (all heading, none
  // zeroed) sees the same commands for a seed whatever the training's shares.
  auto chance = [&](double share) { return share >= 1.0 || (share > 0.0 && rng_.Uniform() < share); };
  command_[0] = rng_.Uniform(p.vx_mps[0], p.vx_mps[1]);
  command_[1] = rng_.Uniform(p.vy_mps[0], p.vy_mps[1]);
  heading_mode_ = chance(p.heading_share);
  if (heading_mode_) {
    command_[3] = rng_.Uniform(p.heading_rad[0], p.heading_rad[1]);
  } else {
    command_[2] = rng_.Uniform(p.yaw_rate_radps[0], p.yaw_rate_radps[1]);
  }
  if (chance(p.single_axis_share)) {
    // One axis alone, the others 0 and no heading (a single-axis share of 0 draws nothing here).
    const int axis = std::min(2, static_cast<int>(rng_.Uniform() * 3.0));
    heading_mode_ = false;
    if (axis != 0) command_[0] = 0.0;
    if (axis != 1) command_[1] = 0.0;
    command_[2] = axis == 2 ? rng_.Uniform(p.yaw_rate_radps[0], p.yaw_rate_radps[1]) : 0.0;
  }
  if (chance(p.zero_planar_share) || std::hypot(command_[0], command_[1]) < p.zero_below_mps)
    command_[0] = command_[1] = 0.0;
  ++tel_.command_index;
}

void QuadrupedWalk::Reset(Rng& rng, std::span<float> observation) {
  const Shared& s = *shared_;
  const QuadrupedWalkParams& p = s.params;
  rng_.Seed(rng.Next());
  const bool dr = s.options.randomize;
  friction_ = dr ? rng_.Uniform(p.friction[0], p.friction[1]) : 1.0;
  added_mass_ = dr ? rng_.Uniform(p.added_mass_kg[0], p.added_mass_kg[1]) : 0.0;
  const double lat = dr ? rng_.Uniform(p.latency_periods[0], p.latency_periods[1]) : 0.0;
  latency_substeps_ = static_cast<int>(std::lround(lat * p.decimation));
  for (std::size_t j = 0; j < kp_.size(); ++j) {
    kp_[j] = p.kp_nm_rad * (dr ? rng_.Uniform(p.gain_scale[0], p.gain_scale[1]) : 1.0);
    kd_[j] = p.kd_nm_s_rad * (dr ? rng_.Uniform(p.gain_scale[0], p.gain_scale[1]) : 1.0);
  }
  for (int g = 0; g < m_->ngeom; ++g) m_->geom_friction[3 * g] = friction_;
  m_->body_mass[s.base_body] = s.base_mass + added_mass_;
  BuildTerrain(s.options.terrain == "mixed" && rng_.Uniform() < s.options.blocks_fraction);

  mj_resetData(m_, d_);
  d_->qpos[2] = p.init_base_height_m + GroundHeight(0, 0);
  for (std::size_t j = 0; j < kp_.size(); ++j) {
    const double q = s.robot().default_q_rad[j] * rng_.Uniform(p.init_joint_scale[0], p.init_joint_scale[1]);
    const robot::UrdfJoint& uj = s.robot().joint_at(j);
    d_->qpos[s.qpos_adr[j]] = std::clamp(q, uj.lower_rad, uj.upper_rad);
    target_[j] = prev_target_[j] = s.robot().default_q_rad[j];
    action_[j] = last_action_[j] = 0.0;
    last_dq_[j] = torque_[j] = 0.0;
  }
  for (int k = 0; k < 6; ++k) d_->qvel[k] = rng_.Uniform(-p.init_base_velocity, p.init_base_velocity);
  UpdateBlockPool();
  mj_forward(m_, d_);
  std::fill(air_time_.begin(), air_time_.end(), 0.0);
  foot_contact_.fill(false);
  last_foot_contact_.fill(false);
  step_ = 0;
  fell_ = false;
  done_ = false;
  tel_ = WalkTelemetry{.physics_overflows = tel_.physics_overflows};
  if (!held_) command_ = {0, 0, 0, 0};
  error_sum_ = {0, 0, 0};
  ResampleCommand();
  Contacts();
  Observe(observation, true);
}

void QuadrupedWalk::ApplyTargets(const double* target, int substeps) noexcept {
  const Shared& s = *shared_;
  const std::size_t n = kp_.size();
  for (int k = 0; k < substeps; ++k) {
    for (std::size_t j = 0; j < n; ++j) {
      const double q = d_->qpos[s.qpos_adr[j]], dq = d_->qvel[s.dof_adr[j]];
      const double tau = kp_[j] * (target[j] - q) - kd_[j] * dq;
      torque_[j] = std::clamp(tau, -s.effort[j], s.effort[j]);
      d_->ctrl[j] = torque_[j];
    }
    mj_step(m_, d_);
  }
  for (const int w : {mjWARN_CONTACTFULL, mjWARN_CNSTRFULL}) {
    tel_.physics_overflows += static_cast<std::uint32_t>(d_->warning[w].number);
    d_->warning[w].number = 0;
  }
}

void QuadrupedWalk::Contacts() noexcept {
  const Shared& s = *shared_;
  last_foot_contact_ = foot_contact_;
  foot_contact_.fill(false);
  collisions_ = 0;
  base_contact_ = false;
  for (int i = 0; i < d_->ncon; ++i) {
    const mjContact& c = d_->contact[i];
    const int g = s.geom_kind[c.geom1] != GeomKind::kGround ? c.geom1 : c.geom2;
    const GeomKind kind = s.geom_kind[g];
    if (kind == GeomKind::kGround) continue;
    if (kind == GeomKind::kBase) {
      base_contact_ = true;
      continue;
    }
    mjtNum f[6];
    mj_contactForce(m_, d_, i, f);
    if (kind == GeomKind::kFoot) {
      if (f[0] > shared_->params.contact_force_n) foot_contact_[static_cast<std::size_t>(s.geom_foot[g])] = true;
    } else if (f[0] > 0.1) {
      ++collisions_;
    }
  }
}

// The robot model's fields as the devices report them: each motor's MIT reply and the base IMU's
// sample through their codecs (what the CAN transport decodes), or as float32 (a DDS robot's
// messages); the operator's command as sent.
void QuadrupedWalk::WriteFields() noexcept {
  const Shared& s = *shared_;
  const robot::RobotModel& m = *s.robot_model;
  double* f = fields_.data();
  // The base IMU: orientation (base to world), angular velocity in the base frame, and the
  // specific force in the base frame, R^T (a - g), from the last step's acceleration.
  can::ImuSample imu;
  const mjtNum* q = d_->qpos + 3;  // w x y z
  mjtNum rot[9], a_world[3], a_body[3];
  mju_quat2Mat(rot, q);
  for (int k = 0; k < 3; ++k) a_world[k] = d_->qacc[k] - m_->opt.gravity[k];
  mju_mulMatTVec(a_body, rot, a_world, 3, 3);
  for (int k = 0; k < 4; ++k) imu.quat_wxyz[k] = q[k];
  for (int k = 0; k < 3; ++k) {
    imu.gyro_rad_s[k] = d_->qvel[3 + k];
    imu.accel_m_s2[k] = a_body[k];
  }
  imu.status = can::kImuOrientationValid;
  can::ImuSample got;
  if (s.float_devices) {
    const auto f32 = [](double v) { return static_cast<double>(static_cast<float>(v)); };
    for (std::size_t k = 0; k < m.motors.size(); ++k) {
      const robot::MotorSpec& mo = m.motors[k];
      const std::size_t j = s.motor_joint[k];
      f[mo.q_field] = f32(d_->qpos[s.qpos_adr[j]]);
      f[mo.dq_field] = f32(d_->qvel[s.dof_adr[j]]);
      f[mo.tau_field] = f32(torque_[j]);
    }
    for (int k = 0; k < 4; ++k) got.quat_wxyz[k] = f32(imu.quat_wxyz[k]);
    for (int k = 0; k < 3; ++k) got.gyro_rad_s[k] = f32(imu.gyro_rad_s[k]);
    for (int k = 0; k < 3; ++k) got.accel_m_s2[k] = f32(imu.accel_m_s2[k]);
  } else {
    for (std::size_t k = 0; k < m.motors.size(); ++k) {
      const robot::MotorSpec& mo = m.motors[k];
      const std::size_t j = s.motor_joint[k];
      const can::MitReply sent{s.motor_id[k], d_->qpos[s.qpos_adr[j]], d_->qvel[s.dof_adr[j]], torque_[j]};
      std::uint8_t frame[can::kMitReplyLen];
      (void)can::EncodeMitReply(s.motor_range[k], sent, frame);
      can::MitReply reply;
      (void)can::DecodeMitReply(s.motor_range[k], frame, can::kMitReplyLen, &reply);
      f[mo.q_field] = reply.q_rad;
      f[mo.dq_field] = reply.dq_rad_s;
      f[mo.tau_field] = reply.tau_nm;
    }
    if (s.imu_format == robot::ImuFormat::kFd) {
      std::uint8_t frame[can::kImuFdLen];
      can::EncodeImuFd(imu, frame);
      (void)can::DecodeImuFd(frame, can::kImuFdLen, &got);
    } else {
      std::uint8_t frames[3][can::kImuClassicLen];
      can::EncodeImuClassic(imu, frames[0], frames[1], frames[2]);
      for (unsigned k = 0; k < 3; ++k) (void)can::DecodeImuClassicFrame(k, frames[k], can::kImuClassicLen, &got);
    }
  }
  double* i = f + s.imu_field;  // qw qx qy qz, gyro x y z, accel x y z (the robot model's IMU stream)
  for (int k = 0; k < 4; ++k) i[k] = got.quat_wxyz[k];
  for (int k = 0; k < 3; ++k) i[4 + k] = got.gyro_rad_s[k];
  for (int k = 0; k < 3; ++k) i[7 + k] = got.accel_m_s2[k];
  for (std::size_t k = 0; k < 3; ++k) f[s.command_field[k]] = command_[k];
}

// The controller's observation of the fields (SignalProgram, ObservationBuilder). Training noise is
// added to the signals between the two (uniform, walk.yaml's amplitudes, drawn in noise_order);
// the critic's copy has none.
void QuadrupedWalk::Observe(std::span<float> observation, bool first) noexcept {
  const Shared& s = *shared_;
  WriteFields();
  for (std::size_t j = 0; j < action_.size(); ++j) observed_action_[j] = static_cast<float>(action_[j]);
  s.signals.Compute(fields_, observed_action_, clean_signals_.data());
  const double level = s.options.noise ? s.params.noise_level : 0.0;
  std::copy(clean_signals_.begin(), clean_signals_.end(), signals_.begin());  // (-0.0 stays -0.0)
  if (level > 0)
    for (const std::size_t k : s.noise_order) signals_[k] += (2 * rng_.Uniform() - 1) * s.noise[k] * level;
  builder_.Build(signals_.data(), first, observation.data());
  clean_builder_.Build(clean_signals_.data(), first, clean_obs_.data());
}

void QuadrupedWalk::CriticObservation(std::span<float> out) const noexcept {
  const Shared& s = *shared_;
  std::copy(clean_obs_.begin(), clean_obs_.end(), out.begin());
  std::size_t k = clean_obs_.size();
  const mjtNum* q = d_->qpos + 3;
  mjtNum rot[9], v_body[3];
  mju_quat2Mat(rot, q);
  mju_mulMatTVec(v_body, rot, d_->qvel, 3, 3);
  for (int a = 0; a < 3; ++a) out[k++] = static_cast<float>(2.0 * v_body[a]);
  out[k++] = static_cast<float>(d_->qpos[2] - GroundHeight(d_->qpos[0], d_->qpos[1]));
  for (int f = 0; f < kFeet; ++f) out[k++] = foot_contact_[static_cast<std::size_t>(f)] ? 1.0f : 0.0f;
  out[k++] = static_cast<float>(friction_);
  out[k++] = static_cast<float>(added_mass_);
  out[k++] = static_cast<float>(static_cast<double>(latency_substeps_) / s.params.decimation);
}

double QuadrupedWalk::Reward() noexcept {
  const Shared& s = *shared_;
  const QuadrupedWalkParams& p = s.params;
  const WalkRewardScales& w = p.scales;
  const double dt = p.policy_dt_s();
  mjtNum rot[9], v[3];
  mju_quat2Mat(rot, d_->qpos + 3);
  mju_mulMatTVec(v, rot, d_->qvel, 3, 3);
  const mjtNum* om = d_->qvel + 3;          // base frame
  const double g0 = -rot[6], g1 = -rot[7];  // gravity in the base frame, x and y
  const std::size_t n = kp_.size();
  double torques = 0, acc = 0, rate = 0, limits = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const double dq = d_->qvel[s.dof_adr[j]], qj = d_->qpos[s.qpos_adr[j]];
    torques += torque_[j] * torque_[j];
    const double a = (dq - last_dq_[j]) / dt;
    acc += a * a;
    rate += (last_action_[j] - action_[j]) * (last_action_[j] - action_[j]);
    limits += std::max(0.0, s.soft_lower[j] - qj) + std::max(0.0, qj - s.soft_upper[j]);
  }
  const double ev = (command_[0] - v[0]) * (command_[0] - v[0]) + (command_[1] - v[1]) * (command_[1] - v[1]);
  const double ew = (command_[2] - om[2]) * (command_[2] - om[2]);
  double air = 0;
  for (int f = 0; f < kFeet; ++f) {
    const auto k = static_cast<std::size_t>(f);
    const bool contact = foot_contact_[k] || last_foot_contact_[k];
    const bool first = air_time_[k] > 0 && contact;
    air_time_[k] += dt;
    if (first) air += air_time_[k] - p.feet_air_time_target_s;
    if (contact) air_time_[k] = 0;
  }
  if (std::hypot(command_[0], command_[1]) <= 0.1) air = 0;
  double r = w.tracking_lin_vel * std::exp(-ev / p.tracking_sigma) +
             w.tracking_ang_vel * std::exp(-ew / p.tracking_sigma) + w.lin_vel_z * v[2] * v[2] +
             w.ang_vel_xy * (om[0] * om[0] + om[1] * om[1]) + w.orientation * (g0 * g0 + g1 * g1) +
             w.torques * torques + w.dof_acc * acc + w.action_rate * rate + w.collision * collisions_ +
             w.feet_air_time * air + w.dof_pos_limits * limits;
  if (w.base_height != 0) {
    const double h = d_->qpos[2] - GroundHeight(d_->qpos[0], d_->qpos[1]) - p.base_height_target_m;
    r += w.base_height * h * h;
  }
  r *= dt;
  if (p.only_positive) r = std::max(r, 0.0);
  if (fell_) r += w.termination * dt;  // after the clip, as legged_gym adds it
  return r;
}

StepResult QuadrupedWalk::Step(std::span<const float> action, std::span<float> observation) {
  const Shared& s = *shared_;
  const QuadrupedWalkParams& p = s.params;
  const std::size_t n = kp_.size();
  float a[64];
  for (std::size_t j = 0; j < n; ++j)
    a[j] = std::clamp(std::isfinite(action[j]) ? action[j] : 0.0f, -kActionClip, kActionClip);
  (void)s.mapper.Map(a, target_.data());
  // The action as the controller knows it: from the blob's output, the joint target after the
  // layout's clamp (the same as the policy's output unless the target hit a joint limit).
  for (std::size_t j = 0; j < n; ++j) {
    const robot::ActionElement& e = s.layout().actions[j];
    last_action_[j] = action_[j];
    action_[j] = (target_[j] - e.offset) / e.scale;
    last_dq_[j] = d_->qvel[s.dof_adr[j]];
  }
  UpdateBlockPool();
  ApplyTargets(prev_target_.data(), std::min(latency_substeps_, p.decimation));
  ApplyTargets(target_.data(), p.decimation - std::min(latency_substeps_, p.decimation));
  prev_target_ = target_;
  ++step_;
  const double dt = p.policy_dt_s();
  // Pushes: the base's horizontal velocity set at random.
  const int push_steps = static_cast<int>(std::lround(p.push_interval_s / dt));
  if (s.options.randomize && push_steps > 0 && step_ % push_steps == 0) {
    d_->qvel[0] = rng_.Uniform(-p.push_velocity_mps, p.push_velocity_mps);
    d_->qvel[1] = rng_.Uniform(-p.push_velocity_mps, p.push_velocity_mps);
  }
  const int resample_steps = std::max(1, static_cast<int>(std::lround(p.resample_s / dt)));
  if (step_ % resample_steps == 0) ResampleCommand();
  mjtNum rot[9];
  mju_quat2Mat(rot, d_->qpos + 3);
  const double yaw = std::atan2(rot[3], rot[0]);
  if (heading_mode_ && !held_)
    command_[2] = std::clamp(p.heading_gain * Wrap(command_[3] - yaw), p.yaw_rate_radps[0], p.yaw_rate_radps[1]);
  Contacts();
  const double tilt = std::acos(std::clamp(rot[8], -1.0, 1.0));
  fell_ = (p.terminate_on_base_contact && base_contact_) || tilt > p.max_tilt_rad;
  StepResult res;
  res.reward = Reward();
  res.terminated = fell_;
  res.truncated = step_ >= p.episode_steps();
  Observe(observation, false);
  mjtNum v[3];
  mju_mulMatTVec(v, rot, d_->qvel, 3, 3);
  tel_.time_s = step_ * dt;
  tel_.command = {command_[0], command_[1], command_[2]};
  tel_.measured = {v[0], v[1], d_->qvel[5]};
  for (std::size_t k = 0; k < 3; ++k) error_sum_[k] += std::fabs(tel_.command[k] - tel_.measured[k]);
  tel_.position = {d_->qpos[0], d_->qpos[1], d_->qpos[2]};
  tel_.yaw_rad = yaw;
  tel_.on_blocks = on_blocks_;
  tel_.fell = fell_;
  tel_.base_contact = p.terminate_on_base_contact && base_contact_;
  return res;
}

double QuadrupedWalk::BarePhysicsRate(int steps) const {
  const Shared& s = *shared_;
  mjModel* m = mj_copyModel(nullptr, m_);
  mjData* d = mj_makeData(m);
  mj_copyData(d, m, d_);
  auto cpu = [] {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
  };
  const double t0 = cpu();
  for (int k = 0; k < steps; ++k) {
    for (std::size_t j = 0; j < kp_.size(); ++j)
      d->ctrl[j] = kp_[j] * (s.robot().default_q_rad[j] - d->qpos[s.qpos_adr[j]]) - kd_[j] * d->qvel[s.dof_adr[j]];
    mj_step(m, d);
  }
  const double seconds = cpu() - t0;
  mj_deleteData(d);
  mj_deleteModel(m);
  return steps / seconds;
}

}  // namespace pbppo::envs
