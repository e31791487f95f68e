// The AUV supervisor: limits and rate limits, every cause with its reason text, latching modes,
// reset only while disarmed, and the output invariant on random and hostile inputs.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/safety/auv_supervisor.hpp"

using namespace pbppo::safety;
using pbppo::robot::AuvSensorSample;

namespace {

AuvSensorSample GoodSample() {
  AuvSensorSample s;
  s.sonar_beams = 16;
  for (std::uint32_t i = 0; i < 16; ++i) s.sonar_m[i] = 10.0f;
  s.depth_m = 5.0;
  s.surge_mps = 1.0;
  s.target_distance_m = 12.0;
  s.clearance_m = 4.0;
  return s;
}

std::string Reason(const AuvDecision& d) {
  char buf[200];
  DescribeAuv(d, buf, sizeof buf);
  return buf;
}

// Runs `ticks` ticks with the same input; returns the last decision.
AuvDecision Run(const AuvSupervisorConfig& c, const AuvSupervisorInput& in, AuvSupervisorState& s, int ticks) {
  AuvDecision d;
  for (int k = 0; k < ticks; ++k) {
    d = SuperviseAuv(c, in, s);
    s = d.state;
  }
  return d;
}

}  // namespace

TEST_CASE("auv supervisor: the default configuration validates - bad ones are refused naming the field") {
  char why[200];
  AuvSupervisorConfig c;
  CHECK(ValidateAuvSupervisorConfig(c, why, sizeof why));
  c.v_min_mps = 0.2;
  CHECK_FALSE(ValidateAuvSupervisorConfig(c, why, sizeof why));
  CHECK(std::string(why) == "supervisor: v_min_mps = 0.2: must be <= 0 (stopping must be allowed)");
  c = AuvSupervisorConfig{};
  c.dw_max_radps = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(ValidateAuvSupervisorConfig(c, why, sizeof why));
  CHECK(std::string(why).find("dw_max_radps = nan: not finite") != std::string::npos);
  c = AuvSupervisorConfig{};
  c.stop_dv_mps = 0.05;
  CHECK_FALSE(ValidateAuvSupervisorConfig(c, why, sizeof why));
  CHECK(std::string(why).find("stop_dv_mps = 0.05: must be >= dv_max_mps") != std::string::npos);
  // Magnitudes no vehicle has (a unit error) are refused; the fuzzer found that limits near
  // DBL_MAX make a ramp step of stop_dv inexact.
  c = AuvSupervisorConfig{};
  c.v_max_mps = 1.4e306;
  c.stop_dv_mps = 5e303;
  CHECK_FALSE(ValidateAuvSupervisorConfig(c, why, sizeof why));
  CHECK(std::string(why) == "supervisor: v_max_mps = 1.4e+306: magnitude must be <= 1000");
  c = AuvSupervisorConfig{};
  c.stop_dw_radps = 2000.0;
  CHECK_FALSE(ValidateAuvSupervisorConfig(c, why, sizeof why));
  CHECK(std::string(why) == "supervisor: stop_dw_radps = 2000: magnitude must be <= 1000");
}

TEST_CASE("auv supervisor: command limits and rate limits, counted per cause") {
  const AuvSupervisorConfig c;
  const AuvSensorSample sample = GoodSample();
  AuvSupervisorState s;
  AuvSupervisorInput in{.v_mps = 3.0, .w_radps = -2.0, .sample = &sample};
  AuvDecision d = SuperviseAuv(c, in, s);
  CHECK(d.v_mps == doctest::Approx(0.1));  // one rate step from 0 towards 1.5
  CHECK(d.w_radps == doctest::Approx(-0.25));
  CHECK((d.causes & kAuvCauseCommandLimit) != 0);
  CHECK((d.causes & kAuvCauseRateLimit) != 0);
  CHECK(d.state.mode == AuvMode::kNominal);
  d = Run(c, in, s, 30);
  CHECK(d.v_mps == 1.5);
  CHECK(d.w_radps == -0.5);
  CHECK((d.causes & kAuvCauseRateLimit) == 0);
  CHECK(s.cause_ticks[0] == 30);  // command limit every tick (the first decision above was not kept)
  CHECK(s.cause_ticks[1] == 14);  // rate limited until 1.5 is reached on the 15th tick
  CHECK(s.mode == AuvMode::kNominal);
}

