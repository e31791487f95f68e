// The quadruped on a stand over CAN, in HIL (label `vcan`: needs AF_CAN and vcan0/vcan1, e.g.
// inside tests/vm/vcan-vm; without them these tests fail, loudly). The stand-test controller
// (firmware/quadruped) and the stand HIL (sim_hil: Simbody plant + emulated MIT drivers and
// IMU) run in one thread in lock-step: each controller tick waits for the frames the HIL sent
// in its last tick and each HIL tick for the frames the controller just sent, over real
// SocketCAN sockets. Simulated time is the tick count (1 kHz).
#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "firmware/quadruped/stand_controller.hpp"
#include "runtime/core/alloc_probe.hpp"
#include "runtime/robot/can_map.hpp"
#include "runtime/robot/urdf.hpp"
#include "runtime/transport/can/mit_codec.hpp"
#include "runtime/transport/can/socketcan.hpp"
#include "sim_hil/quadruped_stand_hil.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;
using firmware::Phase;
using safety::Mode;

namespace {

constexpr std::int64_t kWaitNs = 500'000'000;  // lock-step wait per tick (the VM is slow)

std::string Vcan(int i) {
  const char* env = std::getenv(i == 0 ? "PBPPO_VCAN0" : "PBPPO_VCAN1");
  return env != nullptr ? env : (i == 0 ? "vcan0" : "vcan1");
}

struct Rig {
  robot::RobotDescription robot;
  robot::CanMap map;
  std::unique_ptr<sim::StandHil> hil;
  std::unique_ptr<firmware::StandController> ctl;
  std::uint64_t ctl_allocations = 0;
  bool count_allocations = false;

  Rig(sim::StandHilOptions h, firmware::StandControllerOptions c) {
    auto d = robot::LoadRobotDescription(test::SourcePath("models/quadruped/quadruped.yaml"));
    REQUIRE_MESSAGE(d.ok(), d.error().message);
    robot = std::move(*d);
    auto m = robot::LoadCanMap(test::SourcePath("models/quadruped/can_map.yaml"));
    REQUIRE_MESSAGE(m.ok(), m.error().message);
    map = std::move(*m);
    h.interfaces = {Vcan(0), Vcan(1)};
    c.interfaces = {Vcan(0), Vcan(1)};
    auto hr = sim::StandHil::Make(robot, map, h);
    REQUIRE_MESSAGE(hr.ok(), hr.error().message);
    hil = std::move(*hr);
    auto cr = firmware::StandController::Make(robot, map, c);
    REQUIRE_MESSAGE(cr.ok(), cr.error().message);
    ctl = std::move(*cr);
  }

  void Tick() {
    std::uint32_t from_hil[2] = {hil->sent_last_tick(0), hil->sent_last_tick(1)};
    {
      AllocationScope scope;
      ctl->Tick(from_hil, kWaitNs);
      if (count_allocations) ctl_allocations += scope.count();
    }
    std::uint32_t from_ctl[2] = {ctl->sent_last_tick(0), ctl->sent_last_tick(1)};
    REQUIRE(hil->Tick(from_ctl, kWaitNs));
  }

  // Runs until the controller is in `phase` (or `limit` ticks); returns the ticks run.
  int RunUntil(Phase phase, int limit) {
    int k = 0;
    for (; k < limit && ctl->phase() != phase; ++k) Tick();
    return k;
  }

