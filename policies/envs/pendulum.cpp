#include "policies/envs/pendulum.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace pbppo::envs {
namespace {

Error LayoutError(const robot::IoLayout& layout, const std::string& what) {
  return MakeError(ErrorCode::kMismatch, "pendulum: io layout of robot '" + layout.robot + "': " + what);
}

}  // namespace

EnvSpec PendulumEnv() {
  EnvSpec s;
  s.name = "pendulum";
  s.description = "Gymnasium's Pendulum-v1";
  s.make = [](const EnvOptions& o) -> Result<std::unique_ptr<Env>> {
    auto layout = robot::LoadIoLayout(ModelsDir(o) + "/pendulum/io_layout.yaml");
    if (!layout) return std::move(layout).error();
    return AsEnv(Pendulum::Make(std::move(layout).value()));
  };
  return s;
}

Result<std::unique_ptr<Pendulum>> Pendulum::Make(robot::IoLayout layout) {
  if (layout.observation_size() != 3) {
    return LayoutError(layout, "observation size " + std::to_string(layout.observation_size()) + ", expected 3");
  }
  if (layout.action_size() != 1) {
    return LayoutError(layout, "action size " + std::to_string(layout.action_size()) + ", expected 1");
  }
  const auto& a = layout.actions[0];
  if (a.scale != 1.0 || a.offset != 0.0 || a.low != -kMaxTorque || a.high != kMaxTorque) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "action '%s': scale %g offset %g low %g high %g, expected 1 0 -2 2", a.name.c_str(),
                  a.scale, a.offset, a.low, a.high);
    return LayoutError(layout, buf);
  }
  return std::make_unique<Pendulum>(std::move(layout));
}

double Pendulum::AngleNormalize(double x) noexcept {
  constexpr double kPi = std::numbers::pi;
  const double y = 2.0 * kPi;
  double m = std::fmod(x + kPi, y);
  if (m != 0.0) {
    if ((y < 0.0) != (m < 0.0)) m += y;
  } else {
    m = std::copysign(0.0, y);
  }
  return m - kPi;
}

void Pendulum::SetState(double theta, double theta_dot, std::uint32_t elapsed_steps) noexcept {
  th_ = theta;
  thdot_ = theta_dot;
  elapsed_ = elapsed_steps;
}

void Pendulum::Observe(std::span<float> observation) const noexcept {
  observation[0] = static_cast<float>(std::cos(th_));
  observation[1] = static_cast<float>(std::sin(th_));
  observation[2] = static_cast<float>(thdot_);
}

void Pendulum::Reset(Rng& rng, std::span<float> observation) {
  th_ = rng.Uniform(-std::numbers::pi, std::numbers::pi);
  thdot_ = rng.Uniform(-1.0, 1.0);
  elapsed_ = 0;
  Observe(observation);
}

StepResult Pendulum::Step(std::span<const float> action, std::span<float> observation) {
  // numpy: u = clip(float32 action) stays float32; u**2 with a Python int exponent promotes the
  // scalar pair to float64 (NumPy 1.x rules), as do all other mixed expressions.
  const float uf = std::clamp(action[0], low_, high_);
  const double u = static_cast<double>(uf);
  const double an = AngleNormalize(th_);
  const double cost = an * an + 0.1 * (thdot_ * thdot_) + 0.001 * (u * u);

  double newthdot = thdot_ + (3.0 * kG / (2.0 * kL) * std::sin(th_) + 3.0 / (kM * kL * kL) * u) * kDt;
  newthdot = std::clamp(newthdot, -kMaxSpeed, kMaxSpeed);
  th_ = th_ + newthdot * kDt;
  thdot_ = newthdot;
  ++elapsed_;
  Observe(observation);
  StepResult r;
  r.reward = -cost;
  r.truncated = elapsed_ >= kEpisodeSteps;
  return r;
}

}  // namespace pbppo::envs