TEST_CASE("auv supervisor: a rate step that reaches the limit lands on it exactly, never an ulp past it") {
  // Found by fuzz_run.auv_supervisor: -7.97 + (0.1 - -7.97) is 0.10000000000000053 in doubles.
  AuvSupervisorConfig c;
  c.v_min_mps = -8.0;
  c.v_max_mps = 0.1;
  c.degraded_v_max_mps = 0.05;
  c.dv_max_mps = c.stop_dv_mps = 10.0;
  char why[200];
  REQUIRE(ValidateAuvSupervisorConfig(c, why, sizeof why));
  const AuvSensorSample sample = GoodSample();
  AuvSupervisorState s;
  s.v_mps = -7.97;
  const AuvSupervisorInput in{.v_mps = 5.0, .w_radps = 0.0, .sample = &sample};
  const AuvDecision d = SuperviseAuv(c, in, s);
  CHECK(d.v_mps == 0.1);
  CHECK((d.causes & kAuvCauseCommandLimit) != 0);
  CHECK((d.causes & kAuvCauseRateLimit) == 0);  // within one step: not rate limited
  s.v_mps = 0.1;
  const AuvSupervisorInput back{.v_mps = -9.0, .w_radps = 0.0, .sample = &sample};
  CHECK(SuperviseAuv(c, back, s).v_mps == -8.0);
}

TEST_CASE("auv supervisor: a stale sample degrades, then stops - the reason names the age") {
  const AuvSupervisorConfig c;
  const AuvSensorSample sample = GoodSample();
  AuvSupervisorState s;
  AuvSupervisorInput in{.v_mps = 1.0, .w_radps = 0.2, .sample = &sample};
  Run(c, in, s, 20);
  CHECK(s.v_mps == 1.0);
  in.sample_age_ticks = 2;
  AuvDecision d = Run(c, in, s, 1);
  CHECK(d.state.mode == AuvMode::kDegraded);
  CHECK(d.transition);
  CHECK(Reason(d) == "degraded: stale sensor sample: age 2 ticks > 1");
  CHECK(d.v_mps == doctest::Approx(0.9));  // towards degraded_v_max 0.75 at the rate limit
  in.sample_age_ticks = 4;
  d = Run(c, in, s, 1);
  CHECK(d.state.mode == AuvMode::kSafeStop);
  CHECK(Reason(d) == "safe-stop: stale sensor sample: age 4 ticks > 3");
  CHECK(d.v_mps == doctest::Approx(0.6));  // stop ramp 0.3 per tick
  CHECK(d.w_radps == 0.0);                 // hold heading
  // A fresh sample does not bring the mode back down.
  in.sample_age_ticks = 0;
  d = Run(c, in, s, 5);
  CHECK(d.state.mode == AuvMode::kSafeStop);
  CHECK(d.v_mps == 0.0);
  CHECK(s.latched_cause == kAuvCauseStaleSample);
}

TEST_CASE("auv supervisor: lost peer and e-stop request zero the command at once") {
  const AuvSupervisorConfig c;
  const AuvSensorSample sample = GoodSample();
  AuvSupervisorState s;
  AuvSupervisorInput in{.v_mps = 1.0, .w_radps = 0.2, .sample = &sample};
  Run(c, in, s, 20);
  in.sample = nullptr;
  in.sample_age_ticks = 21;
  AuvDecision d = Run(c, in, s, 1);
  CHECK(d.state.mode == AuvMode::kEStop);
  CHECK(d.v_mps == 0.0);
  CHECK(Reason(d) == "e-stop: lost peer: no sample for 21 ticks > 20");
  AuvSupervisorState s2;
  in = AuvSupervisorInput{.v_mps = 1.0, .sample = &sample, .peer_lost = true};
  CHECK(Reason(Run(c, in, s2, 1)) == "e-stop: lost peer: the transport reports the vehicle gone");
  AuvSupervisorState s3;
  in = AuvSupervisorInput{.v_mps = 1.0, .sample = &sample, .estop_request = true};
  CHECK(Reason(Run(c, in, s3, 1)) == "e-stop: e-stop request");
}