  double MaxPoseError() const {
    double e = 0;
    for (std::size_t j = 0; j < robot.joint_count(); ++j)
      e = std::max(e, std::abs(hil->plant().q_rad(j) - robot.default_q_rad[j]));
    return e;
  }
};

firmware::StandControllerOptions WithTrajectory(const robot::RobotDescription& robot, double duration_s = 0) {
  firmware::StandControllerOptions c;
  auto t = firmware::LoadTrajectory(test::SourcePath("models/quadruped/stand_trajectory.yaml"), robot);
  REQUIRE_MESSAGE(t.ok(), t.error().message);
  c.has_trajectory = true;
  c.trajectory = *t;
  if (duration_s > 0) c.trajectory.duration_s = duration_s;  // shorter runs keep the VM test short
  return c;
}

robot::RobotDescription Robot() {
  auto d = robot::LoadRobotDescription(test::SourcePath("models/quadruped/quadruped.yaml"));
  REQUIRE_MESSAGE(d.ok(), d.error().message);
  return *d;
}

std::unique_ptr<can::SocketCanBus> Injector(int i) {
  can::SocketCanOptions o;
  o.interface = Vcan(i);
  o.fd = true;
  auto r = can::SocketCanBus::Open(o);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  return std::move(*r);
}

// Tracking bound of the stand-test PD (kp 150 Nm/rad, kd 2, velocity feed-forward, no gravity or
// acceleration feed-forward) on models/quadruped/stand_trajectory.yaml. The worst joint is a hind
// HFE (0.2 rad at 2 Hz, its knee sweeping 0.3 rad at 2 Hz); error terms, each divided by kp:
//   gravity              leg below the HFE, sum m l = 0.41 kg m: 0.41 * 9.81 / 150       = 0.027 rad
//   own inertia          I = 0.14 kg m^2 about the HFE: 0.14 * 0.2 * (4 pi)^2 / 150       = 0.030 rad
//   knee coupling        M12 = 0.047 kg m^2: 0.047 * 0.3 * (4 pi)^2 / 150                 = 0.015 rad
//   measurement delay    replies are 2 ticks old: 0.2 * 4 pi * 0.002                      = 0.005 rad
// sum 0.077 rad; the bound, 0.12 rad, leaves 50% for what is not estimated (Coriolis terms, the
// torque's 1 ms zero-order hold, quantisation). Front joints move at 1 Hz and stay far below it.
constexpr double kTrackingBoundRad = 0.12;

}  // namespace

TEST_CASE("stand HIL: arming - every motor answers - ramp reaches the default pose within 2 s simulated") {
  Rig rig({}, {});
  const int arm_ticks = rig.RunUntil(Phase::kRamp, 100);
  INFO("arming took ", arm_ticks, " ticks");
  REQUIRE(rig.ctl->phase() == Phase::kRamp);
  CHECK(arm_ticks <= 3);  // enter motor mode, replies, ramp
  for (std::size_t m = 0; m < 12; ++m) CHECK(rig.hil->motor(m).motor_mode);
  rig.RunUntil(Phase::kHold, 2000);
  const std::uint64_t reached = rig.ctl->tick();
  for (int k = 0; k < 200; ++k) rig.Tick();  // settle in hold
  const double err = rig.MaxPoseError();
  std::printf(
      "stand HIL: default pose reached (ramp done) at %.3f s simulated; largest joint error after 0.2 s hold "
      "%.4f rad\n",
      static_cast<double>(reached) * 1e-3, err);
  CHECK(reached <= 2000);
  // Gravity sag of a PD without gravity compensation: (m g l)/kp = 2.1 kg * 9.81 * 0.3 m / 150 = 0.041 rad.
  CHECK(err < 0.045);
  CHECK(rig.ctl->supervisor().mode == Mode::kNominal);
  CHECK(rig.ctl->imu_samples() >= 1200);  // one sample per HIL tick
  CHECK(rig.ctl->imu().accel_m_s2[2] == doctest::Approx(9.81).epsilon(0.001));
}

