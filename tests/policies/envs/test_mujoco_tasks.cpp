// The MuJoCo locomotion tasks: our models against the standard tasks' published figures (sizes,
// time steps, masses), the v3 reward and termination rules, determinism, and bad model files.
#include <doctest/doctest.h>

#include <mujoco/mujoco.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "policies/envs/mujoco_tasks.hpp"
#include "tests/support/test_paths.hpp"

namespace pbppo::envs {
namespace {

std::unique_ptr<MujocoTask> Make(const std::string& name, const std::string& models = "") {
  auto env = MujocoTask::Make(*FindMujocoTask(name), models.empty() ? test::SourcePath("models") : models);
  REQUIRE_MESSAGE(env.ok(), (env ? "" : env.error().message));
  return std::move(env).value();
}

double BodyMass(const MujocoTask& env, const char* body) {
  const mjModel* m = env.model();
  const int id = mj_name2id(m, mjOBJ_BODY, body);
  REQUIRE(id >= 0);
  return m->body_mass[id];
}

TEST_CASE("mujoco tasks: sizes and environment steps are the standard tasks'") {
  struct Want {
    const char* name;
    std::uint32_t obs, act;
    double dt;
  };
  for (const Want& w : {Want{"hopper", 11, 3, 0.008}, Want{"walker2d", 17, 6, 0.008}, Want{"half-cheetah", 17, 6, 0.05},
                        Want{"ant", 111, 8, 0.05}}) {
    CAPTURE(w.name);
    auto env = Make(w.name);
    CHECK(env->observation_size() == w.obs);
    CHECK(env->action_size() == w.act);
    CHECK(env->dt() == doctest::Approx(w.dt).epsilon(1e-12));
    CHECK(env->max_episode_steps() == 1000);
    CHECK(env->layout().observation_size() == w.obs);
  }
}

TEST_CASE("mujoco tasks: masses from our geometry match the published bodies") {
  // The standard Hopper's body masses (kg), as its model's capsules at density 1000 give them.
  auto hopper = Make("hopper");
  CHECK(BodyMass(*hopper, "torso") == doctest::Approx(3.53429174).epsilon(1e-7));
  CHECK(BodyMass(*hopper, "thigh") == doctest::Approx(3.92699082).epsilon(1e-7));
  CHECK(BodyMass(*hopper, "leg") == doctest::Approx(2.71433605).epsilon(1e-7));
  CHECK(BodyMass(*hopper, "foot") == doctest::Approx(5.0893801).epsilon(1e-7));
  // Walker2d: the same torso, thigh and leg, a shorter foot, twice.
  auto walker = Make("walker2d");
  CHECK(BodyMass(*walker, "thigh_left") == doctest::Approx(3.92699082).epsilon(1e-7));
  CHECK(BodyMass(*walker, "foot") == doctest::Approx(BodyMass(*walker, "foot_left")));
  // HalfCheetah: scaled to 14 kg in all.
  auto cheetah = Make("half-cheetah");
  double total = 0;
  for (int b = 0; b < cheetah->model()->nbody; ++b) total += cheetah->model()->body_mass[b];
  CHECK(total == doctest::Approx(14.0).epsilon(1e-9));
}

TEST_CASE("mujoco tasks: same seed, same episode - and a clone continues it bit for bit") {
  for (const auto& name : MujocoTaskNames()) {
    CAPTURE(name);
    auto a = Make(name);
    auto b = Make(name);
    Rng ra(5), rb(5), actions(9);
    std::vector<float> oa(a->observation_size()), ob(b->observation_size()), act(a->action_size());
    a->Reset(ra, oa);
    b->Reset(rb, ob);
    CHECK(oa == ob);
    std::unique_ptr<Env> clone;
    std::vector<float> oc(oa.size());
    for (int t = 0; t < 60; ++t) {
      for (auto& x : act) x = static_cast<float>(actions.Uniform(-1.0, 1.0));
      const auto r1 = a->Step(act, oa);
      const auto r2 = b->Step(act, ob);
      REQUIRE(r1.reward == r2.reward);
      REQUIRE(oa == ob);
      if (t == 20) clone = a->Clone();
      if (clone != nullptr && t > 20) {
        const auto r3 = clone->Step(act, oc);
        REQUIRE(r3.reward == r1.reward);
        REQUIRE(oc == oa);
      }
      if (r1.terminated) break;
    }
  }
}

TEST_CASE("mujoco tasks: the reward is progress + healthy reward - control cost") {
  auto env = Make("hopper");
  Rng rng(1);
  std::vector<float> obs(env->observation_size());
  env->Reset(rng, obs);
  const std::vector<float> act = {0.5f, -0.25f, 2.0f};  // the last is clipped to 1
  const double x0 = env->data()->qpos[0];
  const auto r = env->Step(act, obs);
  const double progress = (env->data()->qpos[0] - x0) / 0.008;
  CHECK(r.reward == doctest::Approx(progress + 1.0 - 1e-3 * (0.25 + 0.0625 + 1.0)).epsilon(1e-12));
  CHECK(env->data()->ctrl[2] == 1.0);

  // HalfCheetah: no healthy reward, control cost 0.1.
  auto cheetah = Make("half-cheetah");
  std::vector<float> o2(cheetah->observation_size());
  cheetah->Reset(rng, o2);
  const double c0 = cheetah->data()->qpos[0];
  const std::vector<float> a2(6, -1.0f);
  const auto r2 = cheetah->Step(a2, o2);
  CHECK(r2.reward == doctest::Approx((cheetah->data()->qpos[0] - c0) / 0.05 - 0.1 * 6).epsilon(1e-12));
}

TEST_CASE("mujoco tasks: termination when unhealthy, truncation at 1000 steps") {
  Rng rng(2);
  // Each task's unhealthy state: one coordinate moved out of its healthy range.
  struct Unhealthy {
    const char* task;
    int qpos;
    double value;
  };
  for (const Unhealthy& u : {Unhealthy{"hopper", 2, 0.3},    // torso pitched beyond 0.2 rad
                             Unhealthy{"walker2d", 1, 0.5},  // torso below 0.8 m
                             Unhealthy{"ant", 2, 1.5}}) {    // torso above 1 m
    CAPTURE(u.task);
    auto env = Make(u.task);
    std::vector<float> obs(env->observation_size()), act(env->action_size(), 0.0f);
    env->Reset(rng, obs);
    CHECK(env->healthy());
    env->data()->qpos[u.qpos] = u.value;
    const auto r = env->Step(act, obs);
    CHECK(r.terminated);
    CHECK(std::isfinite(r.reward));
  }
  SUBCASE("half-cheetah: never terminates; truncated after 1000 steps") {
    auto env = Make("half-cheetah");
    std::vector<float> obs(env->observation_size()), act(6);
    env->Reset(rng, obs);
    int steps = 0;
    StepResult r;
    do {
      for (auto& a : act) a = static_cast<float>(rng.Uniform(-1.0, 1.0));
      r = env->Step(act, obs);
      ++steps;
    } while (!r.terminated && !r.truncated);
    CHECK(steps == 1000);
    CHECK(r.truncated);
    CHECK_FALSE(r.terminated);
  }
}

TEST_CASE("mujoco tasks: observations - root x left out, velocities clipped, ant contact forces") {
  Rng rng(3);
  auto hopper = Make("hopper");
  std::vector<float> obs(hopper->observation_size());
  hopper->Reset(rng, obs);
  CHECK(obs[0] == static_cast<float>(hopper->data()->qpos[1]));  // height first: x is not observed
  CHECK(obs[0] == doctest::Approx(1.25).epsilon(0.01));
  hopper->data()->qvel[3] = 50;
  hopper->Observe(obs);
  CHECK(obs[5 + 3] == 10.0f);

  // The ant standing still: its feet carry it, so some clipped contact force is non-zero.
  auto ant = Make("ant");
  std::vector<float> a(ant->observation_size()), act(8, 0.0f);
  ant->Reset(rng, a);
  for (int t = 0; t < 40; ++t) REQUIRE_FALSE(ant->Step(act, a).terminated);
  double contact = 0;
  for (std::size_t i = 27; i < a.size(); ++i) {
    CHECK(std::fabs(a[i]) <= 1.0f);
    contact += std::fabs(a[i]);
  }
  CHECK(contact > 0.5);
  CHECK(ant->provenance() == "ant");

  // --contact-forces zero (the paper's software): observed as 0 and no contact cost, the same
  // motion otherwise; refused on another task or with another value.
  envs::EnvOptions o;
  o.name = "ant";
  o.models_dir = test::SourcePath("models");
  o.flags["contact-forces"] = "zero";
  auto zero = MakeEnv(o);
  REQUIRE_MESSAGE(zero.ok(), zero.error().message);
  CHECK((*zero)->provenance() == "ant (contact forces zero)");
  Rng r1(5), r2(5);
  std::vector<float> with(a.size()), without(a.size());
  ant->Reset(r1, with);
  (*zero)->Reset(r2, without);
  double reward_with = 0, reward_without = 0;
  for (int t = 0; t < 40; ++t) {
    reward_with += ant->Step(act, with).reward;
    reward_without += (*zero)->Step(act, without).reward;
  }
  for (std::size_t i = 0; i < 27; ++i) CHECK(with[i] == without[i]);
  for (std::size_t i = 27; i < a.size(); ++i) CHECK(without[i] == 0.0f);
  CHECK(reward_without > reward_with);  // the contact cost is gone, nothing else changed
  o.flags["contact-forces"] = "none";
  CHECK(MakeEnv(o).error().message == "--contact-forces: 'none' is not computed or zero");
  o.name = "hopper";
  o.flags["contact-forces"] = "zero";
  CHECK(MakeEnv(o).error().message == "--contact-forces: only ant has contact forces to leave out, not 'hopper'");
}

TEST_CASE("mujoco tasks: a broken model or a layout of the wrong size is refused naming the file") {
  const std::string dir = test::ScratchDir("mujoco_tasks_bad");
  std::filesystem::create_directories(dir + "/hopper");
  std::filesystem::copy_file(test::SourcePath("models/hopper/io_layout.yaml"), dir + "/hopper/io_layout.yaml");
  {
    std::ofstream(dir + "/hopper/hopper.xml") << "<mujoco><worldbody><body></mujoco>";
  }
  auto bad = MujocoTask::Make(*FindMujocoTask("hopper"), dir);
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("hopper/hopper.xml") != std::string::npos);

