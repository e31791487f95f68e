// The learning rate over a run (--lr-schedule):
//   constant       the --lr throughout;
//   anneal         linear decay to 0 over the budget, counted in iterations (CleanRL's anneal_lr);
//   adaptive[:KL]  rsl_rl's rule: after each minibatch's forward pass, the mean KL divergence
//                  between the policy that collected the rollout and the current one sets the rate
//                  for that minibatch's step and the next: divided by 1.5 when KL > 2 KL*, multiplied
//                  by 1.5 when 0 < KL < KL* / 2, kept within [1e-5, 1e-2]; it carries over from one
//                  iteration to the next. KL* (desired KL) defaults to 0.01.
#pragma once

#include <string>

#include "runtime/core/result.hpp"

namespace pbppo::trainer {

struct LrSchedule {
  enum class Kind { kConstant, kAnneal, kAdaptive };
  Kind kind = Kind::kConstant;
  double desired_kl = 0.01;  // adaptive

  static constexpr double kMinAdaptive = 1e-5;
  static constexpr double kMaxAdaptive = 1e-2;
  static constexpr double kFactor = 1.5;

  // "constant", "anneal" or "adaptive:KL".
  std::string Describe() const;
  // The rate of iteration `it` of `iterations` for constant and anneal, from the base rate `lr`.
  double AtIteration(double lr, int it, int iterations) const;
  // The adaptive rule: the rate after a minibatch whose mean KL was `kl`.
  double Adapt(double lr, double kl) const;
};

// "constant", "anneal", "adaptive" or "adaptive:KL" (KL in (0, 1]); errors name --lr-schedule and
// the value.
Result<LrSchedule> ParseLrSchedule(const std::string& text);

}  // namespace pbppo::trainer