TEST_CASE(
    "stand HIL: sinusoids tracked within the bound - every command answered - no allocation - DBC decode of "
    "the candump log matches what the controller sent") {
  const auto robot = Robot();
  auto copts = WithTrajectory(robot);
  const std::string dir = test::ScratchDir("stand_hil_sinusoid");
  copts.candump_path = dir + "/stand.candump.log";
  copts.command_record_capacity = 12 * 6000;
  Rig rig({}, copts);
  rig.RunUntil(Phase::kTrajectory, 3000);
  REQUIRE(rig.ctl->phase() == Phase::kTrajectory);
  rig.count_allocations = true;
  const auto t0 = std::chrono::steady_clock::now();
  const int ticks = rig.RunUntil(Phase::kHold, 3000);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  rig.count_allocations = false;
  REQUIRE(rig.ctl->phase() == Phase::kHold);
  std::printf("stand HIL lock-step over CAN: %d ticks (%.3f s simulated) in %.3f s wall: %.3f simulated s per wall s\n",
              ticks, ticks * 1e-3, wall, ticks * 1e-3 / wall);
  double worst = 0;
  for (std::size_t j = 0; j < 12; ++j) {
    INFO(rig.robot.joint_names[j]);
    worst = std::max(worst, rig.ctl->max_tracking_error_rad(j));
    CHECK(rig.ctl->max_tracking_error_rad(j) < kTrackingBoundRad);
  }
  std::printf("stand HIL: sinusoid tracking error: max %.4f rad, RMS %.4f rad over %llu ticks\n", worst,
              rig.ctl->rms_tracking_error_rad(), static_cast<unsigned long long>(rig.ctl->trajectory_ticks()));
  CHECK(rig.ctl->supervisor().mode == Mode::kNominal);
  CHECK(rig.ctl_allocations == 0);

  // Every command answered: every frame the controller sent reached its driver, which replied.
  rig.ctl->Tick(std::vector<std::uint32_t>{rig.hil->sent_last_tick(0), rig.hil->sent_last_tick(1)}.data(), kWaitNs);
  for (std::size_t m = 0; m < 12; ++m) {
    INFO("motor ", m);
    const auto& s = rig.hil->motor(m);
    CHECK(s.frames + 0 == rig.ctl->commands_sent(m) - 1);  // the last tick's commands are still in flight
    CHECK(s.replies == s.frames);
    CHECK(rig.ctl->replies(m) == s.replies);
  }
  for (std::size_t b = 0; b < 2; ++b) {
    CHECK(rig.ctl->bus_stats(b).tx_dropped == 0);
    CHECK(rig.ctl->bus_stats(b).wrong_lengths == 0);
    CHECK(rig.hil->bus_stats(b).tx_dropped == 0);
  }

  // The candump log, decoded with python3-canmatrix through the DBC, equals what the controller sent.
  rig.ctl->Stop();
  CHECK(rig.ctl->candump_dropped() == 0);
  CHECK(rig.ctl->records_dropped() == 0);
  {
    std::ofstream out(dir + "/commands.txt");
    out.precision(17);
    for (const auto& r : rig.ctl->RecordedCommands())
      out << r.tick << ' ' << rig.map.motors[r.motor].joint << ' ' << r.q_rad << ' ' << r.dq_rad_s << ' ' << r.kp << ' '
          << r.kd << ' ' << r.tau_nm << '\n';
  }
  const std::string cmd = "/usr/bin/python3 " + test::SourcePath("tests/sim_hil/check_stand_dbc.py") + " " + dir +
                          "/stand.candump.log " + dir + "/commands.txt " +
                          test::SourcePath("models/quadruped/quadruped.dbc");
  CHECK(std::system(cmd.c_str()) == 0);
}

