// The Pb-PPO paper's quadruped test on our robot: N robots (50 in the paper), each one episode
// of quadruped-walk (20 s, commands drawn from the task's ranges at the start and again at 10 s:
// legged_gym's resampling period, whatever the training used; the caller builds the environment
// with QuadrupedWalkOptions::paper_test) driven by a
// frozen policy through the runtime's Forward, the same arithmetic as the controller. Reports
// the mean absolute tracking error of the body velocity per axis (vx, vy in the base frame, yaw
// rate), over every step and over the steps at least settle_s after a command change, and the
// falls (base contact or tilt), on flat ground and on blocks apart.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "policies/envs/quadruped_walk.hpp"
#include "runtime/core/result.hpp"
#include "runtime/policy/policy_model.hpp"

namespace pbppo::envs {

struct WalkEvalOptions {
  int robots = 50;
  std::uint64_t seed = 7;
  double settle_s = 1.0;
  int trace_robots = 3;  // the first robots' every step, for plots
};

struct WalkFall {
  int robot = 0;
  double time_s = 0;
  std::array<double, 3> command{};  // at the fall
  bool on_blocks = false;
  bool base_contact = false;  // else a tilt beyond the limit
};

struct WalkEvalResult {
  int robots = 0, robots_on_blocks = 0;
  int falls = 0, falls_on_blocks = 0;
  std::array<double, 3> mean_abs_error{};          // vx, vy (m/s), yaw rate (rad/s): every step
  std::array<double, 3> mean_abs_error_settled{};  // the steps at least settle_s after a command change
  std::uint64_t steps = 0, settled_steps = 0, forward_problems = 0;
  double mean_return = 0;
  std::vector<WalkFall> fall_list;
  std::vector<std::vector<WalkTelemetry>> traces;
};

// A velocity command schedule played to one robot in MuJoCo (the HIL's schedules, runtime/loop/
// schedule.hpp, converted by the caller): sim-to-sim on the same commands as the Simbody HIL.
struct WalkSchedulePhase {
  std::string name;
  double start_s = 0, duration_s = 0;
  std::array<double, 3> command{};  // vx, vy (m/s), yaw rate (rad/s)
};

struct WalkSchedulePhaseResult {
  WalkSchedulePhase phase;
  std::array<double, 3> mean_abs_error{};  // the steps at least settle_s into the phase
  std::array<double, 3> mean_measured{};
  std::uint64_t samples = 0;
};

struct WalkScheduleResult {
  std::vector<WalkSchedulePhaseResult> phases;
  bool fell = false;
  double fell_at_s = -1;
  double distance_m = 0;             // the base's path length
  std::vector<WalkTelemetry> trace;  // every policy step
};

// One robot from `seed`'s reset, commanded phase by phase (QuadrupedWalk::HoldCommand) until the
// schedule ends, a fall, or the episode's end; the phases must fit in one episode.
Result<WalkScheduleResult> EvaluateWalkSchedule(const policy::PolicyModel& model, QuadrupedWalk& env,
                                                const std::vector<WalkSchedulePhase>& phases, double settle_s,
                                                std::uint64_t seed);

// Refuses a blob whose IO layout is not the environment's, naming the first difference.
Result<WalkEvalResult> EvaluateWalk(const policy::PolicyModel& model, QuadrupedWalk& env,
                                    const WalkEvalOptions& options);

}  // namespace pbppo::envs
