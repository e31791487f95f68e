// The quadruped driven from a gamepad in the Simbody HIL, natively: the shipped robot file
// models/quadruped_gamepad (a gamepad through evdev, its buttons the operator's requests) with a
// recorded event file in place of the pad's device (as --gamepad gives it), played on the
// controller's tick clock: models/quadruped_gamepad/sessions/demo.ev, one session: arm on START,
// walk on A with the dead-man (LB) held and the left stick forward, the dead-man released (the
// robot stands), walking again, e-stop on BACK (the motors damp, latched), re-armed on the Xbox
// button (passive), stood up on START, walking, and the pad gone mid-walk (the file's end: the
// robot stands). The controller's recording of the
// session replays bit for bit. sessions/switch.ev switches policy mid-walk, sessions/sit.ev sits
// the robot down and stands it up again.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "runtime/loop/log.hpp"
#include "runtime/loop/policy_set.hpp"
#include "runtime/loop/replay.hpp"
#include "runtime/loop/schedule.hpp"
#include "runtime/loop/source_files.hpp"
#include "runtime/transport/bindings.hpp"
#include "runtime/transport/evdev/evdev_transport.hpp"
#include "sim_hil/quadruped_rig.hpp"
#include "sim_hil/quadruped_scenario.hpp"
#include "tests/support/command_limits.hpp"
#include "tests/support/robot_models.hpp"

using namespace pbppo;
using loop::Phase;
using safety::Mode;

namespace {

const std::string kPolicy = "policies/frozen/quadruped_walk/flat.blob";

// The session's times (tools/gamepad_session.py wrote it): arm at 0.2 s, the dead-man at 1.8 and A
// at 1.9, 0.5 m/s from 2.1 to 7.5, the dead-man released at 8.5, walking again from 10.1 (0.5 m/s
// 10.5-12.0), released at 12.5, e-stop at 13.0, re-arm at 14.0, START at 14.5, walking from 16.1
// (0.5 m/s from 16.5), the pad gone after its last report at 18.0.
constexpr double kRelease1 = 8.5, kWalk2 = 10.1, kEStop = 13.0, kRearm = 14.0, kStand = 14.5, kWalk3 = 16.1,
                 kGone = 18.0;

std::size_t At(double t_s) {
  return static_cast<std::size_t>(std::llround(t_s / 0.001));
}

// A session (models/quadruped_gamepad/sessions/NAME.ev) played for `duration_s` through the rig,
// the controller recording; per tick its phase, mode and the largest step of a q command.
struct SessionRun {
  const robot::RobotModel& m = test::GamepadRobot();
  std::unique_ptr<robot::Transport> pad;
  std::unique_ptr<sim::QuadrupedRig> rig;
  std::string log_path;
  std::vector<Phase> phase;
  std::vector<Mode> mode;
  std::vector<double> q_step;  // max over the joints of |q_des(t) - q_des(t - 1)|