TEST_CASE(
    "stand HIL: a motor stops answering - the supervisor damps within 3 ticks and names the motor - e-stop "
    "after 500") {
  sim::StandHilOptions h;
  h.silent_motor = 2;  // LF_KFE
  h.silent_from_tick = 1500;
  firmware::StandControllerOptions c;
  c.command_record_capacity = 12 * 2000;
  Rig rig(h, c);
  for (int k = 0; k < 1560; ++k) rig.Tick();  // past the silent driver's 50-tick watchdog
  const auto& sup = rig.ctl->supervisor();
  REQUIRE(sup.mode == Mode::kSafeStop);
  const auto& entered = sup.entered[static_cast<int>(Mode::kSafeStop)];
  const std::uint64_t at = sup.entered_tick[static_cast<int>(Mode::kSafeStop)];
  std::printf("stand HIL: LF_KFE silent from tick 1500: %s at tick %llu; degraded at tick %llu\n",
              safety::Describe(rig.ctl->supervisor_model(), entered).c_str(), static_cast<unsigned long long>(at),
              static_cast<unsigned long long>(sup.entered_tick[static_cast<int>(Mode::kDegraded)]));
  CHECK(at > 1500);
  CHECK(at <= 1503);
  CHECK(entered.fault == safety::Fault::kStaleFeedback);
  CHECK(entered.channel == 2);
  CHECK(rig.ctl->supervisor_model().channel_names[2] == "LF_KFE");
  // The commands since then are damping: kp 0, kd = the damping gain, no feed-forward.
  const auto& rec = rig.ctl->RecordedCommands();
  REQUIRE(!rec.empty());
  for (const auto& r : rec) {
    if (r.tick < at) continue;
    CHECK(r.kp == 0.0);
    CHECK(r.kd == rig.robot.damping_kd_nm_s_rad);
    CHECK(r.tau_nm == 0.0);
  }
  // The silent driver's watchdog cuts its torque.
  CHECK(rig.hil->motor(2).timeouts > 0);
  CHECK(rig.hil->plant().tau_nm(2) == 0.0);
  // Still silent after 500 ticks: e-stop, every other driver is switched out of motor mode.
  for (int k = 0; k < 450; ++k) rig.Tick();
  REQUIRE(sup.mode == Mode::kEStop);
  CHECK(sup.entered_tick[static_cast<int>(Mode::kEStop)] == 1500 + 500);
  CHECK(sup.entered[static_cast<int>(Mode::kEStop)].channel == 2);
  for (std::size_t m = 0; m < 12; ++m)
    if (m != 2) CHECK_FALSE(rig.hil->motor(m).motor_mode);
}

TEST_CASE("stand HIL: 10% of frames dropped by the drivers - tracking degrades but stays safe") {
  const auto robot = Robot();
  // Clean run for the reference tracking error.
  double clean_rms = 0;
  {
    Rig rig({}, WithTrajectory(robot, 1.0));
    rig.RunUntil(Phase::kTrajectory, 3000);
    rig.RunUntil(Phase::kHold, 3000);
    clean_rms = rig.ctl->rms_tracking_error_rad();
  }
  sim::StandHilOptions h;
  h.drop_probability = 0.10;
  h.max_drop_burst = 2;  // see below
  h.seed = 7;
  Rig rig(h, WithTrajectory(robot, 1.0));
  rig.RunUntil(Phase::kTrajectory, 3000);
  REQUIRE(rig.ctl->phase() == Phase::kTrajectory);
  rig.RunUntil(Phase::kHold, 3000);
  REQUIRE(rig.ctl->phase() == Phase::kHold);
  std::uint64_t dropped = 0, frames = 0;
  for (std::size_t m = 0; m < 12; ++m) {
    dropped += rig.hil->motor(m).dropped;
    frames += rig.hil->motor(m).dropped + rig.hil->motor(m).frames;
  }
  const double rate = static_cast<double>(dropped) / static_cast<double>(frames);
  double worst = 0;
  for (std::size_t j = 0; j < 12; ++j) worst = std::max(worst, rig.ctl->max_tracking_error_rad(j));
  const auto& sup = rig.ctl->supervisor();
  std::printf("stand HIL, %.1f%% of frames dropped: tracking RMS %.4f rad (clean %.4f), max %.4f rad; mode %s (%s)\n",
              100 * rate, rig.ctl->rms_tracking_error_rad(), clean_rms, worst, safety::ToString(sup.mode),
              safety::Describe(rig.ctl->supervisor_model(), sup.entered[1]).c_str());
  CHECK(rate > 0.08);
  CHECK(rate < 0.12);
  CHECK(rig.ctl->rms_tracking_error_rad() > clean_rms);  // degrades
  CHECK(worst < 2 * kTrackingBoundRad);                  // but stays bounded
  // A lost reply is a stale motor for a tick or two: degraded, never worse. (A driver that stays
  // silent for 3 ticks is indistinguishable from a dead one and is stopped: hence the bounded
  // bursts of this loss model.)
  CHECK(sup.mode == Mode::kDegraded);
  CHECK(sup.entered[1].fault == safety::Fault::kStaleFeedback);
  CHECK(sup.ticks_in_mode[static_cast<int>(Mode::kSafeStop)] == 0);
}

