// The auv-nav training environment: the AUV task behind the Env interface, with the IO layout's
// action map, layouts by name, mixed layouts, clones and episode information.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "policies/envs/auv_nav.hpp"
#include "tests/support/refusal.hpp"

namespace pbppo::envs {
namespace {

// MakeEnv with `o` for the environment `name`.
Result<std::unique_ptr<Env>> MakeNamed(const std::string& name, EnvOptions o) {
  o.name = name;
  return MakeEnv(o);
}

std::unique_ptr<Env> Make(const std::string& layout) {
  EnvOptions o;
  o.flags["layout"] = layout;
  auto env = MakeNamed("auv-nav", o);
  REQUIRE_MESSAGE(env.ok(), env.error().message);
  return std::move(env).value();
}

// Index of the observation element `name` of the env's IO layout (models/auv/io_layout.yaml).
std::size_t Input(const Env& env, const std::string& name) {
  const auto names = env.layout().ObservationNames();
  const auto it = std::find(names.begin(), names.end(), name);
  REQUIRE_MESSAGE(it != names.end(), "no observation element '" << name << "'");
  return static_cast<std::size_t>(it - names.begin());
}

// Makes auv-nav with `o` and resets it 40 times from `seed`, handing each episode's task
// configuration to `check`; the layouts the episodes drew.
std::set<std::string> CheckEpisodeConfigs(const EnvOptions& o, std::uint64_t seed,
                                          const std::function<void(const sim::AuvTaskConfig&)>& check) {
  auto made = MakeNamed("auv-nav", o);
  REQUIRE_MESSAGE(made.ok(), made.error().message);
  auto* auv = dynamic_cast<AuvNav*>(made->get());
  REQUIRE(auv != nullptr);
  Rng rng(seed);
  std::vector<float> obs((*made)->observation_size());
  std::set<std::string> seen;
  for (int i = 0; i < 40; ++i) {
    (*made)->Reset(rng, obs);
    CAPTURE(auv->config().layout.name);
    check(auv->config());
    seen.insert(auv->config().layout.name);
  }
  return seen;
}

// Options on the mixed layout (each episode draws easy, medium or hard) with `flags` besides.
EnvOptions Mixed(std::map<std::string, std::string> flags) {
  EnvOptions o;
  o.flags = std::move(flags);
  o.flags["layout"] = "mixed";
  return o;
}

// auv-nav made with `o` and --FLAG VALUE is refused with "--FLAG: MESSAGE", for each (VALUE, MESSAGE).
void CheckRefusals(EnvOptions o, const std::string& flag,
                   const std::vector<std::pair<std::string, std::string>>& value_messages) {
  for (const auto& [value, message] : value_messages) {
    CAPTURE(value);
    o.flags[flag] = value;
    CHECK(test::RefusalOf(MakeNamed("auv-nav", o)) == "--" + flag + ": " + message);
  }
}

// The same episode (seed 9) on the hard layout driven straight ahead for up to `steps` steps in
// auv-nav made with `with` and with `with` less the flag `flag`: the observations agree at every
// step (the flag changes the reward only); returns the two returns, each step's reward pair
// handed to `step_check`.
std::pair<double, double> SameEpisodeReturns(EnvOptions with, const std::string& flag, int steps,
                                             const std::function<void(double, double)>& step_check = {}) {
  with.flags["layout"] = "hard";
  EnvOptions without = with;
  without.flags.erase(flag);
  auto a = MakeNamed("auv-nav", with);
  auto b = MakeNamed("auv-nav", without);
  REQUIRE(a.ok());
  REQUIRE(b.ok());
  Rng r1(9), r2(9);
  std::vector<float> o1((*a)->observation_size()), o2(o1.size());
  (*a)->Reset(r1, o1);
  (*b)->Reset(r2, o2);
  const std::vector<float> ahead{1.0f, 0.0f};
  std::pair<double, double> sums{0.0, 0.0};
  for (int k = 0; k < steps; ++k) {
    const auto ra = (*a)->Step(ahead, o1);
    const auto rb = (*b)->Step(ahead, o2);
    sums.first += ra.reward;
    sums.second += rb.reward;
    CHECK(o1 == o2);
    if (step_check) step_check(ra.reward, rb.reward);
    if (ra.terminated || ra.truncated) break;
  }
  return sums;
}

TEST_CASE("auv-nav has the IO layout's sizes, names and policy-unit action bounds") {
  auto env = Make("hard");
  CHECK(env->name() == "auv-nav:hard");
  CHECK(env->observation_size() == env->layout().observation_size());
  CHECK(env->observation_size() == 24);
  CHECK(env->action_size() == 2);
  CHECK(env->action_low()[0] == -1.f);
  CHECK(env->action_high()[1] == 1.f);
  CHECK(env->max_episode_steps() == 2000);
  CHECK(env->layout().robot == "auv");
}

TEST_CASE("actions in policy units are mapped through the layout to speed commands") {
  auto env = Make("easy");
  auto* auv = dynamic_cast<AuvNav*>(env.get());
  REQUIRE(auv != nullptr);
  Rng rng(3);
  std::vector<float> obs(env->observation_size());
  env->Reset(rng, obs);
  const float full[2] = {1.f, -1.f};
  env->Step(full, obs);
  CHECK(auv->task().commanded_speed_mps() == doctest::Approx(1.5));
  CHECK(auv->task().commanded_yaw_rate_radps() == doctest::Approx(-0.5));
  const float beyond[2] = {7.f, 0.5f};  // clipped to the action box first
  env->Step(beyond, obs);
  CHECK(auv->task().commanded_speed_mps() == doctest::Approx(1.5));
  CHECK(auv->task().commanded_yaw_rate_radps() == doctest::Approx(0.25));
  const float stop[2] = {-1.f, 0.f};
  env->Step(stop, obs);
  CHECK(auv->task().commanded_speed_mps() == doctest::Approx(0.0));
  // Accelerating forward for 2 s shows up in the surge-speed observation.
  for (int i = 0; i < 20; ++i) env->Step(full, obs);
  CHECK(obs[Input(*env, "surge_speed")] > 0.3f);
}

TEST_CASE("same rng gives the same episode - clones are independent instances") {
  auto a = Make("medium");
  auto b = a->Clone();
  Rng ra(11), rb(11);
  std::vector<float> oa(a->observation_size()), ob(b->observation_size());
  a->Reset(ra, oa);
  b->Reset(rb, ob);
  CHECK(oa == ob);
  Rng noise(5);
  double ret_a = 0, ret_b = 0;
  for (int t = 0; t < 300; ++t) {
    const float act[2] = {static_cast<float>(noise.Uniform(-1, 1)), static_cast<float>(noise.Uniform(-1, 1))};
    const StepResult x = a->Step(act, oa);
    const StepResult y = b->Step(act, ob);
    ret_a += x.reward;
    ret_b += y.reward;
    REQUIRE(oa == ob);
    REQUIRE(x.terminated == y.terminated);
    if (x.terminated || x.truncated) break;
  }
  CHECK(ret_a == ret_b);
}

TEST_CASE("driving into an obstacle ends the episode as a collision - the info says so") {
  auto env = Make("easy");
  Rng rng(2);
  std::vector<float> obs(env->observation_size());
  env->Reset(rng, obs);
  CHECK(env->episode_info().available);
  CHECK_FALSE(env->episode_info().success);
  StepResult r;
  const float circle[2] = {1.f, 0.15f};  // a wide full-speed circle ends on a wall or an obstacle
  int steps = 0;
  for (; steps < 2000; ++steps) {
    r = env->Step(circle, obs);
    if (r.terminated || r.truncated) break;
  }
  REQUIRE(r.terminated);
  CHECK(env->episode_info().failure);
  CHECK(r.reward < -400);
  CHECK(obs[Input(*env, "episode_end")] == 1.f);  // chi
}

TEST_CASE("layout 'mixed' draws every layout - unknown layouts are refused by name") {
  auto env = Make("mixed");
  auto* auv = dynamic_cast<AuvNav*>(env.get());
  Rng rng(9);
  std::vector<float> obs(env->observation_size());
  std::set<std::string> seen;
  for (int i = 0; i < 30; ++i) {
    env->Reset(rng, obs);
    seen.insert(auv->config().layout.name);
  }
  CHECK(seen.size() == 3);
  EnvOptions o;
  o.flags["layout"] = "labyrinth";
  CHECK(test::RefusalOf(MakeNamed("auv-nav", o)).find("--layout: 'labyrinth' unknown") != std::string::npos);
}

TEST_CASE("auv-nav: --geodesic-margin sets the margin in every layout, bad values are refused naming the part") {
  EnvOptions o = Mixed({{"progress", "geodesic"}, {"geodesic-margin", "2:4"}});
  CHECK(CheckEpisodeConfigs(o, 5, [](const sim::AuvTaskConfig& cfg) {
          CHECK(cfg.task.geodesic_margin_m == 2.0);
          CHECK(cfg.task.geodesic_margin_cost == 4.0);
        }).size() == 3);
  // The same episode earns a different progress reward with the margin (the path and its length
  // change) and the same observations (the reward only).
  const auto [sum_with, sum_without] = SameEpisodeReturns(o, "geodesic-margin", 30);
  CHECK(sum_with != sum_without);
  CheckRefusals(o, "geodesic-margin",
                {{"2", "'2' is not DISTANCE_M:COST (e.g. 2:4)"},
                 {"2:", "'2:': cost '' is not a number in [0, 100]"},
                 {"x:4", "'x:4': distance 'x' is not a number in [0, 100]"},
                 {"2:-1", "'2:-1': cost '-1' is not a number in [0, 100]"},
                 {"2:4:1", "'2:4:1': cost '4:1' is not a number in [0, 100]"},
                 {"nan:4", "'nan:4': distance 'nan' is not a number in [0, 100]"}});
  CHECK(test::RefusalOf(MakeNamed("pendulum", o)) == "--geodesic-margin: only auv-nav has one, not 'pendulum'");
}

TEST_CASE("auv-nav: --clearance-penalty sets the clearance term in every layout, bad values are refused") {
  EnvOptions o = Mixed({{"clearance-penalty", "1.5:0.75"}});
  CHECK(CheckEpisodeConfigs(o, 5, [](const sim::AuvTaskConfig& cfg) {
          CHECK(cfg.task.clearance_penalty_m == 1.5);
          CHECK(cfg.task.clearance_penalty_per_step == 0.75);
        }).size() == 3);
  // Straight ahead from the hard start runs along the bottom wall or into the first circle: the
  // same observations, less reward once inside the band.
  const auto [sum_with, sum_without] =
      SameEpisodeReturns(o, "clearance-penalty", 200, [](double with, double plain) { CHECK(with <= plain); });
  CHECK(sum_with < sum_without);
  o.flags["clearance-penalty"] = "1.5:1";
  CHECK(test::RefusalOf(MakeNamed("pendulum", o)) == "--clearance-penalty: only auv-nav has one, not 'pendulum'");
  CheckRefusals(o, "clearance-penalty",
                {{"1.5", "'1.5' is not DISTANCE_M:PER_STEP (e.g. 1.5:1)"},
                 {"1.5:", "'1.5:': per-step cost '' is not a number in [0, 100]"},
                 {"-1:1", "'-1:1': distance '-1' is not a number in [0, 100]"},
                 {"1.5:inf", "'1.5:inf': per-step cost 'inf' is not a number in [0, 100]"}});
}

TEST_CASE("auv-nav: --extra-obstacles draws more random obstacles per episode in every layout") {
  // Mean random obstacles placed over 40 episodes per layout, without and with 3 extra.
  auto placed = [](int extra) {
    EnvOptions o = Mixed({{"extra-obstacles", std::to_string(extra)}});
    auto made = MakeNamed("auv-nav", o);
    REQUIRE_MESSAGE(made.ok(), made.error().message);
    auto* auv = dynamic_cast<AuvNav*>(made->get());
    REQUIRE(auv != nullptr);
    Rng rng(21);
    std::vector<float> obs((*made)->observation_size());
    std::map<std::string, double> mean;
    std::map<std::string, int> episodes;
    for (int i = 0; i < 120; ++i) {
      (*made)->Reset(rng, obs);
      const auto& cfg = auv->config();
      const auto& count = cfg.layout.random_obstacles.count;
      const int n = auv->task().stats().random_obstacles;
      CHECK(n <= count[1]);
      CHECK(static_cast<int>(auv->task().world().circles.size()) ==
            static_cast<int>(cfg.layout.world.circles.size()) + n);
      mean[cfg.layout.name] += n;
      episodes[cfg.layout.name] += 1;
    }
    for (auto& [name, m] : mean) m /= episodes[name];
    return mean;
  };
  const auto plain = placed(0), more = placed(3);
  for (const char* layout : {"easy", "medium", "hard"}) {
    CAPTURE(layout);
    CHECK(more.at(layout) > plain.at(layout) + 2.0);  // 3 more asked; a crowded layout may fit fewer
  }
  EnvOptions o;
  o.flags["extra-obstacles"] = "17";
  CHECK(test::RefusalOf(MakeNamed("auv-nav", o)) == "--extra-obstacles: 17 is not in [0, 16]");
  // insert_or_assign, not `= "1"`: GCC 12 warns (-Wrestrict) wrongly on that assignment here
  o.flags.insert_or_assign("extra-obstacles", std::string("1"));
  CHECK(test::RefusalOf(MakeNamed("pendulum", o)) == "--extra-obstacles: only auv-nav has obstacles, not 'pendulum'");
}

TEST_CASE("auv-nav: --progress replaces auv.yaml's progress term in every layout, bad names are refused") {
  EnvOptions o = Mixed({{"progress", "geodesic"}});
  CHECK(CheckEpisodeConfigs(o, 3, [](const sim::AuvTaskConfig& cfg) {
          CHECK(cfg.task.progress == sim::AuvTaskParams::Progress::kGeodesic);
        }).size() == 3);
  o.flags.erase("progress");
  auto plain = MakeNamed("auv-nav", o);
  REQUIRE(plain.ok());
  CHECK(dynamic_cast<AuvNav*>(plain->get())->config().task.progress == sim::AuvTaskParams::Progress::kEuclidean);
  o.flags["progress"] = "manhattan";
  CHECK(test::RefusalOf(MakeNamed("auv-nav", o)) ==
        "--progress: 'manhattan': unknown (euclidean, geodesic, or LAYOUT=MODE,...)");
  // Per layout: the named layouts take the mode, the others keep auv.yaml's.
  o.flags["progress"] = "hard=geodesic";
  CHECK(CheckEpisodeConfigs(o, 4, [](const sim::AuvTaskConfig& cfg) {
          CHECK(cfg.task.progress == (cfg.layout.name == "hard" ? sim::AuvTaskParams::Progress::kGeodesic
                                                                : sim::AuvTaskParams::Progress::kEuclidean));
        }).size() == 3);
  for (const auto& [spec, message] : std::vector<std::pair<std::string, std::string>>{
           {"hard=geodesic,deep=geodesic", "'hard=geodesic,deep=geodesic': layout 'deep' unknown (easy, medium, hard)"},
           {"hard=geodesic,hard=euclidean", "'hard=geodesic,hard=euclidean': layout 'hard' given twice"},
           {"hard=bee-line", "'hard=bee-line': 'bee-line' for hard is not euclidean or geodesic"},
           {"hard=geodesic,", "'hard=geodesic,': '' is not LAYOUT=MODE"},
           {"medium=euclidean,geodesic", "'medium=euclidean,geodesic': 'geodesic' is not LAYOUT=MODE"}}) {
    CAPTURE(spec);
    o.flags["progress"] = spec;
    CHECK(test::RefusalOf(MakeNamed("auv-nav", o)) == "--progress: " + message);
    CHECK(AuvNav::ProgressFor(spec, "hard").error().message == message);
  }
  CHECK(*AuvNav::ProgressFor("easy=geodesic,medium=euclidean", "easy").value() ==
        sim::AuvTaskParams::Progress::kGeodesic);
  CHECK(*AuvNav::ProgressFor("easy=geodesic,medium=euclidean", "medium").value() ==
        sim::AuvTaskParams::Progress::kEuclidean);
  CHECK_FALSE(AuvNav::ProgressFor("easy=geodesic,medium=euclidean", "hard").value().has_value());
  o.flags["progress"] = "geodesic";
  o.flags.erase("layout");
  CHECK(test::RefusalOf(MakeNamed("pendulum", o)).find("only auv-nav has a progress term") != std::string::npos);
}

TEST_CASE("exploring starts: anywhere free, any current target - success counted only from the layout's start") {
  EnvOptions o;
  o.flags["layout"] = "hard";
  o.flags["exploring-starts"] = "1";
  auto made = MakeNamed("auv-nav", o);
  REQUIRE(made.ok());
  auto env = std::move(made).value();
  auto clone = env->Clone();  // clones keep the setting
  auto* auv = dynamic_cast<AuvNav*>(clone.get());
  REQUIRE(auv != nullptr);
  Rng rng(21);
  std::vector<float> obs(clone->observation_size());
  std::set<int> targets;
  double x_min = 1e9, x_max = -1e9, y_min = 1e9, y_max = -1e9;
  for (int i = 0; i < 60; ++i) {
    clone->Reset(rng, obs);
    const auto& t = auv->task();
    CHECK(t.stats().exploring_start);
    CHECK_FALSE(clone->episode_info().available);
    CHECK(t.stats().targets_reached == t.target_index());
    targets.insert(t.target_index());
    x_min = std::min(x_min, t.vehicle().x_m);
    x_max = std::max(x_max, t.vehicle().x_m);
    y_min = std::min(y_min, t.vehicle().y_m);
    y_max = std::max(y_max, t.vehicle().y_m);
    // Free space: clear of every obstacle by more than l_safe.
    CHECK(t.stats().min_clearance_m >= auv->config().task.safe_distance_m + 1.0 - 1e-9);
  }
  CHECK(targets.size() == 3);
  // All three corridors of the hard layout (y 0-14, 16-24, 26-40) and both halves in x.
  CHECK(y_min < 14.0);
  CHECK(y_max > 26.0);
  CHECK(x_min < 15.0);
  CHECK(x_max > 25.0);

  // The default (0) keeps the layout's start region and the random sequence of before.
  auto plain = Make("hard");
  auto* p = dynamic_cast<AuvNav*>(plain.get());
  Rng r1(21);
  plain->Reset(r1, obs);
  CHECK_FALSE(p->task().stats().exploring_start);
  CHECK(p->task().target_index() == 0);
  CHECK(p->task().vehicle().x_m <= 5.0);
  CHECK(plain->episode_info().available);
}

}  // namespace
}  // namespace pbppo::envs
