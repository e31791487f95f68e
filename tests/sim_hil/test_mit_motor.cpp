// The emulated MIT driver's firmware behaviour, frame by frame (pure, host), and its position
// wrapping for a continuous joint.
#include <doctest/doctest.h>

#include <algorithm>

#include "runtime/transport/can/mit_codec.hpp"
#include "sim_hil/devices/mit_motor.hpp"

using namespace pbppo;

namespace {

sim::MitMotorConfig Config() {
  sim::MitMotorConfig c;
  c.motor_id = 3;
  c.reply_id = 0x103;
  c.range = {-12.5, 12.5, -50, 50, 0, 500, 0, 5, -25, 25};
  c.tau_limit_nm = 20;
  c.timeout_ticks = 10;
  return c;
}

can::MitReply Decode(const sim::MitMotorConfig& c, const can::CanFrame& f) {
  can::MitReply r;
  REQUIRE(f.id == c.reply_id);
  REQUIRE(can::DecodeMitReply(c.range, f.data, f.len, &r));
  return r;
}

}  // namespace

TEST_CASE("MIT driver: replies to every frame - obeys only in motor mode - PD - torque limit - watchdog") {
  const auto c = Config();
  auto s = sim::MakeMitMotorState(c);
  can::CanFrame reply;
  const auto cmd = can::MakeMitCommandFrame(3, c.range, {1.0, 0.0, 10.0, 0.5, 0.0});
  // Outside motor mode: answered, not obeyed.
  REQUIRE(sim::MitMotorReceive(c, s, cmd, 0, 0.2, 0.1, &reply));
  CHECK(Decode(c, reply).motor_id == 3);
  CHECK(Decode(c, reply).q_rad == doctest::Approx(0.2).epsilon(1e-3));
  CHECK(sim::MitMotorTorque(c, s, 0, 0.2, 0.1) == 0.0);
  // Enter motor mode, then the PD law from the latest command.
  REQUIRE(
      sim::MitMotorReceive(c, s, can::MakeMitSpecialFrame(3, can::MitSpecial::kEnterMotorMode), 1, 0.2, 0.1, &reply));
  CHECK(s.motor_mode);
  CHECK(sim::MitMotorTorque(c, s, 1, 0.2, 0.1) == 0.0);  // no command yet
  REQUIRE(sim::MitMotorReceive(c, s, cmd, 2, 0.2, 0.1, &reply));
  const can::MitCommand& m = s.command;  // the decoded (quantised) command
  CHECK(m.q_rad == doctest::Approx(1.0).epsilon(1e-3));
  CHECK(sim::MitMotorTorque(c, s, 2, 0.2, 0.1) ==
        doctest::Approx(m.kp_nm_rad * (m.q_rad - 0.2) + m.kd_nm_s_rad * (m.dq_rad_s - 0.1) + m.tau_ff_nm));
  CHECK(Decode(c, reply).tau_nm == doctest::Approx(0.0).epsilon(0.02));  // torque before this command
  // Torque limit from the actuator config.
  REQUIRE(
      sim::MitMotorReceive(c, s, can::MakeMitCommandFrame(3, c.range, {5.0, 0.0, 100.0, 0.0, 0.0}), 3, 0, 0, &reply));
  CHECK(sim::MitMotorTorque(c, s, 3, 0.0, 0.0) == 20.0);
  // Watchdog: no command for more than timeout_ticks -> zero torque.
  CHECK(sim::MitMotorTorque(c, s, 13, 0.0, 0.0) == 20.0);
  CHECK(sim::MitMotorTorque(c, s, 14, 0.0, 0.0) == 0.0);
  CHECK(s.timeouts == 1);
  // Set zero: positions are relative to the new zero.
  REQUIRE(sim::MitMotorReceive(c, s, can::MakeMitSpecialFrame(3, can::MitSpecial::kSetZero), 15, 0.7, 0, &reply));
  CHECK(Decode(c, reply).q_rad == doctest::Approx(0.0).epsilon(1e-3));
  REQUIRE(sim::MitMotorReceive(c, s, cmd, 16, 0.8, 0, &reply));
  CHECK(Decode(c, reply).q_rad == doctest::Approx(0.1).epsilon(1e-3));
  // Exit motor mode: zero torque, still answering.
  REQUIRE(sim::MitMotorReceive(c, s, can::MakeMitSpecialFrame(3, can::MitSpecial::kExitMotorMode), 17, 0.8, 0, &reply));
  CHECK_FALSE(s.motor_mode);
  CHECK(sim::MitMotorTorque(c, s, 17, 0.8, 0.0) == 0.0);
  // A wrong length is ignored without a reply.
  can::CanFrame short_cmd = cmd;
  short_cmd.len = 5;
  CHECK_FALSE(sim::MitMotorReceive(c, s, short_cmd, 18, 0, 0, &reply));
  CHECK(s.ignored_length == 1);
  CHECK(s.replies == s.frames);
}

