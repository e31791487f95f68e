// The paper's Pb-PPO (pbppo-paper:wi-ad, six arms 0.02..0.5, two evaluation episodes per iteration)
// learns hopper on a short budget with the paper's PPO settings (one environment, 2048-step
// rollouts, minibatch 64, 10 epochs, 64-64 tanh): from a hopper that falls at once (about 16 per
// episode) to one that hops (tools/mujoco_table.sh trains the same run ten times longer), and the
// bandit's evaluation steps are counted beside the training steps.
// Label `learning` (not `unit`): 10^5 environment steps, too long for the sanitizer builds.
#include <doctest/doctest.h>

#include "policies/trainer/clip_schedule.hpp"
#include "policies/trainer/trainer.hpp"
#include "tests/support/test_paths.hpp"
#include "tests/support/train_options.hpp"

namespace pbppo::trainer {
namespace {

TEST_CASE("Pb-PPO learns hopper on a short budget with the paper's settings - return up, evaluation steps counted") {
  TrainOptions c = test::ForEnv("hopper");
  c.schedule = test::Schedule("pbppo-paper:wi-ad", "0.02:0.5:6");
  c.threads = 1;
  c.total_steps = 50 * 2048;
  c.seed = 1;
  auto r = Train(c);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  REQUIRE(r->iterations.size() == 50);
  const IterationStats& first = r->iterations.front();
  const IterationStats& last = r->iterations.back();
  MESSAGE("return (last 100 episodes) " << first.train_return_100 << " -> " << last.train_return_100 << "; "
                                        << r->eval_steps << " evaluation steps");
  CHECK(first.train_return_100 < 40);
  CHECK(last.train_return_100 > 250);
  CHECK(r->env_steps == 50 * 2048);
  CHECK(r->eval_steps > 2 * 50 * 10);  // two episodes per iteration, each longer than 10 steps
  CHECK(last.eval_steps == r->eval_steps);
}

}  // namespace
}  // namespace pbppo::trainer
