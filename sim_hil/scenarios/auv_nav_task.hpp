// The AUV navigation task of the Pb-PPO paper (appendix): reach three targets in order in a
// 40 m x 40 m arena without coming closer than l_safe to an obstacle or wall. One instance owns
// one AuvPlant (one Simbody System), so use one instance per thread. The trainer's environment
// wraps Reset/Step; the HIL simulator runs the same plant and the same reward.
//
// Reward (per control period): r = dc * r_c + dg * r_g + de * r_e with
//   r_c = -collision_penalty        if clearance < l_safe (the episode terminates),
//   r_g = +goal_reward              the first time l_AT < l_AT_max for the current target,
//   r_e = -step_penalty + distance_gain * (l_AT(t-1) - l_AT(t)) + bearing_gain * (|phi(t-1)| - |phi(t)|),
// where l_AT and phi (bearing to the target relative to the heading, wrapped to (-pi, pi]) are
// both taken with respect to the target that was current at the start of the step. With
// task.progress: geodesic, r_e takes the shortest-path distance through the free space instead
// of l_AT, and the bearing of that path's direction instead of phi (not in the paper: it stops
// paying for progress into dead ends).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/random.hpp"
#include "runtime/core/result.hpp"
#include "runtime/robot/io_layout.hpp"
#include "runtime/robot/observation_builder.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/robot/signals.hpp"
#include "sim_hil/plants/auv_plant.hpp"
#include "sim_hil/scenarios/auv_geodesic.hpp"
#include "sim_hil/scenarios/auv_layout.hpp"
#include "sim_hil/scenarios/auv_sonar.hpp"

