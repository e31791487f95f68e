// Gymnasium Pendulum-v1 (0.29.1), reproduced exactly: max speed 8, max torque 2, dt 0.05, g 10,
// m 1, l 1; reward -(angle_normalize(th)^2 + 0.1 thdot^2 + 0.001 u^2) on the state before the
// step, with u^2 in float32 as numpy computes it; semi-implicit Euler; 200-step episodes ending
// by truncation; initial th ~ U(-pi, pi), thdot ~ U(-1, 1).
#pragma once

#include <array>

#include "policies/envs/registry.hpp"

namespace pbppo::envs {

class Pendulum final : public Env {
 public:
  static constexpr double kMaxSpeed = 8.0;
  static constexpr double kMaxTorque = 2.0;
  static constexpr double kDt = 0.05;
  static constexpr double kG = 10.0;
  static constexpr double kM = 1.0;
  static constexpr double kL = 1.0;
  static constexpr std::uint32_t kEpisodeSteps = 200;

  // Checks that the layout describes 3 observations and 1 action with bounds +-kMaxTorque and
  // an identity action map, so that blob and environment agree.
  static Result<std::unique_ptr<Pendulum>> Make(robot::IoLayout layout);

  const std::string& name() const noexcept override { return name_; }
  std::span<const float> action_low() const noexcept override { return {&low_, 1}; }
  std::span<const float> action_high() const noexcept override { return {&high_, 1}; }
  std::uint32_t max_episode_steps() const noexcept override { return kEpisodeSteps; }
  const robot::IoLayout& layout() const noexcept override { return layout_; }

  void Reset(Rng& rng, std::span<float> observation) override;
  StepResult Step(std::span<const float> action, std::span<float> observation) override;
  std::unique_ptr<Env> Clone() const override { return std::make_unique<Pendulum>(*this); }

  // Direct state access for tests and replays.
  void SetState(double theta, double theta_dot, std::uint32_t elapsed_steps = 0) noexcept;
  double theta() const noexcept { return th_; }
  double theta_dot() const noexcept { return thdot_; }
  void Observe(std::span<float> observation) const noexcept;

  // Python's ((x + pi) % (2 pi)) - pi.
  static double AngleNormalize(double x) noexcept;

  explicit Pendulum(robot::IoLayout layout) : layout_(std::move(layout)) {}

 private:
  std::string name_ = "pendulum";
  robot::IoLayout layout_;
  double th_ = 0.0;
  double thdot_ = 0.0;
  std::uint32_t elapsed_ = 0;
  float low_ = -static_cast<float>(kMaxTorque);
  float high_ = static_cast<float>(kMaxTorque);
};

// `pendulum`: no flags of its own; the layout is models/pendulum/io_layout.yaml.
EnvSpec PendulumEnv();

}  // namespace pbppo::envs
