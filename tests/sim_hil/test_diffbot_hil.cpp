// A CAN robot that exists only as data (tests/data/diffbot: two continuous, velocity-commanded
// wheels and a position-commanded head) against the generic rotor plant (sim_hil/rotor_hil.hpp),
// in one process over the in-process CAN network (no kernel needed: the default suite). The
// controller is runtime/loop over the CAN transport with the robot's trajectory as its command
// source; controller and HIL tick in lock-step, each reading what the other sent in its last tick
// (the same frames, codecs and quantisation as over SocketCAN). The vcan counterpart, through the
// pbppo-controller program, is tests/sim_hil/diffbot_programs.sh.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <string>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/loop/log.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/loop/replay.hpp"
#include "runtime/loop/trajectory_source.hpp"
#include "runtime/transport/can/can_transport.hpp"
#include "runtime/transport/can/memory_bus.hpp"
#include "sim_hil/rotor_hil.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;
using loop::Phase;
using safety::Mode;

namespace {

constexpr std::uint64_t kTrajectoryHash = 7;

struct Rig {
  const robot::RobotModel& model = test::DiffbotRobot();
  can::MemoryCanNetwork net{{"main"}};
  std::unique_ptr<sim::RotorHil> hil;
  std::unique_ptr<can::CanTransport> can;
  std::unique_ptr<loop::TrajectorySource> source;
  robot::RobotData data = robot::MakeRobotData(model);
  std::unique_ptr<loop::LoopData> loop;
  std::unique_ptr<loop::Recorder> recorder;
  robot::Transport* transports[1] = {};
  std::uint64_t tick = 0, allocations = 0;

  explicit Rig(const std::string& record_path = "") {
    sim::RotorHilOptions h;
    h.network = &net;
    auto hr = sim::RotorHil::Make(model, h);
    REQUIRE_MESSAGE(hr.ok(), hr.error().message);
    hil = std::move(*hr);
    can::CanTransportOptions co;
    co.network = &net;
    auto cr = can::CanTransport::Open(model, "can", co);
    REQUIRE_MESSAGE(cr.ok(), cr.error().message);
    can = std::move(*cr);
    transports[0] = can.get();
    auto t = loop::RobotTrajectory(model);
    REQUIRE_MESSAGE(t.ok(), t.error().message);
    source = std::make_unique<loop::TrajectorySource>(model, *t);
    loop = loop::MakeLoopData(model, source.get());
    if (!record_path.empty()) {
      auto r = loop::Recorder::Open(record_path, model,
                                    loop::MakeLogHeader(model, loop::SourceKind::kTrajectory, kTrajectoryHash));
      REQUIRE_MESSAGE(r.ok(), r.error().message);
      recorder = std::move(*r);
      REQUIRE(loop::AttachRecorder(model, data, *loop, recorder.get()).ok());
    }
    loop->Arm();
  }

  // One controller tick (reading what the HIL sent in its last tick), then one HIL tick.
  loop::TickStatus Tick() {
    const std::uint32_t from_hil[1] = {hil->devices().sent_last_tick(0)};
    can->Expect(from_hil);
    loop::TickStatus st;
    {
      AllocationScope scope;
      rt::TickTiming timing;
      timing.tick = tick++;
      st = loop::Tick(model, data, *loop, transports, timing);
      allocations += scope.count();
    }
    const std::uint32_t from_ctl[1] = {can->sent_last_tick(0)};
    hil->Tick(from_ctl, 0);
    return st;
  }
  void Until(Phase p, int limit) {
    for (int k = 0; k < limit && loop->phase() != p; ++k) Tick();
    REQUIRE(loop->phase() == p);
  }
  double Field(const char* name) const { return data.fields[static_cast<std::size_t>(model.FieldIndex(name))]; }
};

}  // namespace

TEST_CASE("rotor plant: each joint's inertia about its axis from the URDF, a continuous joint unbounded") {
  const robot::RobotModel& m = test::DiffbotRobot();
  auto p = sim::RotorPlant::Make(*m.body, m.tick_period_s);
  REQUIRE_MESSAGE(p.ok(), p.error().message);
  CHECK(p->inertia_kg_m2(0) == doctest::Approx(0.0032));  // the wheel about y
  CHECK(p->inertia_kg_m2(2) == doctest::Approx(0.004));   // the head about z (its COM on the axis)
  // 0.1 Nm for 1 s on a free wheel: the damping (0.01) and friction (0.02) take their share.
  const double tau[3] = {0.1, 0.0, 0.5};
  for (int k = 0; k < 1000; ++k) p->Step(tau);
  const double w_inf = (0.1 - 0.02) / 0.01, tc = 0.0032 / 0.01;  // 8 rad/s, 0.32 s
  CHECK(p->dq_rad_s()[0] == doctest::Approx(w_inf * (1 - std::exp(-1.0 / tc))).epsilon(0.01));
  CHECK(p->q_rad()[0] > 2.0);
  CHECK(p->dq_rad_s()[1] == 0.0);  // friction holds an undriven joint
  CHECK(p->q_rad()[2] == 1.5);     // the head against its upper limit
  CHECK(p->dq_rad_s()[2] == 0.0);
}