  SessionRun(const std::string& name, double duration_s, const std::vector<std::string>& switch_policies = {}) {
    const int op = m.TransportIndex("gamepad");
    REQUIRE(op >= 0);
    transport::Settings settings;
    settings.evdev.device = test::SourcePath("models/quadruped_gamepad/sessions/" + name + ".ev");
    auto opened = transport::Open(m, m.transports[static_cast<std::size_t>(op)], settings);
    REQUIRE_MESSAGE(opened.ok(), opened.error().message);
    pad = std::move(*opened);
    sim::RigOptions o;
    o.policy = test::SourcePath(kPolicy);
    for (const std::string& p : switch_policies) o.switch_policies.push_back(test::SourcePath(p));
    o.operator_transport = pad.get();
    o.command_record_capacity = At(duration_s) * m.motors.size();  // every command of the session
    auto schedule = loop::ParseSchedule(
        "stream: velocity_command\nphases:\n  - {name: session, duration_s: " + std::to_string(duration_s) + "}\n",
        "session", m);
    REQUIRE_MESSAGE(schedule.ok(), schedule.error().message);
    auto flat =
        sim::LoadQuadrupedScenario(test::SourcePath("models/quadruped/scenarios/flat.yaml"), m, m.tick_period_s);
    REQUIRE_MESSAGE(flat.ok(), flat.error().message);
    auto made = sim::QuadrupedRig::Make(m, flat->hil, std::move(*schedule), o);
    REQUIRE_MESSAGE(made.ok(), made.error().message);
    rig = std::move(*made);
    sim::QuadrupedRig& r = *rig;
    log_path = test::ScratchDir("gamepad_hil_" + name) + "/session.pbppolog";
    auto recorder = loop::Recorder::Open(log_path, m, loop::MakeLogHeader(m, r.source().kind, r.source().hash));
    REQUIRE_MESSAGE(recorder.ok(), recorder.error().message);
    REQUIRE(loop::AttachRecorder(m, r.data(), r.loop(), recorder->get()).ok());
    std::vector<double> q_before;
    for (const robot::MotorSpec& mo : m.motors) q_before.push_back(r.data().command[mo.q]);
    for (std::size_t k = 0; k < At(duration_s); ++k) {  // the operator arms (nobody calls Arm here)
      REQUIRE(r.Tick());
      phase.push_back(r.loop().phase());
      mode.push_back(r.loop().supervisor().mode);
      double step = 0;
      for (std::size_t j = 0; j < m.motors.size(); ++j) {
        const double q = r.data().command[m.motors[j].q];
        step = std::max(step, std::abs(q - q_before[j]));
        q_before[j] = q;
      }
      q_step.push_back(step);
    }
    REQUIRE(loop::AttachRecorder(m, r.data(), r.loop(), nullptr).ok());
    REQUIRE((*recorder)->Stop().ok());
    CHECK((*recorder)->dropped() == 0);
    REQUIRE(r.trace().size() == phase.size());
    REQUIRE(r.can().records_dropped() == 0);
  }
  double MeanVx(double from, double to) const {
    double sum = 0;
    for (std::size_t k = At(from); k < At(to); ++k) sum += rig->trace()[k].vx_mps;
    return sum / static_cast<double>(At(to) - At(from));
  }
  bool Upright(double from, double to) const {
    float worst = 0;
    for (std::size_t k = At(from); k < At(to); ++k) worst = std::max(worst, rig->trace()[k].tilt_rad);
    return worst < 0.35f;
  }
  double MaxStep(double from, double to) const {
    return *std::max_element(q_step.begin() + static_cast<std::ptrdiff_t>(At(from)),
                             q_step.begin() + static_cast<std::ptrdiff_t>(At(to)));
  }
  // The recording replays to the same commands, bit for bit (the requests from the fields).
  void CheckReplay(const std::vector<std::string>& switch_policies = {}) const {
    auto log = loop::ReadLog(log_path);
    REQUIRE_MESSAGE(log.ok(), log.error().message);
    std::vector<std::string> more;
    for (const std::string& p : switch_policies) more.push_back(test::SourcePath(p));
    auto source = loop::LoadSource(m, {test::SourcePath(kPolicy), "", true, policy::Kernel::kAuto, more});
    REQUIRE_MESSAGE(source.ok(), source.error().message);
    auto replay = loop::Replay(m, *log, source->source.get(), source->hash);
    REQUIRE_MESSAGE(replay.ok(), replay.error().message);
    CHECK(replay->ticks == phase.size());
    CHECK(replay->compared == phase.size());
    CHECK_MESSAGE(replay->mismatches == 0, replay->first_mismatch);
  }
};

}  // namespace