  // The walker's body with the hopper's layout: sizes disagree.
  std::filesystem::copy_file(test::SourcePath("models/walker2d/walker2d.xml"), dir + "/hopper/hopper.xml",
                             std::filesystem::copy_options::overwrite_existing);
  auto wrong = MujocoTask::Make(*FindMujocoTask("hopper"), dir);
  REQUIRE_FALSE(wrong.ok());
  CHECK(wrong.error().message.find("nq 6") != std::string::npos);

  // The hopper's body with a layout that misses an observation.
  std::filesystem::copy_file(test::SourcePath("models/hopper/hopper.xml"), dir + "/hopper/hopper.xml",
                             std::filesystem::copy_options::overwrite_existing);
  std::ifstream in(test::SourcePath("models/hopper/io_layout.yaml"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto pos = text.find("  - {name: vz");
  text.erase(pos, text.find('\n', pos) - pos + 1);
  std::ofstream(dir + "/hopper/io_layout.yaml") << text;
  auto short_layout = MujocoTask::Make(*FindMujocoTask("hopper"), dir);
  REQUIRE_FALSE(short_layout.ok());
  CHECK(short_layout.error().message.find("io_layout.yaml") != std::string::npos);
  CHECK(short_layout.error().message.find("11 observations") != std::string::npos);
}

TEST_CASE("mujoco tasks: MakeEnv builds them and refuses other environments' flags") {
  EnvOptions o;
  o.name = "walker2d";
  auto env = MakeEnv(o);
  REQUIRE(env.ok());
  CHECK((*env)->name() == "walker2d");
  o.flags["terrain"] = "mixed";
  auto bad = MakeEnv(o);
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("--terrain") != std::string::npos);
}

}  // namespace
}  // namespace pbppo::envs
