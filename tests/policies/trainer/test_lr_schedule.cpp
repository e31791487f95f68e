// The learning-rate schedules (constant, anneal, rsl_rl's KL-adaptive rule), their parsing, and
// the Gaussian KL divergence the adaptive rule reads.
#include <doctest/doctest.h>

#include <cmath>

#include "policies/trainer/lr_schedule.hpp"
#include "policies/trainer/ppo_loss.hpp"

namespace pbppo::trainer {
namespace {

TEST_CASE("lr schedules: constant, linear anneal over the iterations, the adaptive rule and its bounds") {
  LrSchedule constant;
  CHECK(constant.AtIteration(3e-4, 5, 10) == 3e-4);
  LrSchedule anneal = ParseLrSchedule("anneal").value();
  CHECK(anneal.AtIteration(3e-4, 0, 10) == 3e-4);
  CHECK(anneal.AtIteration(3e-4, 5, 10) == doctest::Approx(1.5e-4));
  CHECK(anneal.AtIteration(3e-4, 9, 10) == doctest::Approx(3e-5));

  const LrSchedule a = ParseLrSchedule("adaptive").value();
  CHECK(a.desired_kl == 0.01);
  CHECK(a.Adapt(1e-3, 0.021) == doctest::Approx(1e-3 / 1.5));  // above 2 KL*: divided
  CHECK(a.Adapt(1e-3, 0.02) == 1e-3);                          // 2 KL* itself: kept
  CHECK(a.Adapt(1e-3, 0.01) == 1e-3);
  CHECK(a.Adapt(1e-3, 0.005) == 1e-3);                     // KL* / 2 itself: kept
  CHECK(a.Adapt(1e-3, 0.004) == doctest::Approx(1.5e-3));  // below KL* / 2: multiplied
  CHECK(a.Adapt(1e-3, 0.0) == 1e-3);                       // no change at all: kept
  CHECK(a.Adapt(1.2e-5, 1.0) == 1e-5);                     // clamped below
  CHECK(a.Adapt(8e-3, 1e-6) == 1e-2);                      // and above
  CHECK(ParseLrSchedule("adaptive:0.02").value().desired_kl == 0.02);
  CHECK(ParseLrSchedule("adaptive:0.02").value().Describe() == "adaptive:0.02");
  CHECK(ParseLrSchedule("constant").value().Describe() == "constant");
  CHECK(anneal.Describe() == "anneal");
}

TEST_CASE("lr schedules: bad names and desired KLs are refused naming the flag and the value") {
  CHECK(ParseLrSchedule("cosine").error().message ==
        "--lr-schedule: 'cosine' unknown (constant, anneal, adaptive or adaptive:KL)");
  CHECK(ParseLrSchedule("adaptive:").error().message ==
        "--lr-schedule: 'adaptive:': desired KL '' is not a number in (0, 1]");
  CHECK(ParseLrSchedule("adaptive:0").error().message ==
        "--lr-schedule: 'adaptive:0': desired KL '0' is not a number in (0, 1]");
  CHECK(ParseLrSchedule("adaptive:x").error().message ==
        "--lr-schedule: 'adaptive:x': desired KL 'x' is not a number in (0, 1]");
}

TEST_CASE("the Gaussian KL divergence: zero between equal policies, the closed form otherwise") {
  Mat<double> mu(2, 2), old_mu(2, 2);
  mu << 0.5, -1.0, 2.0, 0.0;
  old_mu = mu;
  const double log_std[2] = {-0.5, 0.3};
  // The rsl_rl form adds 1e-5 inside the logarithm: log(1 + 1e-5) per action and column.
  CHECK(SumGaussianKl(mu, log_std, old_mu, log_std) == doctest::Approx(4 * std::log(1 + 1e-5)).epsilon(1e-9));
  const double old_log_std[2] = {0.0, 0.0};
  old_mu(0, 1) = -0.5;
  double want = 0;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      const double s = std::exp(log_std[j]), s0 = 1.0, d = old_mu(j, i) - mu(j, i);
      want += std::log(s / s0) + (s0 * s0 + d * d) / (2 * s * s) - 0.5;
    }
  CHECK(SumGaussianKl(mu, log_std, old_mu, old_log_std) == doctest::Approx(want).epsilon(1e-4));
}

}  // namespace
}  // namespace pbppo::trainer