TEST_CASE(
    "gamepad HIL: a recorded session drives the walking quadruped - stand, walk, dead-man, e-stop, re-arm, pad lost - "
    "replays bit for bit") {
  SessionRun s("demo", 20.0);
  const std::vector<Phase>& phase = s.phase;
  const std::vector<Mode>& mode = s.mode;
  sim::QuadrupedRig& r = *s.rig;
  const robot::RobotModel& m = s.m;
  // Disarmed until START; arming at its press, standing, then holding (no walk without A).
  CHECK(phase[At(0.19)] == Phase::kDisarmed);
  CHECK(phase[At(0.25)] == Phase::kStandUp);
  CHECK(phase[At(1.85)] == Phase::kHold);
  CHECK(phase[At(2.05)] == Phase::kRun);
  // Walking on the stick: 0.5 m/s tracked within 0.2 (settled, 3.5-7.5 s).
  const double v1 = s.MeanVx(3.5, 7.5);
  MESSAGE("walk 1: mean vx " << v1 << " m/s for 0.5");
  CHECK(std::abs(v1 - 0.5) <= 0.2);
  CHECK(s.Upright(2.0, kRelease1));
  // The dead-man released: standing up from the measured pose, then holding; upright.
  CHECK(phase[At(kRelease1) - 1] == Phase::kRun);
  CHECK(phase[At(kRelease1) + 1] == Phase::kStandUp);
  CHECK(phase[At(kRelease1 + 1.5)] == Phase::kHold);
  CHECK(s.Upright(kRelease1, kWalk2));
  CHECK(std::abs(s.MeanVx(kRelease1 + 1.0, kWalk2)) < 0.1);
  // Walking again (the policy started clean).
  CHECK(phase[At(kWalk2) + 2] == Phase::kRun);
  const double v2 = s.MeanVx(11.2, 12.0);
  MESSAGE("walk 2: mean vx " << v2 << " m/s for 0.5");
  CHECK(std::abs(v2 - 0.5) <= 0.2);
  CHECK(s.Upright(kWalk2, kEStop));
  // E-stop: within 3 ticks of the press, latched after the release, until MODE; the motors damp
  // (supervisor.estop: damping): every motor commanded every tick with kp 0 and the damping kd.
  const std::size_t e = At(kEStop);
  CHECK(mode[e - 1] < Mode::kEStop);
  bool within3 = false;
  for (std::size_t k = e; k <= e + 3; ++k) within3 = within3 || mode[k] == Mode::kEStop;
  CHECK(within3);
  for (std::size_t k = e + 3; k < At(kRearm); ++k) REQUIRE(mode[k] == Mode::kEStop);
  CHECK(r.loop().recovery().requested == 1);
  CHECK(r.loop().recovery().refused == 0);
  const double kd = m.supervisor_model.commands[m.motors[0].kd].stop_value;
  REQUIRE(kd > 0.0);
  // Damped from the tick the e-stop is seen (within 3 of the press) to the re-arm, and passive
  // after the re-arm until START.
  const auto damped = [&](double from, double to, std::size_t* other) {
    std::size_t n = 0;
    for (const can::CommandRecord& c : r.can().RecordedCommands())
      if (c.tick >= At(from) && c.tick < At(to)) {
        if (c.kp == 0.0 && c.kd == kd)
          ++n;
        else
          ++*other;
      }
    return n;
  };
  std::size_t other = 0;
  CHECK(damped(kEStop + 0.003, kRearm, &other) == (At(kRearm) - At(kEStop + 0.003)) * m.motors.size());
  CHECK(other == 0);
  const double sunk = r.trace()[At(kRearm) - 1].z_m, standing = r.trace()[e - 1].z_m;
  MESSAGE("base height: standing " << standing << " m, after 1 s of the e-stop's damping " << sunk << " m");
  CHECK(sunk < standing - 0.05);
  // Re-armed (rearm_to: passive): arming, then passive, damped where it lies, until START.
  CHECK(mode[At(kRearm) + 2] == Mode::kNominal);
  CHECK(phase[At(kRearm) + 2] == Phase::kPassive);
  CHECK(phase[At(kStand) - 1] == Phase::kPassive);
  CHECK(damped(kRearm + 0.002, kStand, &other) == (At(kStand) - At(kRearm + 0.002)) * m.motors.size());
  CHECK(other == 0);
  // START: standing up from there, holding, upright.
  CHECK(phase[At(kStand)] == Phase::kStandUp);
  CHECK(phase[At(kStand + 1.1)] == Phase::kHold);
  CHECK(s.Upright(kStand + 1.1, kWalk3));
  CHECK(r.trace()[At(kWalk3) - 1].z_m > standing - 0.03);
  // Walking a third time; the pad gone mid-walk: the command stops, the robot stands, upright.
  CHECK(phase[At(kWalk3) + 2] == Phase::kRun);
  CHECK(phase[At(kGone) + 2] == Phase::kStandUp);
  CHECK(phase[At(kGone + 1.5)] == Phase::kHold);
  CHECK(r.trace()[At(kGone) + 2].cmd_vx == 0.0f);
  CHECK(s.Upright(kGone, 20.0));
  CHECK(mode.back() == Mode::kNominal);
  const auto& stats = dynamic_cast<evdev::EvdevTransport&>(*s.pad).stats();
  CHECK(stats.losses == 1);
  CHECK(stats.unmapped == 0);
  CHECK(r.loop().operator_status().refused == 0);
  CHECK(test::CommandsOutsideLimits(m, r.can().RecordedCommands()) == 0);
  s.CheckReplay();
}

TEST_CASE(
    "gamepad HIL: switching policy mid-walk (RB, blended over 0.5 s) and back - no fall, no jump, tracked - replays "
    "bit for bit") {
  // tools/gamepad_session.py switch: walking 0.5 m/s from 2.1 s on the flat policy, RB at 5.0
  // (mixed.blob, blended in), RB at 9.0 (flat again), the stick back at 12.0, stand at 12.5.
  const std::vector<std::string> more = {"policies/frozen/quadruped_walk/mixed.blob"};
  SessionRun s("switch", 13.5, more);
  const auto& set = dynamic_cast<const loop::PolicySet&>(*s.rig->source().source);
  CHECK(set.switches() == 2);
  CHECK(set.current() == 0);
  for (const auto& [from, to] : {std::pair{3.5, 5.0}, std::pair{6.0, 9.0}, std::pair{10.0, 12.0}}) {
    const double v = s.MeanVx(from, to);
    MESSAGE("walking " << from << "-" << to << " s: mean vx " << v << " m/s for 0.5");
    CHECK(std::abs(v - 0.5) <= 0.2);
  }
  CHECK(s.Upright(2.0, 13.5));
  for (double t : {4.9, 5.3, 7.0, 9.3, 11.0}) CHECK(s.phase[At(t)] == Phase::kRun);
  CHECK(s.mode.back() == Mode::kNominal);
  // No jump: the largest step of a joint's target within each blend is no larger than walking's own
  // (the policy's action changes every 20 ticks).
  const double walking = s.MaxStep(3.0, 5.0), blend1 = s.MaxStep(5.0, 5.6), blend2 = s.MaxStep(9.0, 9.6);
  MESSAGE("largest q target step: walking " << walking << ", switching " << blend1 << ", back " << blend2 << " rad");
  CHECK(blend1 <= walking);
  CHECK(blend2 <= walking);
  CHECK(s.rig->loop().operator_status().refused == 0);
  CHECK(test::CommandsOutsideLimits(s.m, s.rig->can().RecordedCommands()) == 0);
  s.CheckReplay(more);
}

