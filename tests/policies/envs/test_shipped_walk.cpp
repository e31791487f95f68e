// The shipped quadruped walking policies still meet their figures: the paper's test (50 robots x
// 20 s, commands vx, vy in [-1, 1] m/s and a heading in [-pi, pi], nominal robots with
// observation noise) through the runtime's Forward, and their golden vectors reproduce.
//   flat.blob   on flat ground: mean |error| <= 0.15 m/s in vx and vy, <= 0.15 rad/s in yaw rate,
//               no fall; on the 1:1 mix of flat ground and blocks at most 2 falls of 50
//   mixed.blob  on the 1:1 mix of flat ground and blocks: at most 2 falls of 50; on flat ground
//               the same tracking figures as the flat policy
//   go2_walk/flat.blob  (the Unitree Go2) on flat ground: the same tracking figures on the test's
//               two seeds, at most 1 fall of 50 (seed 7: one robot tips over 1.4 s into its
//               episode, turning on the spot from the start's random pose and velocity; seed 8:
//               none)
// Label `shipped` (not `unit`): it runs 300 robot-episodes, too long for the sanitizer builds.
#include <doctest/doctest.h>

#include <cmath>
#include <string>

#include "policies/envs/walk_eval.hpp"
#include "runtime/policy/reference.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;

namespace {

const std::string kDir = "policies/frozen/quadruped_walk/";
const std::string kGo2Dir = "policies/frozen/go2_walk/";

// The report's figures are the portable kernel's: the same on every machine. The AVX-512 kernel
// rounds differently, and 20 s on blocks turns that into other robots falling (mixed.blob, seed 7:
// 4 of 50 where the portable kernel gives 2; the folder's README).
envs::WalkEvalResult Test(const std::string& blob, const std::string& terrain, std::uint64_t seed,
                          const std::string& robot = "quadruped", const std::string& dir = kDir) {
  policy::LoadOptions load;
  load.kernel = policy::Kernel::kPortable;
  auto model = policy::PolicyModel::FromFile(test::SourcePath(dir + blob), load);
  REQUIRE_MESSAGE(model.ok(), model.error().message);
  envs::QuadrupedWalkOptions o;
  o.models_dir = test::SourcePath("models");
  o.robot = robot;
  o.terrain = terrain;
  o.randomize = false;
  o.paper_test = true;
  auto env = envs::QuadrupedWalk::Make(o);
  REQUIRE_MESSAGE(env.ok(), env.error().message);
  envs::WalkEvalOptions eo;
  eo.seed = seed;
  auto r = envs::EvaluateWalk(*model, **env, eo);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  MESSAGE(robot << " " << blob << " on " << terrain << ", seed " << seed << ": |error| vx " << r->mean_abs_error[0]
                << " vy " << r->mean_abs_error[1] << " yaw rate " << r->mean_abs_error[2] << ", falls " << r->falls
                << " (on blocks " << r->falls_on_blocks << " of " << r->robots_on_blocks << ")");
  CHECK(r->robots == 50);
  CHECK(r->forward_problems == 0);
  return *r;
}

void CheckTracking(const envs::WalkEvalResult& r) {
  CHECK(r.mean_abs_error[0] <= 0.15);
  CHECK(r.mean_abs_error[1] <= 0.15);
  CHECK(r.mean_abs_error[2] <= 0.15);
}

}  // namespace

TEST_CASE("shipped walking policies: golden vectors reproduce through the runtime's Forward") {
  for (const std::string& name : {kDir + "flat", kDir + "mixed", kGo2Dir + "flat"}) {
    CAPTURE(name);
    const std::string blob = test::SourcePath(name + ".blob");
    auto model = policy::PolicyModel::FromFile(blob);
    REQUIRE_MESSAGE(model.ok(), model.error().message);
    auto g = policy::ReadGoldenFile(policy::GoldenPathFor(blob));
    REQUIRE_MESSAGE(g.ok(), g.error().message);
    auto data = policy::MakePolicyData(*model);
    REQUIRE(data.ok());
    REQUIRE(g->observations.size() >= 16);
    for (std::size_t row = 0; row < g->observations.size(); ++row) {
      std::copy(g->observations[row].begin(), g->observations[row].end(), data->observation().begin());
      REQUIRE(policy::Forward(*model, *data) == policy::ForwardStatus::kOk);
      for (std::size_t j = 0; j < g->expected[row].action.size(); ++j)
        CHECK(std::fabs(data->action()[j] - g->expected[row].action[j]) <= g->expected[row].error_bound[j]);
    }
  }
}

TEST_CASE(
    "shipped flat policy: the paper's test on flat ground - tracking within 0.15, no fall, on blocks <= 2 of 50") {
  const auto r = Test("flat.blob", "flat", 7);
  CheckTracking(r);
  CHECK(r.falls == 0);
  const auto mixed = Test("flat.blob", "mixed", 7);
  CHECK(mixed.robots_on_blocks > 15);
  CHECK(mixed.falls <= 2);
}

TEST_CASE("shipped mixed policy: the paper's test on flat ground and blocks - at most 2 falls of 50") {
  const auto mixed = Test("mixed.blob", "mixed", 7);
  CHECK(mixed.robots_on_blocks > 15);
  CHECK(mixed.falls <= 2);
  const auto flat = Test("mixed.blob", "flat", 7);
  CheckTracking(flat);
  CHECK(flat.falls == 0);
}

TEST_CASE("shipped Go2 policy: the paper's test on flat ground - tracking within 0.15, at most 1 fall of 50") {
  for (const std::uint64_t seed : {7u, 8u}) {
    const auto r = Test("flat.blob", "flat", seed, "go2", kGo2Dir);
    CheckTracking(r);
    CHECK(r.falls <= 1);
  }
}

TEST_CASE("shipped flat policy in MuJoCo on a held velocity schedule - the command observed, tracked, no fall") {
  auto model = policy::PolicyModel::FromFile(test::SourcePath(kDir + "flat.blob"));
  REQUIRE_MESSAGE(model.ok(), model.error().message);
  envs::QuadrupedWalkOptions o;
  o.models_dir = test::SourcePath("models");
  o.randomize = false;
  auto env = envs::QuadrupedWalk::Make(o);
  REQUIRE_MESSAGE(env.ok(), env.error().message);
  const std::vector<envs::WalkSchedulePhase> phases = {{"stand", 0.0, 2.0, {0, 0, 0}},
                                                       {"forward", 2.0, 4.0, {0.5, 0, 0}}};
  auto r = envs::EvaluateWalkSchedule(*model, **env, phases, 1.0, 7);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  CHECK_FALSE(r->fell);
  REQUIRE(r->phases.size() == 2);
  CHECK(r->phases[1].samples == 150);  // 3 s after settling, 50 Hz
  CHECK(r->phases[1].mean_abs_error[0] <= 0.2);
  CHECK(r->phases[1].mean_measured[0] > 0.3);
  // The environment held the schedule's command: no draw, no heading controller.
  for (const envs::WalkTelemetry& t : r->trace) {
    CHECK(t.command[0] == (t.time_s < 2.0 - 1e-9 ? 0.0 : 0.5));  // the command observed for the next step
    CHECK(t.command[2] == 0.0);
  }
  // A schedule longer than an episode is refused, naming both lengths.
  auto too_long = envs::EvaluateWalkSchedule(*model, **env, {{"long", 0.0, 25.0, {0, 0, 0}}}, 1.0, 7);
  REQUIRE_FALSE(too_long.ok());
  CHECK(too_long.error().message.find("longer than an episode") != std::string::npos);
}
