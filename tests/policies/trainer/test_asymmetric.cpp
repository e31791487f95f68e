// Asymmetric actor-critic: a task whose reward level depends on a per-episode constant the actor
// cannot observe. The critic that is given it (a privileged observation) explains the returns far
// better, the blob carries only the actor's input, and the runs stay deterministic.
#include <doctest/doctest.h>

#include <algorithm>
#include <memory>
#include <string>

#include "policies/envs/env.hpp"
#include "policies/trainer/trainer.hpp"
#include "runtime/robot/io_layout.hpp"

namespace pbppo::trainer {
namespace {

// x' = x + 0.2 a (a in [-1, 1], x within [-2, 2]), reward -x^2 + 2c for 50 steps (truncated);
// x0 and c drawn from U(-1, 1) at each reset. The actor sees x; the privileged critic also sees c
// and the time left. c shifts the reward, never the best action.
class HiddenOffset final : public envs::Env {
 public:
  explicit HiddenOffset(bool privileged) : privileged_(privileged) {
    layout_ = robot::ParseIoLayout(
                  "robot: hidden_offset\nobservations:\n  - {name: x, signal: x}\nactions:\n"
                  "  - {name: push, command: push, low: -1, high: 1}\n",
                  "test")
                  .value();
  }
  const std::string& name() const noexcept override { return name_; }
  std::span<const float> action_low() const noexcept override { return {&low_, 1}; }
  std::span<const float> action_high() const noexcept override { return {&high_, 1}; }
  std::uint32_t max_episode_steps() const noexcept override { return kSteps; }
  const robot::IoLayout& layout() const noexcept override { return layout_; }
  std::uint32_t critic_observation_size() const noexcept override { return privileged_ ? 3 : 0; }
  void CriticObservation(std::span<float> out) const noexcept override {
    out[0] = static_cast<float>(x_);
    out[1] = static_cast<float>(c_);
    out[2] = static_cast<float>(kSteps - t_) / kSteps;
  }
  void Reset(Rng& rng, std::span<float> observation) override {
    x_ = rng.Uniform(-1.0, 1.0);
    c_ = rng.Uniform(-1.0, 1.0);
    t_ = 0;
    observation[0] = static_cast<float>(x_);
  }
  envs::StepResult Step(std::span<const float> action, std::span<float> observation) override {
    x_ = std::clamp(x_ + 0.2 * std::clamp(static_cast<double>(action[0]), -1.0, 1.0), -2.0, 2.0);
    ++t_;
    observation[0] = static_cast<float>(x_);
    envs::StepResult r;
    r.reward = -x_ * x_ + 2.0 * c_;
    r.truncated = t_ >= kSteps;
    return r;
  }
  std::unique_ptr<Env> Clone() const override { return std::make_unique<HiddenOffset>(*this); }

 private:
  static constexpr std::uint32_t kSteps = 50;
  bool privileged_;
  robot::IoLayout layout_;
  std::string name_ = "hidden-offset";
  float low_ = -1.f, high_ = 1.f;
  double x_ = 0, c_ = 0;
  std::uint32_t t_ = 0;
};

TrainOptions Options(int threads) {
  return {.seed = 5,
          .total_steps = 16000,
          .num_envs = 8,
          .rollout_steps = 100,
          .threads = threads,
          .minibatch = 200,
          .epochs = 5,
          .learning_rate = 1e-3,
          .gamma = 0.95,
          .normalize_observations = true};
}

double LateExplainedVariance(const TrainResult& r) {
  double sum = 0;
  const std::size_t n = r.iterations.size(), from = n - 5;
  for (std::size_t i = from; i < n; ++i) sum += r.iterations[i].explained_variance;
  return sum / static_cast<double>(n - from);
}

TEST_CASE(
    "a privileged critic observation explains the returns the actor's cannot, and the blob holds the actor only") {
  auto plain = Train(Options(1), std::make_unique<HiddenOffset>(false));
  auto privileged = Train(Options(1), std::make_unique<HiddenOffset>(true));
  REQUIRE_MESSAGE(plain.ok(), (plain.ok() ? "" : plain.error().message));
  REQUIRE_MESSAGE(privileged.ok(), (privileged.ok() ? "" : privileged.error().message));
  const double ev_plain = LateExplainedVariance(*plain), ev_privileged = LateExplainedVariance(*privileged);
  MESSAGE("explained variance over the last 5 iterations: actor's observation " << ev_plain << ", privileged "
                                                                                << ev_privileged);
  CHECK(ev_privileged > 0.9);
  CHECK(ev_privileged > ev_plain + 0.3);
  CHECK(privileged->iterations.back().value_loss < 0.5 * plain->iterations.back().value_loss);
  // The blob: the actor's one input and its normaliser, nothing of the critic's three.
  const policy::PolicySpec& spec = privileged->spec;
  CHECK(spec.input_size == 1);
  CHECK(spec.layers.front().in == 1);
  CHECK(spec.obs_mean.size() == 1);
  CHECK(spec.obs_inv_std.size() == 1);
  CHECK(privileged->freeze_check <= 1.0);
}

TEST_CASE("privileged critic: same seed and thread count give the same run") {
  for (int threads : {1, 2}) {
    auto a = Train(Options(threads), std::make_unique<HiddenOffset>(true));
    auto b = Train(Options(threads), std::make_unique<HiddenOffset>(true));
    REQUIRE(a.ok());
    REQUIRE(b.ok());
    for (std::size_t l = 0; l < a->spec.layers.size(); ++l) CHECK(a->spec.layers[l].weight == b->spec.layers[l].weight);
    CHECK(a->iterations.back().value_loss == b->iterations.back().value_loss);
  }
}

}  // namespace
}  // namespace pbppo::trainer
