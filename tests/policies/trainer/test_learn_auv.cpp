// PPO learns the AUV navigation task (easy layout) on a small budget with a fixed seed: real
// progress from a policy that collides to one that reaches targets, and the blob the trainer
// writes drives the task through the runtime's Forward with the layout's action map.
// Label `learning` (not `unit`): it is too long for the sanitizer builds.
#include <doctest/doctest.h>

#include <filesystem>
#include <vector>

#include "policies/envs/auv_nav.hpp"
#include "policies/trainer/trainer.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/robot/io_layout.hpp"
#include "tests/support/test_paths.hpp"
#include "tests/support/train_options.hpp"

namespace pbppo::trainer {
namespace {

TEST_CASE("PPO learns auv-nav easy on a small budget - the frozen blob reaches targets") {
  TrainOptions c;
  c.env.name = "auv-nav";
  c.env.flags["layout"] = "easy";
  c.num_envs = 16;
  c.rollout_steps = 256;
  c.minibatch = 512;
  c.epochs = 10;
  c.threads = 2;
  c.normalize_observations = true;
  c.scale_rewards = true;
  c.total_steps = 200000;
  c.seed = 1;
  const std::filesystem::path dir = test::ScratchDir("learn_auv");
  const TrainResult r = test::TrainInto(c, dir);
  const double first = r.iterations.front().train_return;
  MESSAGE("first rollout return " << first << ", last-100 return " << r.final_return);
  CHECK(first < -200);             // the initial policy mostly collides
  CHECK(r.final_return > 1000.0);  // real progress: most episodes now collect target rewards (1000 each)

  // The blob on the runtime side: Forward gives commands; map them back to policy units.
  auto model = policy::PolicyModel::FromFile((dir / "policy.blob").string());
  REQUIRE(model.ok());
  auto data = policy::MakePolicyData(model.value());
  REQUIRE(data.ok());
  auto env = envs::MakeEnv(c.env);
  REQUIRE(env.ok());
  REQUIRE(robot::CheckPolicyMatchesLayout(model->description(), (*env)->layout()).ok());
  const auto& spec = model->description();
  Rng rng(777);
  std::vector<float> obs((*env)->observation_size()), act(2);
  int targets = 0;
  for (int ep = 0; ep < 5; ++ep) {
    (*env)->Reset(rng, obs);
    for (;;) {
      std::copy(obs.begin(), obs.end(), data->observation().begin());
      REQUIRE(policy::Forward(model.value(), data.value()) == policy::ForwardStatus::kOk);
      for (std::size_t j = 0; j < 2; ++j) {
        const float u = data->action()[j];
        CHECK(u >= spec.action_low[j]);
        CHECK(u <= spec.action_high[j]);
        act[j] = (u - spec.action_offset[j]) / spec.action_scale[j];
      }
      const envs::StepResult s = (*env)->Step(act, obs);
      if (s.terminated || s.truncated) break;
    }
    targets += (*env)->episode_info().goals;
  }
  MESSAGE("targets reached in 5 deterministic episodes: " << targets);
  CHECK(targets >= 8);  // of 15
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace pbppo::trainer
