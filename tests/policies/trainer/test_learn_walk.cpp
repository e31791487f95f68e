// Pb-PPO learns quadruped-walk on flat ground on a short budget with the shipped recipe's settings
// (tools/train_quadruped.sh: 512 robots x 24 steps, 5 epochs of 3072-sample minibatches, the
// KL-adaptive rate, 128-64-32 ELU, the privileged critic, clip bounds 0.1..0.3): from robots that
// stand or fall to robots that start to follow their commands. The recipe's first stage trains the
// same run 11 times longer; this is its beginning, step for step (same seed, same thread count).
// Label `learning` (not `unit`): 1.9 M environment steps, too long for the sanitizer builds.
#include <doctest/doctest.h>

#include <filesystem>

#include "policies/trainer/clip_schedule.hpp"
#include "policies/trainer/trainer.hpp"
#include "runtime/policy/policy_model.hpp"
#include "tests/support/test_paths.hpp"
#include "tests/support/train_options.hpp"

namespace pbppo::trainer {
namespace {

TEST_CASE("Pb-PPO learns quadruped-walk on flat ground on a short budget - return up, tracking errors down") {
  TrainOptions c = test::ForEnv("quadruped-walk");
  c.env.flags["terrain"] = "flat";
  c.num_envs = 512;
  c.rollout_steps = 24;
  c.minibatch = 3072;
  c.epochs = 5;
  c.learning_rate = 1e-3;
  c.lr_schedule.kind = LrSchedule::Kind::kAdaptive;
  c.lr_schedule.desired_kl = 0.01;
  c.ent_coef = 0.01;
  c.vf_coef = 1.0;
  c.clip_vf = 0.2;
  c.max_grad_norm = 1.0;
  c.schedule = test::Schedule("pbppo", "0.1:0.3:5");
  c.schedule.feedback = FeedbackSource::kRollout;
  c.policy_hidden = {128, 64, 32};
  c.activation = policy::Activation::kElu;
  c.threads = 2;
  c.total_steps = 151 * 12288;  // 151 iterations of 512 x 24 steps, the recipe's first 151
  c.seed = 1;
  const std::filesystem::path dir = test::ScratchDir("learn_walk");
  const TrainResult r = test::TrainInto(c, dir);
  REQUIRE(r.iterations.size() > 100);

  // The first iterations' episodes (those that end early: falls) against the last 100 episodes.
  const IterationStats& early = r.iterations[10];
  const IterationStats& last = r.iterations.back();
  MESSAGE("return (last 100 episodes) " << early.train_return_100 << " -> " << last.train_return_100 << "; |error| vx "
                                        << early.tracking_error_100[0] << " -> " << last.tracking_error_100[0]
                                        << ", vy " << early.tracking_error_100[1] << " -> "
                                        << last.tracking_error_100[1] << ", yaw rate " << early.tracking_error_100[2]
                                        << " -> " << last.tracking_error_100[2]);
  // At the start the robots mostly stand: each axis's error is about the mean |command|. Walking in
  // the command's direction brings the three down together (vx last: the robot first learns to
  // turn and to step sideways).
  const auto mean_error = [](const IterationStats& s) {
    return (s.tracking_error_100[0] + s.tracking_error_100[1] + s.tracking_error_100[2]) / 3.0;
  };
  CHECK(early.train_return_100 < 0.05);
  CHECK(last.train_return_100 > 0.3);
  CHECK(mean_error(last) < 0.85 * mean_error(early));
  for (int axis = 0; axis < 3; ++axis) {
    CAPTURE(axis);
    CHECK(last.tracking_error_100[static_cast<std::size_t>(axis)] <
          early.tracking_error_100[static_cast<std::size_t>(axis)]);
  }
  // The blob holds the actor alone: the 45 deployable inputs, 12 joint targets.
  auto model = policy::PolicyModel::FromFile((dir / "policy.blob").string());
  REQUIRE_MESSAGE(model.ok(), model.error().message);
  CHECK(model->input_size() == 45);
  CHECK(model->output_size() == 12);
}

}  // namespace
}  // namespace pbppo::trainer
