// GAE on a worked example: truncation bootstraps from the final observation's value,
// termination bootstraps nothing, and neither carries advantage across the boundary.
#include <doctest/doctest.h>

#include <cstdint>

#include "policies/trainer/gae.hpp"

namespace pbppo::trainer {
namespace {

TEST_CASE("GAE bootstraps truncations and stops at terminations") {
  const float rewards[3] = {1, 1, 1};
  const float values[3] = {0.5f, 0.5f, 0.5f};
  const float trunc_values[3] = {0, 2, 0};
  const float last[1] = {3};
  std::uint8_t term[3] = {0, 0, 0};
  std::uint8_t trunc[3] = {0, 1, 0};
  GaeInput in{3, 1, rewards, values, term, trunc, trunc_values, last};
  float adv[3], ret[3];
  ComputeGae(in, 0.9, 0.8, adv, ret);
  CHECK(adv[2] == doctest::Approx(1 + 0.9 * 3 - 0.5));
  CHECK(adv[1] == doctest::Approx(1 + 0.9 * 2 - 0.5));
  CHECK(adv[0] == doctest::Approx(1 + 0.9 * 0.5 - 0.5 + 0.72 * 2.3));
  CHECK(ret[0] == doctest::Approx(adv[0] + 0.5));

  trunc[1] = 0;
  term[1] = 1;
  ComputeGae(in, 0.9, 0.8, adv, ret);
  CHECK(adv[1] == doctest::Approx(0.5));
  CHECK(adv[0] == doctest::Approx(0.95 + 0.72 * 0.5));
}

TEST_CASE("GAE keeps environments apart in the time-major layout") {
  // Two envs, two steps: env 0 gets rewards 1, env 1 gets rewards 10.
  const float rewards[4] = {1, 10, 1, 10};
  const float values[4] = {0, 0, 0, 0};
  const float zeros[4] = {0, 0, 0, 0};
  const float last[2] = {0, 0};
  const std::uint8_t none[4] = {0, 0, 0, 0};
  GaeInput in{2, 2, rewards, values, none, none, zeros, last};
  float adv[4], ret[4];
  ComputeGae(in, 1.0, 1.0, adv, ret);
  CHECK(adv[0] == doctest::Approx(2));
  CHECK(adv[1] == doctest::Approx(20));
  CHECK(adv[2] == doctest::Approx(1));
  CHECK(adv[3] == doctest::Approx(10));
}

}  // namespace
}  // namespace pbppo::trainer
