// The quadruped on a stand over CAN, in HIL (label `vcan`: needs AF_CAN and vcan0/vcan1, e.g.
// inside tests/vm/vcan-vm; without them these tests fail, loudly). The controller (runtime/loop
// over the CAN transport, the stand trajectory as its command source) and the stand HIL (sim_hil:
// Simbody plant + emulated MIT drivers and IMU) run in one thread in lock-step: each controller tick waits for the
// frames the HIL sent in its last tick and each HIL tick for the frames the controller just sent, over real SocketCAN
// sockets. Simulated time is the tick count (1 kHz).
#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/loop/log.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/loop/replay.hpp"
#include "runtime/loop/trajectory_source.hpp"
#include "runtime/transport/can/can_transport.hpp"
#include "runtime/transport/can/socketcan.hpp"
#include "sim_hil/quadruped_hil.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;
using loop::Phase;
using safety::Cause;
using safety::Mode;

namespace {

constexpr std::int64_t kWaitNs = 500'000'000;  // lock-step wait per tick (the VM is slow)

std::string Vcan(int i) {
  const char* env = std::getenv(i == 0 ? "PBPPO_VCAN0" : "PBPPO_VCAN1");
  return env != nullptr ? env : (i == 0 ? "vcan0" : "vcan1");
}

struct ControllerOptions {
  bool trajectory = false;
  double duration_s = 0;  // > 0: a shorter trajectory (keeps the VM test short)
  bool receive_all = false;
  std::string candump_path, record_path;
  std::size_t command_record_capacity = 0;
};

// The quadruped's model (loaded once per process), the stand HIL and the controller: runtime/loop
// over the CAN transport, with the stand trajectory as its command source or none.
struct Rig {
  const robot::RobotModel& model;
  std::unique_ptr<sim::QuadrupedHil> hil;
  std::unique_ptr<loop::TrajectorySource> source;
  std::unique_ptr<can::CanTransport> can;
  robot::RobotData data;
  std::unique_ptr<loop::LoopData> loop;
  std::unique_ptr<loop::Recorder> recorder;
  robot::Transport* transports[1] = {};
  std::uint64_t tick = 0;
  std::uint64_t ctl_allocations = 0;
  bool count_allocations = false;

  Rig(sim::QuadrupedHilOptions h, const ControllerOptions& c, const robot::RobotModel& m = test::QuadrupedRobot())
      : model(m), data(robot::MakeRobotData(model)) {
    h.interfaces = {Vcan(0), Vcan(1)};
    auto hr = sim::QuadrupedHil::Make(model, h);
    REQUIRE_MESSAGE(hr.ok(), hr.error().message);
    hil = std::move(*hr);
    can::CanTransportOptions co;
    co.interfaces = {Vcan(0), Vcan(1)};
    co.receive_all = c.receive_all;
    co.candump_path = c.candump_path;
    co.command_record_capacity = c.command_record_capacity;
    auto cr = can::CanTransport::Open(model, "can", co);
    REQUIRE_MESSAGE(cr.ok(), cr.error().message);
    can = std::move(*cr);
    can->SetLockStep(kWaitNs);
    transports[0] = can.get();
    if (c.trajectory) {
      auto t = loop::RobotTrajectory(model);
      REQUIRE_MESSAGE(t.ok(), t.error().message);
      if (c.duration_s > 0) t->duration_s = c.duration_s;
      source = std::make_unique<loop::TrajectorySource>(model, *t);
    }
    loop = loop::MakeLoopData(model, source.get());
    if (!c.record_path.empty()) {
      auto r = loop::Recorder::Open(c.record_path, model,
                                    loop::MakeLogHeader(model, loop::SourceKind::kTrajectory, TrajectoryHash(c)));
      REQUIRE_MESSAGE(r.ok(), r.error().message);
      recorder = std::move(*r);
      REQUIRE(loop::AttachRecorder(model, data, *loop, recorder.get()).ok());
    }
    loop->Arm();
  }

  static std::uint64_t TrajectoryHash(const ControllerOptions& c) { return c.trajectory ? 1 : 0; }