TEST_CASE("diffbot HIL in process: arming, stand-up, wheel speeds across range ends, damping - then replayed") {
  const std::string dir = test::ScratchDir("diffbot_hil");
  const std::string log_path = dir + "/diffbot.log";
  const robot::RobotModel& m = test::DiffbotRobot();
  const robot::MotorSpec &left = m.motors[0], &right = m.motors[1], &head = m.motors[2];
  std::uint64_t ticks = 0;
  {
    Rig rig(log_path);
    rig.Until(Phase::kStandUp, 5);
    for (std::size_t k = 0; k < 3; ++k) CHECK(rig.hil->devices().motor(k).motor_mode);
    rig.Until(Phase::kHold, 200);
    // Stand-up: the head towards its default pose; the wheels held at zero speed.
    CHECK(rig.hil->plant().q_rad()[2] == doctest::Approx(0.3).epsilon(0.1));
    CHECK(rig.hil->plant().dq_rad_s()[0] == 0.0);
    rig.Until(Phase::kRun, 100);
    // Run: 1 s of wheel speeds (left 12 + 3 sin(4 pi t), right -8 rad/s) and a head sweep. After
    // 0.1 s (ten of the wheels' 10 ms time constants) every tick's speed is within its bound:
    //   steady state   kd (dq_des - dq) = b dq + F:  (0.01 x 15 + 0.02) / 0.31 = 0.55 rad/s (left)
    //                                                (0.01 x 8 + 0.02) / 0.31 = 0.32 rad/s (right)
    //   lag (left)     3 rad/s at 4 pi rad/s through a 10 ms lag and 2 ticks of delay: 3 x 4 pi x 0.012 = 0.45
    // The head's PD (kp 4, kd 0.15, I 0.004): I A w^2 / kp = 0.016 rad, friction 0.0025 rad, two
    // ticks of delay 0.005 rad: within 0.05 rad.
    double worst_left = 0, worst_right = 0, worst_head = 0, worst_unwrap = 0;
    std::uint64_t run_ticks = 0;
    while (rig.loop->phase() == Phase::kRun && run_ticks < 1200) {
      rig.Tick();
      ++run_ticks;
      const double* dq = rig.hil->plant().dq_rad_s();
      const double* q = rig.hil->plant().q_rad();
      // The transport's multi-turn angle is the plant's own (the plant started at 0), one reply old.
      worst_unwrap = std::max(worst_unwrap, std::abs(rig.Field("q_left_wheel") - (q[0] - dq[0] * 2e-3)));
      if (run_ticks < 100) continue;
      worst_left = std::max(worst_left, std::abs(dq[0] - rig.data.command[left.dq]));
      worst_right = std::max(worst_right, std::abs(dq[1] - rig.data.command[right.dq]));
      worst_head = std::max(worst_head, std::abs(q[2] - rig.data.command[head.q]));
    }
    std::printf(
        "diffbot HIL: %llu run ticks; worst speed error left %.3f right %.3f rad/s; head %.4f rad; wheel angle "
        "%.2f rad (%.1f turns of the driver's range), unwrapped within %.4f rad\n",
        static_cast<unsigned long long>(run_ticks), worst_left, worst_right, worst_head, rig.hil->plant().q_rad()[0],
        rig.hil->plant().q_rad()[0] / (2 * std::numbers::pi), worst_unwrap);
    CHECK(rig.loop->phase() == Phase::kHold);  // the trajectory ended
    CHECK(worst_left < 0.55 + 0.45);
    CHECK(worst_right < 0.32 + 0.1);
    CHECK(worst_head < 0.05);
    // Both wheels crossed their drivers' range ends (+-pi): the left one twice, the right once.
    CHECK(rig.hil->plant().q_rad()[0] > 3 * std::numbers::pi);
    CHECK(rig.hil->plant().q_rad()[1] < -std::numbers::pi);
    CHECK(worst_unwrap < 0.01);  // speed x 2 ticks estimate error and quantisation; never a turn (6.28)
    CHECK(rig.loop->supervisor().mode == Mode::kNominal);
    CHECK(rig.loop->supervisor().counts[safety::Cause::kInvalidSample] == 0);
    CHECK(rig.loop->supervisor().counts[safety::Cause::kStaleSample] == 0);
    // Hold: the wheels brake to zero speed.
    for (int k = 0; k < 200; ++k) rig.Tick();
    CHECK(std::abs(rig.hil->plant().dq_rad_s()[0]) < 0.05);
    // Shutdown: damping (kp 0, dq_des 0, the damping gain), then motor off.
    rig.loop->RequestStop();
    rig.Until(Phase::kDone, 400);
    for (std::size_t k = 0; k < 3; ++k) CHECK_FALSE(rig.hil->devices().motor(k).motor_mode);
    CHECK(rig.allocations == 0);
    REQUIRE(rig.recorder->Stop().ok());
    CHECK(rig.recorder->dropped() == 0);
    ticks = rig.tick;
  }
  // The recorded run replays to bit-identical commands.
  auto log = loop::ReadLog(log_path);
  REQUIRE_MESSAGE(log.ok(), log.error().message);
  auto t = loop::RobotTrajectory(m);
  REQUIRE(t.ok());
  loop::TrajectorySource source(m, *t);
  auto replay = loop::Replay(m, *log, &source, kTrajectoryHash);
  REQUIRE_MESSAGE(replay.ok(), replay.error().message);
  CHECK(replay->ticks == ticks);
  CHECK(replay->compared == ticks);
  CHECK_MESSAGE(replay->mismatches == 0, replay->first_mismatch);
}