namespace pbppo::sim {

struct AuvTaskParams {
  double depth_m = 5.0;
  double safe_distance_m = 1.2;  // l_safe
  double target_radius_m = 1.5;  // l_AT_max
  double episode_time_s = 200.0;
  double weight_collision = 1.0;  // delta_c
  double weight_goal = 1.0;       // delta_g
  double weight_progress = 1.0;   // delta_e
  double collision_penalty = 500.0;
  double goal_reward = 1000.0;
  double step_penalty = 0.2;
  double distance_gain = 5.0;
  double bearing_gain = 2.0;
  // The distance and bearing of r_e: "euclidean" (the paper: straight line to the target) or
  // "geodesic" (the shortest path through the free space, see auv_geodesic.hpp). The
  // observation's target distance and bearing stay straight-line (what a vehicle measures).
  enum class Progress { kEuclidean, kGeodesic };
  Progress progress = Progress::kEuclidean;
  // Geodesic only (task.geodesic_margin: {distance_m, cost}): the path pays up to `cost` extra
  // per metre within `distance_m` beyond l_safe of an obstacle (GeodesicField::Compute), so the
  // progress term leads round obstacles with room to spare instead of along the l_safe boundary.
  // 0: the shortest path (it grazes l_safe).
  double geodesic_margin_m = 0.0;
  double geodesic_margin_cost = 0.0;
  // Clearance term (task.clearance_penalty: {distance_m, per_step}, not in the paper): each step
  // with the clearance c within `distance_m` beyond l_safe costs per_step (1 - (c - l_safe) /
  // distance_m), rising linearly from 0 at l_safe + distance_m to per_step at l_safe. The
  // paper's reward charges only the collision itself. 0: off.
  double clearance_penalty_m = 0.0;
  double clearance_penalty_per_step = 0.0;
  // What the mission computer plans the route signal over (task.route_map): "chart" (the
  // layout's fixed obstacles) or "chart_and_sonar" (those plus a map of the sonar's returns in
  // this episode: every point where a receive ray found a surface that is not on the chart; the
  // route is replanned when the map gains a point).
  enum class RouteMap { kChart, kChartAndSonar };
  RouteMap route_map = RouteMap::kChart;
};

// "euclidean" or "geodesic" -> *out; false for any other name (*out unchanged).
bool ParseAuvProgress(const std::string& name, AuvTaskParams::Progress* out) noexcept;

// The AUV's sample as the robot model's fields (models/auv/robot.yaml streams[sensor]): where the
// task writes each quantity it measures (AuvNavTask::FillSensorFields). The HIL publishes them
// (the robot file maps them onto its DDS message), and the task observes them through the model's
// signals (runtime/robot/signals.hpp): what the controller computes from the received sample.
struct AuvFieldIndex {
  std::uint32_t count = 0;  // fields of the robot
  std::uint32_t tick, x, y, depth, roll, pitch, yaw, surge, sway, heave, roll_rate, pitch_rate, yaw_rate,
      target_distance, target_bearing, route_bearing, clearance, target_index, target_x, target_y, mission_complete,
      episode_end, sonar_beams;
  std::vector<std::uint32_t> sonar;  // per beam
};

// Everything a task instance needs, loaded once and shared read-only between instances.
struct AuvTaskConfig {
  AuvParams plant;
  SonarParams sonar;
  AuvTaskParams task;
  AuvLayout layout;
  robot::IoLayout io;
  robot::SignalProgram signals;  // every signal of the robot (robot::SignalNames order)
  AuvFieldIndex fields;
};

// Read the sonar and task sections of the plant file (models/auv/auv.yaml); `path` names it in
// errors. The mission depth is the robot's (robot.yaml parameters.depth_m).
Result<SonarParams> ParseSonarParams(const YAML::Node& plant, const std::string& path);
Result<AuvTaskParams> ParseAuvTaskParams(const YAML::Node& plant, const std::string& path, double depth_m);
// Everything a task needs, from the robot (models/auv/robot.yaml, loaded once): the plant, sonar
// and task of its plant file, the layout `layout` (one of its files.layouts), its IO layout.
Result<AuvTaskConfig> MakeAuvTaskConfig(const robot::RobotModel& model, const std::string& layout);

struct AuvStepEvents {
  int target_reached = -1;  // index of the target reached in this step, or -1
  bool collision = false;
  bool all_targets = false;
};

struct AuvStepResult {
  double reward = 0.0;
  bool terminated = false;  // collision or all targets reached (a true end of the MDP)
  bool truncated = false;   // time limit (bootstrap from the value of the last observation)
  AuvStepEvents events;
  // The three terms before weighting.
  double r_collision = 0.0, r_goal = 0.0, r_progress = 0.0, r_clearance = 0.0;
};

struct AuvEpisodeStats {
  int targets_reached = 0;
  bool collided = false;
  bool success = false;  // every target reached
  bool truncated = false;
  long steps = 0;
  double time_s = 0.0;
  double episode_return = 0.0;
  double min_clearance_m = 0.0;
  long nonfinite_actions = 0;  // action elements replaced by 0 because they were NaN or inf
  int random_obstacles = 0;
  long mapped_returns = 0;       // RouteMap::kChartAndSonar: points the sonar map gained (one per grid cell)
  int first_target = 0;          // index of the target the episode started with
  bool exploring_start = false;  // started anywhere in the arena (training only, set_exploring_starts)
};

class AuvNavTask {
 public:
  // Checks that every observation signal and action command of the IO layout exists.
  static Result<AuvNavTask> Create(const AuvTaskConfig& config);

  int observation_size() const noexcept { return static_cast<int>(obs_size_); }
  int action_size() const noexcept { return 2; }
  const robot::IoLayout& io_layout() const noexcept { return config_.io; }
  std::uint64_t io_layout_hash() const noexcept { return io_hash_; }
  double control_period_s() const noexcept { return config_.plant.control_period_s; }
  long max_episode_steps() const noexcept { return max_steps_; }

  // New episode from `seed`: random start pose in the start region, random extra obstacles.
  // Writes the first observation (observation_size() floats).
  void Reset(std::uint64_t seed, float* obs);
  // Training only: with this probability an episode starts anywhere in the free part of the
  // arena (clearance >= l_safe + 1 m, away from its first target), with a random heading and a
  // random current target (the earlier ones count as visited), instead of in the layout's start
  // region. Exploring starts give later legs as much experience as the first. 0 (the default,
  // and what evaluation and the HIL use) leaves Reset's random sequence exactly as without it.
  void set_exploring_starts(double probability) noexcept { exploring_starts_ = probability; }
  // One control period with action [v, w] in policy units (mapped through the IO layout).
  // After the episode has ended, returns zero reward with the same end flags until Reset.
  AuvStepResult Step(const float* action, float* obs);
  // One control period with a physical command: surge speed (m/s) and yaw rate (rad/s), as a
  // controller sends them over DDS (the HIL simulator). No IO-layout mapping; the plant clamps
  // to its controller's limits; non-finite values are replaced by 0 and counted in
  // stats().nonfinite_actions. Step(action) maps the action through the IO layout, then calls this.
  AuvStepResult StepCommand(double surge_speed_mps, double yaw_rate_radps, float* obs);
  // The vehicle's current state as the sensor sample the HIL publishes, in the robot model's
  // fields (config().fields; the others are left alone), as the vehicle reports them: tick
  // (control periods since Reset), pose (yaw wrapped to (-pi, pi]), body velocities, sonar ranges
  // (in single precision, as its sample carries them), the current target, the route's bearing,
  // clearance, flags (episode_end: the episode has ended).
  void FillSensorFields(std::span<double> fields) const;
  const AuvTaskConfig& config() const noexcept { return config_; }