  // One controller tick (waiting for the frames the HIL sent in its last tick), then one HIL tick
  // (waiting for the frames the controller just sent).
  void Tick() {
    const std::uint32_t from_hil[2] = {hil->sent_last_tick(0), hil->sent_last_tick(1)};
    can->Expect(from_hil);
    {
      AllocationScope scope;
      rt::TickTiming timing;
      timing.tick = tick++;
      (void)loop::Tick(model, data, *loop, transports, timing);
      if (count_allocations) ctl_allocations += scope.count();
    }
    const std::uint32_t from_ctl[2] = {can->sent_last_tick(0), can->sent_last_tick(1)};
    REQUIRE(hil->Tick(from_ctl, kWaitNs));
  }

  // Runs until the loop is in `phase` (or `limit` ticks); returns the ticks run.
  int RunUntil(Phase phase, int limit) {
    int k = 0;
    for (; k < limit && loop->phase() != phase; ++k) Tick();
    return k;
  }

  const safety::SupervisorState& supervisor() const { return loop->supervisor(); }
  std::string Describe(Mode mode) const {
    return safety::Describe(model.supervisor_model, supervisor().entered[static_cast<std::size_t>(mode)]);
  }

  double MaxPoseError() const {
    double e = 0;
    for (std::size_t j = 0; j < model.body->joint_count(); ++j)
      e = std::max(e, std::abs(hil->plant().q_rad(j) - model.body->default_q_rad[j]));
    return e;
  }
};

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

TEST_CASE("stand HIL: arming - every motor answers - stand-up reaches the default pose within 2 s simulated") {
  Rig rig({}, {});
  const int arm_ticks = rig.RunUntil(Phase::kStandUp, 100);
  INFO("arming took ", arm_ticks, " ticks");
  REQUIRE(rig.loop->phase() == Phase::kStandUp);
  CHECK(arm_ticks <= 3);  // enter motor mode, replies, stand-up
  for (std::size_t m = 0; m < 12; ++m) CHECK(rig.hil->motor(m).motor_mode);
  rig.RunUntil(Phase::kHold, 2000);
  const std::uint64_t reached = rig.tick;
  for (int k = 0; k < 200; ++k) rig.Tick();  // settle in hold (with no source, the loop holds the pose)
  const double err = rig.MaxPoseError();
  std::printf(
      "stand HIL: default pose reached (stand-up done) at %.3f s simulated; largest joint error after 0.2 s hold "
      "%.4f rad\n",
      static_cast<double>(reached) * 1e-3, err);
  CHECK(reached <= 2000);
  // Gravity sag of a PD without gravity compensation: (m g l)/kp = 2.1 kg * 9.81 * 0.3 m / 150 = 0.041 rad.
  CHECK(err < 0.045);
  CHECK(rig.supervisor().mode == Mode::kNominal);
  CHECK(rig.can->imu_samples() >= 1200);  // one sample per HIL tick
  CHECK(rig.can->imu().accel_m_s2[2] == doctest::Approx(9.81).epsilon(0.001));
}

TEST_CASE(
    "stand HIL: sinusoids tracked within the bound - every command answered - no allocation - DBC decode of "
    "the candump log matches what the controller sent") {
  const std::string dir = test::ScratchDir("stand_hil_sinusoid");
  ControllerOptions c;
  c.trajectory = true;
  c.candump_path = dir + "/stand.candump.log";
  c.command_record_capacity = 12 * 6000;
  Rig rig({}, c);
  rig.RunUntil(Phase::kRun, 3000);
  REQUIRE(rig.loop->phase() == Phase::kRun);
  rig.count_allocations = true;
  const auto t0 = std::chrono::steady_clock::now();
  const int ticks = rig.RunUntil(Phase::kHold, 3000);  // the trajectory ended: the default pose again
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  rig.count_allocations = false;
  REQUIRE(rig.loop->phase() == Phase::kHold);
  std::printf("stand HIL lock-step over CAN: %d ticks (%.3f s simulated) in %.3f s wall: %.3f simulated s per wall s\n",
              ticks, ticks * 1e-3, wall, ticks * 1e-3 / wall);
  double worst = 0;
  for (std::size_t j = 0; j < 12; ++j) {
    INFO(rig.model.motors[j].joint);
    worst = std::max(worst, rig.source->max_tracking_error_rad(j));
    CHECK(rig.source->max_tracking_error_rad(j) < kTrackingBoundRad);
  }
  std::printf("stand HIL: sinusoid tracking error: max %.4f rad, RMS %.4f rad over %llu ticks\n", worst,
              rig.source->rms_tracking_error_rad(), static_cast<unsigned long long>(rig.source->ticks()));
  CHECK(rig.supervisor().mode == Mode::kNominal);
  CHECK(rig.ctl_allocations == 0);

  // Every command answered: every frame the controller sent reached its driver, which replied.
  const std::uint32_t from_hil[2] = {rig.hil->sent_last_tick(0), rig.hil->sent_last_tick(1)};
  rig.can->Expect(from_hil);
  rt::TickTiming timing;
  timing.tick = rig.tick++;
  (void)loop::Tick(rig.model, rig.data, *rig.loop, rig.transports, timing);
  for (std::size_t m = 0; m < 12; ++m) {
    INFO("motor ", m);
    const auto& s = rig.hil->motor(m);
    CHECK(s.frames + 0 == rig.can->commands_sent(m) - 1);  // the last tick's commands are still in flight
    CHECK(s.replies == s.frames);
    CHECK(rig.can->replies(m) == s.replies);
  }
  for (std::size_t b = 0; b < 2; ++b) {
    CHECK(rig.can->bus_stats(b).tx_dropped == 0);
    CHECK(rig.can->bus_stats(b).wrong_lengths == 0);
    CHECK(rig.hil->bus_stats(b).tx_dropped == 0);
  }

  // The candump log, decoded with python3-canmatrix through the DBC, equals what the controller sent.
  rig.can->Stop();
  CHECK(rig.can->candump_dropped() == 0);
  CHECK(rig.can->records_dropped() == 0);
  {
    std::ofstream out(dir + "/commands.txt");
    out.precision(17);
    for (const auto& r : rig.can->RecordedCommands())
      out << r.tick << ' ' << rig.model.motors[r.motor].joint << ' ' << r.q_rad << ' ' << r.dq_rad_s << ' ' << r.kp
          << ' ' << r.kd << ' ' << r.tau_nm << '\n';
  }
  const std::string cmd = "/usr/bin/python3 " + test::SourcePath("tests/sim_hil/check_stand_dbc.py") + " " + dir +
                          "/stand.candump.log " + dir + "/commands.txt " +
                          test::SourcePath("models/quadruped/quadruped.dbc");
  CHECK(std::system(cmd.c_str()) == 0);
}

TEST_CASE("stand HIL: a recorded run over vcan replays to bit-identical commands") {
  const std::string dir = test::ScratchDir("stand_hil_replay");
  ControllerOptions c;
  c.trajectory = true;
  c.duration_s = 0.3;
  c.record_path = dir + "/stand.log";
  std::uint64_t ticks = 0;
  {
    Rig rig({}, c);
    rig.RunUntil(Phase::kRun, 3000);
    rig.RunUntil(Phase::kHold, 1000);
    rig.loop->RequestStop();
    rig.RunUntil(Phase::kDone, 1000);
    REQUIRE(rig.loop->phase() == Phase::kDone);
    REQUIRE(rig.recorder->Stop().ok());
    CHECK(rig.recorder->dropped() == 0);
    ticks = rig.tick;
  }
  auto log = loop::ReadLog(c.record_path);
  REQUIRE_MESSAGE(log.ok(), log.error().message);
  CHECK(log->complete);
  auto t = loop::RobotTrajectory(test::QuadrupedRobot());
  REQUIRE(t.ok());
  t->duration_s = c.duration_s;
  loop::TrajectorySource source(test::QuadrupedRobot(), *t);
  auto replay = loop::Replay(test::QuadrupedRobot(), *log, &source, 1);
  REQUIRE_MESSAGE(replay.ok(), replay.error().message);
  std::printf("stand HIL: %llu recorded ticks replayed, %llu outputs compared, %llu different\n",
              static_cast<unsigned long long>(replay->ticks), static_cast<unsigned long long>(replay->compared),
              static_cast<unsigned long long>(replay->mismatches));
  CHECK(replay->ticks == ticks);
  CHECK(replay->compared == ticks);
  CHECK_MESSAGE(replay->mismatches == 0, replay->first_mismatch);
  const std::string text = loop::FormatOutputs(test::QuadrupedRobot(), replay->outputs);
  CHECK(text.find(",run,") != std::string::npos);
  CHECK(text.find(",motor-off,") != std::string::npos);
}

TEST_CASE(
    "stand HIL: a motor stops answering - the supervisor damps within 3 ticks and names the motor - e-stop "
    "after 500") {
  sim::QuadrupedHilOptions h;
  sim::HilFault silent;
  silent.kind = sim::HilFaultKind::kSilentMotor;
  silent.motor = 2;  // LF_KFE
  silent.tick = 1500;
  h.faults = {silent};
  ControllerOptions c;
  c.command_record_capacity = 12 * 2000;
  Rig rig(h, c);
  for (int k = 0; k < 1560; ++k) rig.Tick();  // past the silent driver's 50-tick watchdog
  const auto& sup = rig.supervisor();
  REQUIRE(sup.mode == Mode::kSafeStop);
  const auto& entered = sup.entered[static_cast<int>(Mode::kSafeStop)];
  const std::uint64_t at = sup.entered_tick[static_cast<int>(Mode::kSafeStop)];
  std::printf("stand HIL: LF_KFE silent from tick 1500: %s at tick %llu; degraded at tick %llu\n",
              rig.Describe(Mode::kSafeStop).c_str(), static_cast<unsigned long long>(at),
              static_cast<unsigned long long>(sup.entered_tick[static_cast<int>(Mode::kDegraded)]));
  CHECK(at > 1500);
  CHECK(at <= 1503);
  CHECK(entered.cause == Cause::kStaleSample);
  const auto lf_kfe = static_cast<std::int32_t>(rig.model.motors[2].stream);
  CHECK(entered.subject == lf_kfe);
  CHECK(rig.model.supervisor_model.streams[static_cast<std::size_t>(lf_kfe)].name == "LF_KFE");
  CHECK(rig.Describe(Mode::kSafeStop) == "safe-stop: stale sample: LF_KFE: age 3 ticks > 2");
  // The commands since then are damping: kp 0, kd = the damping gain, no feed-forward.
  const auto& rec = rig.can->RecordedCommands();
  REQUIRE(!rec.empty());
  for (const auto& r : rec) {
    if (r.tick < at) continue;
    CHECK(r.kp == 0.0);
    CHECK(r.kd == rig.model.body->damping_kd_nm_s_rad);
    CHECK(r.tau_nm == 0.0);
  }
  // The silent driver's watchdog cuts its torque.
  CHECK(rig.hil->motor(2).timeouts > 0);
  CHECK(rig.hil->plant().tau_nm(2) == 0.0);
  // Still silent after 500 ticks: e-stop (lost), every other driver is switched out of motor mode.
  for (int k = 0; k < 450; ++k) rig.Tick();
  REQUIRE(sup.mode == Mode::kEStop);
  CHECK(sup.entered_tick[static_cast<int>(Mode::kEStop)] == 1500 + 500);
  CHECK(sup.entered[static_cast<int>(Mode::kEStop)].cause == Cause::kLostPeer);
  CHECK(sup.entered[static_cast<int>(Mode::kEStop)].subject == lf_kfe);
  for (std::size_t m = 0; m < 12; ++m)
    if (m != 2) CHECK_FALSE(rig.hil->motor(m).motor_mode);
}

TEST_CASE("stand HIL: 10% of frames dropped by the drivers - tracking degrades but stays safe") {
  ControllerOptions c;
  c.trajectory = true;
  c.duration_s = 1.0;
  // Clean run for the reference tracking error.
  double clean_rms = 0;
  {
    Rig rig({}, c);
    rig.RunUntil(Phase::kRun, 3000);
    rig.RunUntil(Phase::kHold, 3000);
    clean_rms = rig.source->rms_tracking_error_rad();
  }
  sim::QuadrupedHilOptions h;
  sim::HilFault drop;
  drop.kind = sim::HilFaultKind::kDropFrames;
  drop.probability = 0.10;
  drop.max_burst = 2;  // see below
  h.faults = {drop};
  h.seed = 7;
  Rig rig(h, c);
  rig.RunUntil(Phase::kRun, 3000);
  REQUIRE(rig.loop->phase() == Phase::kRun);
  rig.RunUntil(Phase::kHold, 3000);
  REQUIRE(rig.loop->phase() == Phase::kHold);
  std::uint64_t dropped = 0, frames = 0;
  for (std::size_t m = 0; m < 12; ++m) {
    dropped += rig.hil->motor(m).dropped;
    frames += rig.hil->motor(m).dropped + rig.hil->motor(m).frames;
  }
  const double rate = static_cast<double>(dropped) / static_cast<double>(frames);
  double worst = 0;
  for (std::size_t j = 0; j < 12; ++j) worst = std::max(worst, rig.source->max_tracking_error_rad(j));
  const auto& sup = rig.supervisor();
  std::printf("stand HIL, %.1f%% of frames dropped: tracking RMS %.4f rad (clean %.4f), max %.4f rad; mode %s (%s)\n",
              100 * rate, rig.source->rms_tracking_error_rad(), clean_rms, worst, safety::ToString(sup.mode),
              rig.Describe(Mode::kDegraded).c_str());
  CHECK(rate > 0.08);
  CHECK(rate < 0.12);
  CHECK(rig.source->rms_tracking_error_rad() > clean_rms);  // degrades
  CHECK(worst < 2 * kTrackingBoundRad);                     // but stays bounded
  // A lost reply is a stale motor for a tick or two: degraded, never worse. (A driver that stays
  // silent for 3 ticks is indistinguishable from a dead one and is stopped: hence the bounded
  // bursts of this loss model.)
  CHECK(sup.mode == Mode::kDegraded);
  CHECK(sup.entered[1].cause == Cause::kStaleSample);
  CHECK(sup.ticks_in_mode[static_cast<int>(Mode::kSafeStop)] == 0);
}

TEST_CASE("stand HIL: unknown identifiers and wrong lengths are counted and ignored on both sides") {
  ControllerOptions c;
  c.receive_all = true;  // no kernel filter, so strays reach the dispatcher
  Rig rig({}, c);
  auto inj0 = Injector(0);
  auto inj1 = Injector(1);
  rig.RunUntil(Phase::kHold, 2000);
  const can::BusStats c0 = rig.can->bus_stats(0), h1 = rig.hil->bus_stats(1);
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
  CHECK(rig.can->bus_stats(0).unknown_ids - c0.unknown_ids == kStrays);
  CHECK(rig.can->bus_stats(0).wrong_lengths - c0.wrong_lengths == kStrays);
  CHECK(rig.hil->bus_stats(1).wrong_lengths - h1.wrong_lengths == kStrays);
  CHECK(rig.hil->bus_stats(0).unknown_ids > 0);                  // the HIL sees the stray 0x3F0 too
  CHECK(rig.hil->motor(6).replies == rig.hil->motor(6).frames);  // no reply to the short command
  CHECK(rig.supervisor().mode == Mode::kNominal);
  CHECK(rig.MaxPoseError() < 0.045);
}

namespace {

constexpr std::uint32_t kErrBusOff = 0x40, kErrRestarted = 0x100;  // CAN_ERR_BUSOFF, CAN_ERR_RESTARTED

// Holding on its stand, then an error frame of class `id` on bus 1 (as the bus's controller sends it).
std::unique_ptr<can::SocketCanBus> HoldThenError(Rig& rig, std::uint32_t id) {
  auto inj = Injector(1);
  rig.RunUntil(Phase::kHold, 2000);
  REQUIRE(rig.supervisor().mode == Mode::kNominal);
  can::CanFrame e;
  e.flags = can::kFlagError;
  e.id = id;
  e.len = 8;
  REQUIRE(inj->Send({&e, 1}) == 1);
  return inj;
}

}  // namespace

TEST_CASE("stand HIL: bus-off on one bus (an error frame) - safe-stop naming the bus") {
  Rig rig({}, {});
  auto inj = HoldThenError(rig, kErrBusOff);
  const std::uint64_t sent_at = rig.tick;
  for (int k = 0; k < 5; ++k) rig.Tick();
  const auto& sup = rig.supervisor();
  REQUIRE(sup.mode == Mode::kSafeStop);
  std::printf("stand HIL: bus-off injected before tick %llu: %s at tick %llu\n",
              static_cast<unsigned long long>(sent_at), rig.Describe(Mode::kSafeStop).c_str(),
              static_cast<unsigned long long>(sup.entered_tick[2]));
  CHECK(sup.entered_tick[2] == sent_at);
  CHECK(sup.entered[2].cause == Cause::kTransportFault);
  CHECK(sup.entered[2].subject == 1);
  CHECK(rig.model.supervisor_model.transport_names[1] == "can/hind");
  CHECK(rig.can->bus_stats(1).is_bus_off);
}

TEST_CASE("stand HIL: bus-off, then the bus restarted - the robot file's automatic rule: armed, stood up, holding") {
  static const robot::RobotModel automatic = [] {
    robot::RobotModel m = test::QuadrupedRobot();
    m.supervisor.recovery.automatic = true;
    m.supervisor.recovery.causes = 1u << static_cast<unsigned>(Cause::kTransportFault);
    return m;
  }();
  Rig rig({}, {}, automatic);
  auto inj = HoldThenError(rig, kErrBusOff);
  for (int k = 0; k < 5; ++k) rig.Tick();
  REQUIRE(rig.supervisor().mode == Mode::kSafeStop);
  for (int k = 0; k < 600; ++k) rig.Tick();  // still off: no re-arm however long
  CHECK(rig.loop->recovery().automatic == 0);
  can::CanFrame e;
  e.flags = can::kFlagError;
  e.id = kErrRestarted;
  e.len = 8;
  REQUIRE(inj->Send({&e, 1}) == 1);
  const std::uint64_t restarted_at = rig.tick;
  rig.RunUntil(Phase::kArming, 700);
  CHECK(rig.loop->recovery().automatic == 1);
  CHECK(rig.loop->recovery().last_tick >= restarted_at + automatic.supervisor.recovery.healthy_ticks);
  CHECK_FALSE(rig.can->bus_stats(1).is_bus_off);
  rig.RunUntil(Phase::kHold, 2500);
  REQUIRE(rig.loop->phase() == Phase::kHold);
  for (int k = 0; k < 100; ++k) rig.Tick();
  std::printf("stand HIL: bus restarted at tick %llu: %s; holding from tick %llu, pose error %.3f rad\n",
              static_cast<unsigned long long>(restarted_at), rig.loop->recovery().last,
              static_cast<unsigned long long>(rig.loop->phase_start(Phase::kHold)), rig.MaxPoseError());
  CHECK(rig.supervisor().mode == Mode::kNominal);
  CHECK(rig.MaxPoseError() < 0.05);
}

TEST_CASE("stand HIL: shutdown request - damping - then every motor out of motor mode") {
  Rig rig({}, {});
  rig.RunUntil(Phase::kHold, 2000);
  rig.loop->RequestStop();
  rig.RunUntil(Phase::kDone, 1000);
  REQUIRE(rig.loop->phase() == Phase::kDone);
  const std::uint64_t damping = rig.loop->phase_start(Phase::kMotorOff) - rig.loop->phase_start(Phase::kDamping);
  CHECK(damping == 500);
  for (std::size_t m = 0; m < 12; ++m) CHECK_FALSE(rig.hil->motor(m).motor_mode);
  CHECK(rig.supervisor().mode == Mode::kNominal);
}