TEST_CASE("MIT driver faults: seeded drops with bounded bursts - silence from a tick") {
  auto c = Config();
  c.drop_probability = 0.5;
  c.max_drop_burst = 2;
  auto s = sim::MakeMitMotorState(c);
  can::CanFrame reply;
  const auto cmd = can::MakeMitCommandFrame(3, c.range, {0, 0, 0, 0, 0});
  int burst = 0, worst = 0;
  for (int k = 0; k < 10000; ++k) {
    if (sim::MitMotorReceive(c, s, cmd, static_cast<std::uint64_t>(k), 0, 0, &reply)) {
      burst = 0;
    } else {
      worst = std::max(worst, ++burst);
    }
  }
  CHECK(worst == 2);
  CHECK(s.dropped > 3000);
  CHECK(s.dropped + s.frames == 10000);
  auto s2 = sim::MakeMitMotorState(c);  // same seed: same drops
  for (int k = 0; k < 10000; ++k) (void)sim::MitMotorReceive(c, s2, cmd, static_cast<std::uint64_t>(k), 0, 0, &reply);
  CHECK(s2.dropped == s.dropped);

  auto q = Config();
  q.silent_from_tick = 5;
  auto t = sim::MakeMitMotorState(q);
  CHECK(sim::MitMotorReceive(q, t, cmd, 4, 0, 0, &reply));
  CHECK_FALSE(sim::MitMotorReceive(q, t, cmd, 5, 0, 0, &reply));
  CHECK(t.ignored_silent == 1);
}

TEST_CASE("MIT driver: a continuous joint's driver wraps its position into the MIT range - a velocity command") {
  auto c = Config();
  c.wrap_position = true;
  auto s = sim::MakeMitMotorState(c);
  can::CanFrame reply;
  const auto enter = can::MakeMitSpecialFrame(3, can::MitSpecial::kEnterMotorMode);
  // 30 rad is 30 - 25 = 5 in [-12.5, 12.5); -13 is 12 (one range up); 12.5 is -12.5.
  for (const auto& [q, reported] : {std::pair{30.0, 5.0}, std::pair{-13.0, 12.0}, std::pair{12.5, -12.5},
                                    std::pair{-12.5, -12.5}, std::pair{3.0, 3.0}, std::pair{-62.0, -12.0}}) {
    CAPTURE(q);
    REQUIRE(sim::MitMotorReceive(c, s, enter, 0, q, 4.0, &reply));
    CHECK(Decode(c, reply).q_rad == doctest::Approx(reported).epsilon(1e-3));
    CHECK(Decode(c, reply).dq_rad_s == doctest::Approx(4.0).epsilon(0.01));
  }
  // A velocity command (kp 0): the torque is kd (dq_des - dq) (+ the feed-forward, 0 as quantised:
  // 6 mNm), wherever the joint has turned to.
  REQUIRE(sim::MitMotorReceive(c, s, can::MakeMitCommandFrame(3, c.range, {0.0, 6.0, 0.0, 0.5, 0.0}), 1, 100.0, 4.0,
                               &reply));
  CHECK(s.command.kp_nm_rad == 0.0);
  const can::MitCommand& m = s.command;
  CHECK(sim::MitMotorTorque(c, s, 1, 100.0, 4.0) == doctest::Approx(m.kd_nm_s_rad * (m.dq_rad_s - 4.0) + m.tau_ff_nm));
  CHECK(sim::MitMotorTorque(c, s, 1, 100.0, 4.0) == doctest::Approx(1.0).epsilon(0.01));
}
