// The CAN transport with continuous, velocity-commanded joints (the diffbot of tests/data), over
// the in-process network: a wheel driver's position, wrapped into its MIT range, is unwrapped into
// the multi-turn angle (both ways, across the range's ends and exactly at them); a
// velocity-commanded motor's frames carry kp 0 and p_des 0 whatever the commands hold.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "runtime/transport/can/can_transport.hpp"
#include "runtime/transport/can/memory_bus.hpp"
#include "runtime/transport/can/mit_codec.hpp"
#include "tests/support/robot_models.hpp"

using namespace pbppo;

namespace {

constexpr double kPi = std::numbers::pi;

struct Wire {
  const robot::RobotModel& m = test::DiffbotRobot();
  can::MemoryCanNetwork net{{"main"}};
  std::unique_ptr<can::CanTransport> t;
  std::unique_ptr<can::MemoryCanBus> device;  // the drivers' side of the bus
  robot::RobotData d = robot::MakeRobotData(m);

  Wire() {
    can::CanTransportOptions o;
    o.network = &net;
    auto tr = can::CanTransport::Open(m, "can", o);
    REQUIRE_MESSAGE(tr.ok(), tr.error().message);
    t = std::move(*tr);
    auto dev = net.Attach(0, {}, false, true);
    REQUIRE(dev.ok());
    device = std::move(*dev);
  }
  // A reply of motor `k` at position q (as the driver reports it), then a Read: the field.
  double Reply(std::size_t k, double q) {
    const robot::CanMotor& cm = m.can->motors[k];
    can::MitReply r;
    r.motor_id = static_cast<std::uint8_t>(cm.id);
    r.q_rad = q;
    const can::CanFrame f = can::MakeMitReplyFrame(cm.reply_id, m.can->range_of(cm), r);
    REQUIRE(device->Send({&f, 1}) == 1);
    t->Read(m, d);
    REQUIRE(d.fresh[m.motors[k].stream] == 1);
    return d.fields[m.motors[k].q_field];
  }
};

}  // namespace

TEST_CASE("CAN transport: a continuous joint's wrapped position becomes its multi-turn angle") {
  Wire w;
  const double step = 2 * kPi / 65535;  // the 16-bit position code over [-pi, pi]
  // Forward across +pi (every step below pi): the driver's position jumps to -pi + ..., the angle
  // keeps growing.
  CHECK(w.Reply(0, 2.9) == doctest::Approx(2.9).epsilon(step));
  CHECK(w.Reply(0, -2.9) == doctest::Approx(2 * kPi - 2.9).epsilon(step));
  CHECK(w.Reply(0, -1.0) == doctest::Approx(2 * kPi - 1.0).epsilon(step));
  CHECK(w.Reply(0, 1.5) == doctest::Approx(2 * kPi + 1.5).epsilon(step));
  CHECK(w.Reply(0, -2.5) == doctest::Approx(4 * kPi - 2.5).epsilon(step));
  CHECK(w.Reply(0, -0.5) == doctest::Approx(4 * kPi - 0.5).epsilon(step));
  CHECK(w.Reply(0, 2.5) == doctest::Approx(4 * kPi + 2.5).epsilon(step));
  // The range's two ends are the same angle: code 65535 (pi) then code 0 (-pi) is no turn.
  CHECK(w.Reply(0, kPi) == doctest::Approx(5 * kPi).epsilon(step));
  CHECK(w.Reply(0, -kPi) == doctest::Approx(5 * kPi).epsilon(step));
  // Backward across -pi, three times: the angle comes back below the first reply's.
  CHECK(w.Reply(0, 2.0) == doctest::Approx(4 * kPi + 2.0).epsilon(step));
  CHECK(w.Reply(0, -1.0) == doctest::Approx(4 * kPi - 1.0).epsilon(step));
  CHECK(w.Reply(0, -3.0) == doctest::Approx(4 * kPi - 3.0).epsilon(step));
  CHECK(w.Reply(0, 1.0) == doctest::Approx(2 * kPi + 1.0).epsilon(step));
  CHECK(w.Reply(0, -1.5) == doctest::Approx(2 * kPi - 1.5).epsilon(step));
  CHECK(w.Reply(0, 2.0) == doctest::Approx(2.0).epsilon(step));
  CHECK(w.Reply(0, -0.5) == doctest::Approx(-0.5).epsilon(step));
  CHECK(w.Reply(0, -3.0) == doctest::Approx(-3.0).epsilon(step));
  CHECK(w.Reply(0, 2.0) == doctest::Approx(2.0 - 2 * kPi).epsilon(step));
  // Each wheel counts its own turns; the revolute head is taken as reported.
  CHECK(w.Reply(1, -3.1) == doctest::Approx(-3.1).epsilon(step));
  CHECK(w.Reply(2, 1.2) == doctest::Approx(1.2).epsilon(25.0 / 65535));
  CHECK(w.Reply(0, 3.1) == doctest::Approx(3.1 - 2 * kPi).epsilon(step));
}

TEST_CASE("CAN transport: a velocity-commanded motor's command frame carries kp 0 and p_des 0") {
  Wire w;
  const robot::MotorSpec &wheel = w.m.motors[0], &head = w.m.motors[2];
  for (auto& c : w.d.motors) c = robot::MotorCommand::kCommand;
  w.d.command[wheel.dq] = 7.5;
  w.d.command[wheel.kd] = 0.3;
  w.d.command[wheel.tau] = 0.25;
  w.d.command[head.q] = 0.4;
  w.d.command[head.kp] = 4.0;
  w.t->Write(w.m, w.d);
  std::vector<can::CanFrame> got(8);
  REQUIRE(w.device->Receive(got) == 3);
  for (std::size_t k = 0; k < 3; ++k) {
    const robot::CanMotor& cm = w.m.can->motors[k];
    REQUIRE(got[k].id == cm.id);
    can::MitCommand c;
    REQUIRE(can::DecodeMitCommand(w.m.can->range_of(cm), got[k].data, got[k].len, &c));
    if (k == 2) {
      CHECK(c.q_rad == doctest::Approx(0.4).epsilon(1e-3));
      CHECK(c.kp_nm_rad == doctest::Approx(4.0).epsilon(1e-3));
      continue;
    }
    CHECK(c.kp_nm_rad == 0.0);                    // code 0 exactly: kp_min is 0
    CHECK(std::abs(c.q_rad) <= 2 * kPi / 65535);  // the code nearest 0: irrelevant with kp 0
    CHECK(c.dq_rad_s == doctest::Approx(k == 0 ? 7.5 : 0.0).epsilon(60.0 / 4095));
    CHECK(c.kd_nm_s_rad == doctest::Approx(0.3).epsilon(2.0 / 4095));  // the right wheel: its neutral gain
  }
}