TEST_CASE("auv supervisor: non-finite action, invalid samples and deadline overruns") {
  const AuvSupervisorConfig c;
  AuvSensorSample sample = GoodSample();
  AuvSupervisorState s;
  AuvSupervisorInput in{.v_mps = std::numeric_limits<double>::quiet_NaN(), .sample = &sample};
  AuvDecision d = Run(c, in, s, 1);
  CHECK(d.state.mode == AuvMode::kSafeStop);
  CHECK(Reason(d) == "safe-stop: non-finite action: v = nan");
  CHECK(std::isfinite(d.v_mps));

  s = AuvSupervisorState{};
  in = AuvSupervisorInput{.v_mps = 1.0, .sample = &sample};
  sample.surge_mps = 9.0;
  d = Run(c, in, s, 1);
  CHECK(d.state.mode == AuvMode::kDegraded);
  CHECK(Reason(d) == "degraded: invalid sensor sample: surge_mps = 9 (1 in a row)");
  sample.surge_mps = 1.0;
  sample.sonar_m[5] = std::numeric_limits<float>::infinity();
  d = Run(c, in, s, 2);
  CHECK(d.state.mode == AuvMode::kSafeStop);
  CHECK(Reason(d) == "safe-stop: invalid sensor sample: sonar_m = inf (3 in a row)");
  sample = GoodSample();
  sample.sonar_beams = 8;
  const char* field = "";
  double value = 0;
  CHECK(CheckAuvSample(c, sample, &field, &value) == kAuvCauseInvalidSample);
  CHECK(std::string(field) == "sonar_beams");
  CHECK(value == 8.0);
  sample = GoodSample();
  sample.route_bearing_rad = std::numeric_limits<double>::quiet_NaN();
  CHECK(CheckAuvSample(c, sample, &field, &value) == kAuvCauseInvalidSample);
  CHECK(std::string(field) == "route_bearing_rad");

  s = AuvSupervisorState{};
  sample = GoodSample();
  in = AuvSupervisorInput{.v_mps = 1.0, .sample = &sample, .consecutive_deadline_misses = 2};
  CHECK(Reason(Run(c, in, s, 1)) == "degraded: deadline overrun: 2 consecutive misses >= 2");
  in.consecutive_deadline_misses = 5;
  CHECK(Reason(Run(c, in, s, 1)) == "safe-stop: deadline overrun: 5 consecutive misses >= 5");
  CHECK(s.cause_ticks[6] == 2);
}

TEST_CASE("auv supervisor: the mode comes back down only by a reset while disarmed") {
  const AuvSupervisorConfig c;
  const AuvSensorSample sample = GoodSample();
  AuvSupervisorState s;
  AuvSupervisorInput in{.v_mps = 1.0, .sample = &sample, .estop_request = true};
  Run(c, in, s, 1);
  CHECK(s.mode == AuvMode::kEStop);
  in.estop_request = false;
  Run(c, in, s, 10);
  CHECK(s.mode == AuvMode::kEStop);
  CHECK_FALSE(ResetAuvSupervisor(s, /*armed=*/true));
  CHECK(s.mode == AuvMode::kEStop);
  CHECK(ResetAuvSupervisor(s, /*armed=*/false));
  CHECK(s.mode == AuvMode::kNominal);
  CHECK(Run(c, in, s, 1).v_mps == doctest::Approx(0.1));
}

TEST_CASE("auv supervisor: random hostile inputs keep the command finite and within limits - no allocation") {
  const AuvSupervisorConfig c;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-10, 10);
  const double specials[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(), 1e308, -1e308};
  auto value = [&] { return rng() % 10 == 0 ? specials[rng() % 5] : u(rng); };
  AuvSensorSample sample = GoodSample();
  AuvSupervisorState s;
  std::uint64_t rises = 0;
  pbppo::AllocationScope scope;
  for (int k = 0; k < 100000; ++k) {
    if (k % 5000 == 0) ResetAuvSupervisor(s, false);
    AuvSupervisorInput in{.v_mps = value(), .w_radps = value()};
    sample.surge_mps = rng() % 50 == 0 ? value() : 1.0;
    in.sample = rng() % 20 == 0 ? nullptr : &sample;
    in.sample_age_ticks = static_cast<std::uint32_t>(rng() % 30 == 0 ? rng() % 40 : 0);
    in.consecutive_deadline_misses = static_cast<std::uint32_t>(rng() % 100 == 0 ? rng() % 8 : 0);
    const double v_prev = s.v_mps, w_prev = s.w_radps;
    const AuvDecision d = SuperviseAuv(c, in, s);
    REQUIRE(std::isfinite(d.v_mps));
    REQUIRE(std::isfinite(d.w_radps));
    REQUIRE(d.v_mps >= c.v_min_mps);
    REQUIRE(d.v_mps <= c.v_max_mps);
    REQUIRE(std::abs(d.w_radps) <= c.w_max_radps);
    if (d.state.mode <= AuvMode::kDegraded) {
      REQUIRE(std::abs(d.v_mps - v_prev) <= c.dv_max_mps + 1e-12);
      REQUIRE(std::abs(d.w_radps - w_prev) <= c.dw_max_radps + 1e-12);
    }
    REQUIRE(d.state.mode >= s.mode);
    rises += d.transition;
    s = d.state;
  }
  CHECK(scope.count() == 0);
  CHECK(rises > 20);
}