TEST_CASE(
    "gamepad HIL: sit down from a walk (R3), passive on the ground, stand up again (START), walk, sit from hold, stop "
    "from passive - no fall, replays bit for bit") {
  // tools/gamepad_session.py sit: walking 0.5 m/s from 2.1 s, the stick back at 5.0, R3 at 6.0
  // (sit-down 1.5 s, then passive), A at 8.5 (refused), START at 10.0 (stand up), walking 0.5 m/s
  // from 11.8 to 15.0, the dead-man released at 16.0, R3 at 17.3, B at 19.5 (damping, motors off).
  constexpr double kSit1 = 6.0, kStand = 10.0, kSit2 = 17.3, kStop = 19.5;
  SessionRun s("sit", 19.9);
  const std::vector<Phase>& phase = s.phase;
  const std::vector<sim::RigSample>& trace = s.rig->trace();
  const robot::RobotModel& m = s.m;
  CHECK(phase[At(kSit1) - 1] == Phase::kRun);
  CHECK(phase[At(kSit1)] == Phase::kSitDown);  // at the press's tick, from the walk
  CHECK(phase[At(kSit1) + 1499] == Phase::kSitDown);
  CHECK(phase[At(kSit1) + 1500] == Phase::kPassive);
  // Seated, upright: the base lowered from standing (0.46 m in hold) to about the sit pose's 0.19 m.
  const float seated = trace[At(kSit1) + 1499].z_m, standing = trace[At(1.7)].z_m;
  MESSAGE("base height: standing " << standing << " m, seated " << seated << " m, passive " << trace[At(kStand) - 1].z_m
                                   << " m");
  CHECK(standing > 0.40f);
  CHECK(seated > 0.15f);
  CHECK(seated < 0.22f);
  CHECK(s.Upright(kSit1, kStand + 1.5));
  // The sit-down starts from the measured pose (its first target is where each joint is, so the
  // stand gains take over without a torque step), then moves smoothly: its largest step per tick
  // after the first a small fraction of the walk's own.
  const double walking = s.MaxStep(3.0, 5.0), sitting = s.MaxStep(kSit1 + 0.001, kSit1 + 1.5);
  MESSAGE("largest q target step: walking " << walking << ", sitting down " << sitting << " rad");
  CHECK(sitting <= 0.01 * walking);
  // Passive: damped (kp 0), resting on its body by the time START comes; walking refused.
  CHECK(trace[At(kStand) - 1].body_contact);
  CHECK(std::string(s.rig->loop().operator_status().last).find("walk refused at tick 8500: not holding (passive)") ==
        0);
  // START: up again from the ground, holding, then walking 0.5 m/s within 0.2.
  CHECK(phase[At(kStand)] == Phase::kStandUp);
  CHECK(phase[At(kStand + 1.1)] == Phase::kHold);
  CHECK(trace[At(kStand + 1.4)].z_m > 0.40f);
  CHECK_FALSE(trace[At(kStand + 1.4)].body_contact);
  const double v = s.MeanVx(12.8, 15.0);
  MESSAGE("walking after standing up from passive: mean vx " << v << " m/s for 0.5");
  CHECK(std::abs(v - 0.5) <= 0.2);
  CHECK(s.Upright(kStand, kStop));
  // Sit from hold, then B from passive: damping, motors off.
  CHECK(phase[At(kSit2) - 1] == Phase::kHold);
  CHECK(phase[At(kSit2)] == Phase::kSitDown);
  CHECK(phase[At(kSit2 + 1.6)] == Phase::kPassive);
  CHECK(phase[At(kStop)] == Phase::kDamping);
  CHECK(s.mode.back() == Mode::kNominal);
  CHECK_FALSE(s.rig->Report(1.0, true).fell);
  CHECK(s.rig->loop().operator_status().refused == 1);
  CHECK(test::CommandsOutsideLimits(m, s.rig->can().RecordedCommands()) == 0);
  s.CheckReplay();
}