  const AuvEpisodeStats& stats() const noexcept { return stats_; }
  const AuvState& vehicle() const noexcept { return plant_.State(); }
  const World2d& world() const noexcept { return world_; }
  int target_index() const noexcept { return target_; }
  // Physics steps since construction (the plant's counter restarts at every Reset).
  std::uint64_t physics_steps() const noexcept { return physics_steps_ + plant_.physics_steps(); }
  const std::vector<double>& sonar_ranges() const noexcept { return sonar_; }
  // Physical commands of the last step (after the IO layout's scale, offset and limits).
  double commanded_speed_mps() const noexcept { return v_cmd_; }
  double commanded_yaw_rate_radps() const noexcept { return w_cmd_; }
  // The names of every signal an IO layout may use.
  const std::vector<std::string>& SignalNames() const noexcept { return config_.signals.names(); }

 private:
  AuvNavTask(const AuvTaskConfig& config, AuvPlant plant);
  void PlaceRandomObstacles(Rng& rng);
  void ExploringStart(Rng& rng, AuvPose& pose);
  void Measure();     // sonar, l_AT, phi, clearance, route from the plant's state
  void MapReturns();  // RouteMap::kChartAndSonar: add the sonar's new uncharted returns to the route map
  // The observation of the current state (episode_end: done_), history restarted when `first`.
  void WriteObservation(bool first, float* obs);

  AuvTaskConfig config_;
  AuvPlant plant_;
  std::uint64_t io_hash_ = 0;
  std::uint32_t obs_size_ = 0;
  long max_steps_ = 0;
  robot::ObservationBuilder observe_;
  robot::ActionMapper act_;
  std::array<int, 2> action_of_;  // action index of surge_speed and yaw_rate
  std::vector<double> fields_;    // the robot model's fields (AuvTaskConfig::fields)
  std::vector<double> signals_;   // config_.signals order
  std::vector<float> last_action_;
  std::vector<float> last_obs_;
  std::vector<double> sonar_;
  World2d world_;
  int target_ = 0;
  std::uint64_t physics_steps_ = 0;  // of finished episodes
  double l_at_ = 0.0, phi_at_ = 0.0, clearance_ = 0.0;
  // Geodesic progress: the field of the current target (computed when the target changes) and
  // r_e's distance and bearing; equal to l_at_ and phi_at_ in euclidean mode.
  std::optional<GeodesicField> geodesic_;
  int geodesic_target_ = -1;
  double progress_l_ = 0.0, progress_phi_ = 0.0;
  // The route signal: the path to the current target (route_target_; -1: replan) over the chart
  // (chart_: its clearances, computed once) plus, with RouteMap::kChartAndSonar, the points of the
  // sonar map (mapped_: per grid cell, whether a return there is in the map; rays_: the last
  // scan's per-ray ranges), replanned when the target or the map changes; route_phi_ is its
  // bearing relative to the heading (phi_at_ where there is no path).
  std::optional<GeodesicField> chart_;
  std::optional<GeodesicField> route_;
  int route_target_ = -1;
  std::vector<double> rays_;
  std::vector<std::uint8_t> mapped_;
  double route_phi_ = 0.0;
  double v_cmd_ = 0.0, w_cmd_ = 0.0;
  bool done_ = false, terminated_ = false, truncated_ = false;
  double exploring_starts_ = 0.0;
  AuvEpisodeStats stats_;
};

// Drives the task with actions drawn uniformly from [-1, 1] for `steps` control steps; an ended
// episode is reset with the seed *next_seed (then incremented). Returns the episodes ended. For
// benchmarks and tests of the task itself.
long StepRandomly(AuvNavTask& task, Rng& rng, long steps, float* obs, std::uint64_t* next_seed);

}  // namespace pbppo::sim