TEST_CASE("stand HIL: unknown identifiers and wrong lengths are counted and ignored on both sides") {
  firmware::StandControllerOptions c;
  c.receive_all = true;  // no kernel filter, so strays reach the dispatcher
  Rig rig({}, c);
  auto inj0 = Injector(0);
  auto inj1 = Injector(1);
  rig.RunUntil(Phase::kHold, 2000);
  const can::BusStats c0 = rig.ctl->bus_stats(0), h1 = rig.hil->bus_stats(1);
  const int kStrays = 50;
  for (int k = 0; k < kStrays; ++k) {
    can::CanFrame unknown;
    unknown.id = 0x3F0;
    unknown.len = 8;
    can::CanFrame short_reply;  // LF_HAA's reply identifier, 4 bytes
    short_reply.id = 0x101;
    short_reply.len = 4;
    can::CanFrame short_cmd;  // LH_HAA's command identifier, 3 bytes
    short_cmd.id = 0x007;
    short_cmd.len = 3;
    const can::CanFrame f0[] = {unknown, short_reply};
    const can::CanFrame f1[] = {short_cmd};
    REQUIRE(inj0->Send(f0) == 2);
    REQUIRE(inj1->Send(f1) == 1);
    rig.Tick();
  }
  rig.Tick();
  CHECK(rig.ctl->bus_stats(0).unknown_ids - c0.unknown_ids == kStrays);
  CHECK(rig.ctl->bus_stats(0).wrong_lengths - c0.wrong_lengths == kStrays);
  CHECK(rig.hil->bus_stats(1).wrong_lengths - h1.wrong_lengths == kStrays);
  CHECK(rig.hil->bus_stats(0).unknown_ids > 0);                  // the HIL sees the stray 0x3F0 too
  CHECK(rig.hil->motor(6).replies == rig.hil->motor(6).frames);  // no reply to the short command
  CHECK(rig.ctl->supervisor().mode == Mode::kNominal);
  CHECK(rig.MaxPoseError() < 0.045);
}

TEST_CASE("stand HIL: bus-off on one bus (an error frame) - safe-stop naming the bus") {
  Rig rig({}, {});
  auto inj = Injector(1);
  rig.RunUntil(Phase::kHold, 2000);
  REQUIRE(rig.ctl->supervisor().mode == Mode::kNominal);
  can::CanFrame e;
  e.flags = can::kFlagError;
  e.id = 0x40;  // CAN_ERR_BUSOFF
  e.len = 8;
  REQUIRE(inj->Send({&e, 1}) == 1);
  const std::uint64_t sent_at = rig.ctl->tick();
  for (int k = 0; k < 5; ++k) rig.Tick();
  const auto& sup = rig.ctl->supervisor();
  REQUIRE(sup.mode == Mode::kSafeStop);
  std::printf("stand HIL: bus-off injected before tick %llu: %s at tick %llu\n",
              static_cast<unsigned long long>(sent_at),
              safety::Describe(rig.ctl->supervisor_model(), sup.entered[2]).c_str(),
              static_cast<unsigned long long>(sup.entered_tick[2]));
  CHECK(sup.entered_tick[2] == sent_at);
  CHECK(sup.entered[2].fault == safety::Fault::kTransportFault);
  CHECK(sup.entered[2].transport == 1);
  CHECK(rig.ctl->bus_stats(1).is_bus_off);
}

TEST_CASE("stand HIL: shutdown request - damping - then every motor out of motor mode") {
  Rig rig({}, {});
  rig.RunUntil(Phase::kHold, 2000);
  rig.ctl->RequestShutdown();
  rig.RunUntil(Phase::kDone, 1000);
  REQUIRE(rig.ctl->phase() == Phase::kDone);
  const std::uint64_t damping =
      rig.ctl->phase_start_tick(Phase::kMotorOff) - rig.ctl->phase_start_tick(Phase::kShutdownDamping);
  CHECK(damping == 500);
  for (std::size_t m = 0; m < 12; ++m) CHECK_FALSE(rig.hil->motor(m).motor_mode);
  CHECK(rig.ctl->supervisor().mode == Mode::kNominal);
}
