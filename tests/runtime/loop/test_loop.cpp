// runtime/loop over an in-memory transport: the quadruped's phases with the stand trajectory
// (what each motor is sent in each phase, no allocation), the diffbot's velocity-commanded wheels, a silent motor
// (safe-stop naming it, then e-stop switching every motor off), a walking policy's observation from generic signal
// names (IMU gyro, gravity from the orientation, an operator's command, joint q / dq, the last
// action) run every 20 ticks with its action held between, and the source's failure as a named
// supervisor cause.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/loop/policy_set.hpp"
#include "runtime/loop/policy_source.hpp"
#include "runtime/loop/trajectory_source.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/robot/signals.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/scripted_transport.hpp"

using namespace pbppo;
using loop::Phase;
using robot::MotorCommand;
using safety::Mode;

namespace {

// A robot on a test bench: motors answer every frame they get (position as commanded, like a
// stiff joint; `silent` stops one from tick `silent_from`), the IMU reports `quat` every tick.
struct Bench {
  const robot::RobotModel& m;
  robot::RobotData data;
  std::unique_ptr<loop::LoopData> loop;
  test::ScriptedTransport t;
  robot::Transport* ts[1];
  int silent = -1;
  std::uint64_t silent_from = ~0ull;
  double quat[4] = {1, 0, 0, 0};
  std::uint64_t tick = 0;

  Bench(const robot::RobotModel& model, loop::CommandSource* source)
      : m(model), data(robot::MakeRobotData(model)), loop(loop::MakeLoopData(model, source)), t(model), ts{&t} {}

  loop::TickStatus Step() {
    // Replies to what was sent last tick.
    for (std::size_t k = 0; k < m.motors.size(); ++k) {
      const robot::MotorSpec& mo = m.motors[k];
      if (t.writes == 0 || t.motors[k] == MotorCommand::kNone) continue;
      if (static_cast<int>(k) == silent && tick >= silent_from) continue;
      // A position-commanded joint is where it was commanded; a velocity-commanded one turns at
      // the commanded speed.
      const bool commanded = t.motors[k] == MotorCommand::kCommand;
      const double dq = commanded && mo.velocity_commanded() ? t.command[mo.dq] : 0.0;
      const double q = commanded && !mo.velocity_commanded() ? t.command[mo.q] : data.fields[mo.q_field] + dq * 1e-3;
      const double reply[3] = {q, dq, 0.0};
      t.Put(m, mo.stream, reply);
    }
    const int imu = m.StreamIndex("base_imu");
    if (imu >= 0) {
      const double sample[10] = {quat[0], quat[1], quat[2], quat[3], 0.1, -0.2, 0.3, 0, 0, 9.81};
      t.Put(m, static_cast<std::uint32_t>(imu), sample);
    }
    rt::TickTiming timing;
    timing.tick = tick++;
    return loop::Tick(m, data, *loop, ts, timing);
  }
  void Until(Phase p, int limit) {
    for (int k = 0; k < limit && loop->phase() != p; ++k) Step();
    REQUIRE(loop->phase() == p);
  }
  // A stop request: the next tick damps every motor (kp 0 where it has one, dq_des 0, the damping
  // gain, no torque).
  void StopAndCheckDamping() {
    loop->RequestStop();
    Step();
    CHECK(loop->phase() == Phase::kDamping);
    for (const auto& mo : m.motors) {
      if (!mo.velocity_commanded()) CHECK(t.command[mo.kp] == 0.0);
      CHECK(t.command[mo.dq] == 0.0);
      CHECK(t.command[mo.kd] == m.body->damping_kd_nm_s_rad);
      CHECK(t.command[mo.tau] == 0.0);
    }
  }
};

}  // namespace

TEST_CASE("loop: the quadruped's phases - arming, stand-up, hold, the trajectory, damping, motor off") {
  const robot::RobotModel& m = test::QuadrupedRobot();
  auto trajectory = loop::RobotTrajectory(m);
  REQUIRE_MESSAGE(trajectory.ok(), trajectory.error().message);
  loop::TrajectorySource source(m, *trajectory);
  Bench b(m, &source);
  b.loop->Arm();
  b.Step();
  CHECK(b.loop->phase() == Phase::kArming);
  for (auto c : b.t.motors) CHECK(c == MotorCommand::kEnable);
  b.Step();  // every motor answered: stand up from the measured pose (all zero)
  CHECK(b.loop->phase() == Phase::kStandUp);
  for (auto c : b.t.motors) CHECK(c == MotorCommand::kCommand);
  CHECK(b.t.command[m.motors[2].q] == 0.0);
  CHECK(b.t.command[m.motors[2].kp] == m.body->kp_nm_rad);
  const std::uint64_t up = b.loop->phase_start(Phase::kStandUp);
  {
    AllocationScope scope;
    b.Until(Phase::kHold, 1100);
    b.Until(Phase::kRun, 300);
    for (int k = 0; k < 100; ++k) b.Step();
    CHECK(scope.count() == 0);
  }
  CHECK(b.loop->phase_start(Phase::kHold) - up == m.phases.stand_up_ticks);
  CHECK(b.loop->phase_start(Phase::kRun) - b.loop->phase_start(Phase::kHold) == m.phases.hold_ticks);
  CHECK(b.t.command[m.motors[2].q] != doctest::Approx(m.motors[2].default_q_rad));  // sinusoids
  b.Until(Phase::kHold, 2100);  // the trajectory ended: the default pose again
  CHECK(source.ticks() == 2000);
  CHECK(source.rms_tracking_error_rad() < 0.01);  // the bench's joints follow exactly, a tick late
  b.StopAndCheckDamping();
  b.Until(Phase::kMotorOff, 600);
  CHECK(b.loop->phase_start(Phase::kMotorOff) - b.loop->phase_start(Phase::kDamping) == m.phases.damping_ticks);
  for (auto c : b.t.motors) CHECK(c == MotorCommand::kDisable);
  CHECK(b.Step() == loop::TickStatus::kDone);  // every motor answered the motor-off frame
  CHECK(b.loop->supervisor().mode == Mode::kNominal);
}

TEST_CASE("loop: velocity-commanded wheels - zero speed in stand-up and hold, speeds in run, braked in damping") {
  const robot::RobotModel& m = test::DiffbotRobot();
  auto trajectory = loop::RobotTrajectory(m);
  REQUIRE_MESSAGE(trajectory.ok(), trajectory.error().message);
  loop::TrajectorySource source(m, *trajectory);
  Bench b(m, &source);
  const robot::MotorSpec &left = m.motors[0], &right = m.motors[1], &head = m.motors[2];
  b.loop->Arm();
  b.Until(Phase::kStandUp, 5);
  // Stand-up: the head ramps to its default pose; the wheels hold zero speed with their velocity gain.
  for (int k = 0; k < 50; ++k) b.Step();
  CHECK(b.t.command[head.q] > 0.0);
  CHECK(b.t.command[head.q] < 0.3);
  for (const auto* w : {&left, &right}) {
    CHECK(b.t.command[w->dq] == 0.0);
    CHECK(b.t.command[w->kd] == 0.3);
    CHECK(b.t.command[w->tau] == 0.0);
  }
  b.Until(Phase::kHold, 100);
  b.Step();
  CHECK(b.t.command[head.q] == 0.3);
  CHECK(b.t.command[left.dq] == 0.0);
  b.Until(Phase::kRun, 100);
  for (int k = 0; k < 300; ++k) b.Step();
  // Run: the trajectory's speeds (left 12 + 3 sin(4 pi t), right -8); the wheels' angles grow
  // past any MIT range, unbounded, with no finding.
  CHECK(b.t.command[left.dq] == doctest::Approx(12.0 + 3.0 * std::sin(4 * std::numbers::pi * 0.3)).epsilon(1e-9));
  CHECK(b.t.command[right.dq] == -8.0);
  CHECK(b.data.fields[right.q_field] < -2.0);
  const double travelled = b.data.fields[left.q_field];
  b.Until(Phase::kHold, 1000);  // the trajectory ended: zero speed, the head at its default pose
  CHECK(b.data.fields[left.q_field] > travelled + 5.0);
  CHECK(b.data.fields[left.q_field] > 3.2);  // beyond the wheel drivers' MIT range [-pi, pi)
  b.Step();
  CHECK(b.t.command[left.dq] == 0.0);
  CHECK(source.rms_speed_error_rad_s() < 0.5);  // the bench's wheels follow exactly, a tick late
  CHECK(source.rms_tracking_error_rad() < 0.01);
  CHECK(b.loop->supervisor().mode == Mode::kNominal);
  CHECK(b.loop->supervisor().counts[safety::Cause::kInvalidSample] == 0);
  // Damping: no stiffness anywhere, dq_des 0 and the damping gain: the wheels brake to a stop.
  b.StopAndCheckDamping();
  b.Until(Phase::kDone, 200);
}

TEST_CASE("loop: a silent motor - degraded, safe-stop naming it within 3 ticks, e-stop after 500 switches off") {
  const robot::RobotModel& m = test::QuadrupedRobot();
  Bench b(m, nullptr);
  b.silent = 2;  // LF_KFE
  b.loop->Arm();
  b.Until(Phase::kHold, 1100);
  b.silent_from = b.tick;
  const std::uint64_t from = b.tick;
  for (int k = 0; k < 5; ++k) b.Step();
  const safety::SupervisorState& s = b.loop->supervisor();
  REQUIRE(s.mode == Mode::kSafeStop);
  CHECK(s.entered[2].cause == safety::Cause::kStaleSample);
  CHECK(s.entered[2].subject == static_cast<std::int32_t>(m.motors[2].stream));
  CHECK(s.entered_tick[2] <= from + 4);
  CHECK(safety::Describe(m.supervisor_model, s.entered[2]) == "safe-stop: stale sample: LF_KFE: age 3 ticks > 2");
  for (const auto& mo : m.motors) CHECK(b.t.command[mo.kp] == 0.0);
  while (s.mode != Mode::kEStop && b.tick < from + 600) b.Step();
  CHECK(s.entered[3].cause == safety::Cause::kLostPeer);
  CHECK(s.entered[3].subject == static_cast<std::int32_t>(m.motors[2].stream));
  for (auto c : b.t.motors) CHECK(c == MotorCommand::kDisable);
}

namespace {

// The quadruped with a walking policy's layout and an operator's velocity command (issue 18's
// signals), in a copy of its folder named `scratch`: one per test case (ctest runs a binary's test
// cases as parallel processes, which must not rewrite each other's files).
std::string WalkingRobot(const std::string& scratch) {
  const std::string dir = test::CopyRobotFolder("quadruped", scratch);
  const auto& m = test::QuadrupedRobot();
  std::ofstream io(dir + "/io_layout.yaml");
  io << "robot: quadruped\nobservations:\n";
  for (const char* s : {"base_ang_vel_x", "base_ang_vel_y", "base_ang_vel_z", "projected_gravity_x",
                        "projected_gravity_y", "projected_gravity_z", "command_vx", "command_vy", "command_yaw_rate"})
    io << "  - {name: " << s << "}\n";
  for (const auto& mo : m.motors) io << "  - {name: q_" << mo.joint << ", offset: " << mo.default_q_rad << "}\n";
  for (const auto& mo : m.motors) io << "  - {name: dq_" << mo.joint << "}\n";
  for (const auto& mo : m.motors) io << "  - {name: last_action_" << mo.joint << "}\n";
  io << "actions:\n";
  for (const auto& mo : m.motors)
    io << "  - {name: " << mo.joint << ", command: q_des_" << mo.joint
       << ", unit: rad, scale: 0.25, offset: " << mo.default_q_rad << ", low: " << mo.default_q_rad - 0.25
       << ", high: " << mo.default_q_rad + 0.25 << "}\n";
  io.close();
  std::ifstream in(dir + "/robot.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // The copy keeps robot.yaml (its io_layout is this layout; its operator is velocity_command).
  std::ofstream(dir + "/robot.yaml") << text;
  return dir + "/robot.yaml";
}

}  // namespace

namespace {

// A policy of random weights for `layout` (one tanh hidden layer) and the loop's source running it
// on `m` (or the reason it is refused).
struct RandomPolicy {
  policy::PolicyModel model;
  Result<std::unique_ptr<loop::PolicySource>> source;

  RandomPolicy(const robot::RobotModel& m, const robot::IoLayout& layout, std::uint32_t hidden, std::uint64_t seed)
      : model(Make(layout, hidden, seed)), source(loop::PolicySource::Create(m, model)) {}
  static policy::PolicyModel Make(const robot::IoLayout& layout, std::uint32_t hidden, std::uint64_t seed) {
    policy::PolicySpec spec = policy::MakeRandomSpec({layout.observation_size(), hidden, layout.action_size()},
                                                     policy::Activation::kTanh, seed);
    robot::ApplyLayoutToSpec(layout, spec);
    auto model = policy::PolicyModel::FromSpec(spec);
    REQUIRE(model.ok());
    return std::move(*model);
  }
};

}  // namespace

TEST_CASE("loop: a walking policy - generic signals, 50 Hz over 1 kHz ticks, the action held between") {
  auto loaded = robot::LoadRobotModel(WalkingRobot("walking"));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error().message);
  const robot::RobotModel& m = *loaded;
  REQUIRE(m.policy_period_ticks == 20);
  const RandomPolicy p(m, *m.io, 32, 3);
  REQUIRE_MESSAGE(p.source.ok(), p.source.error().message);
  const auto& source = p.source;
  Bench b(m, source->get());
  // A body rolled by 0.2 rad about x: gravity in the base frame (0, -sin 0.2, -cos 0.2).
  b.quat[0] = std::cos(0.1);
  b.quat[1] = std::sin(0.1);
  const std::uint32_t op = static_cast<std::uint32_t>(m.StreamIndex("velocity_command"));
  const double command[3] = {0.5, -0.25, 0.75};
  b.loop->Arm();
  for (int k = 0; k < 1400 && b.loop->phase() != Phase::kRun; ++k) {
    if (k % 20 == 0) b.t.Put(m, op, command);  // the operator is there from the start
    b.Step();
  }
  REQUIRE(b.loop->phase() == Phase::kRun);
  auto commanded = [&] {
    std::vector<double> q;
    for (const auto& mo : m.motors) q.push_back(b.t.command[mo.q]);
    return q;
  };
  std::vector<double> held = commanded(), before;  // before: what the last run's predecessor held
  std::uint64_t runs = (*source)->runs(), changes = 0;
  for (int k = 0; k < 200; ++k) {
    if (b.tick % 20 == 0) b.t.Put(m, op, command);
    b.Step();
    const std::vector<double> q = commanded();
    if (q != held) {
      ++changes;
      before = held;
    }
    held = q;
  }
  CHECK((*source)->runs() - runs == 10);  // every 20th tick
  CHECK(changes <= 10);                   // held between runs
  const std::span<const float> obs = (*source)->observation();
  CHECK(obs[0] == doctest::Approx(0.1));  // base_ang_vel_x: the IMU's gyro
  CHECK(obs[2] == doctest::Approx(0.3));
  CHECK(obs[3] == doctest::Approx(0.0).epsilon(1e-6));  // projected_gravity_x
  CHECK(obs[4] == doctest::Approx(-std::sin(0.2)));
  CHECK(obs[5] == doctest::Approx(-std::cos(0.2)));
  CHECK(obs[6] == 0.5f);  // command_vx
  CHECK(obs[8] == 0.75f);
  // last_action_<joint>: the previous run's action in policy units, (q - default) / 0.25.
  REQUIRE(!before.empty());
  const double last = (before[0] - m.motors[0].default_q_rad) / 0.25;
  CHECK(obs[9 + 24] == doctest::Approx(last).epsilon(1e-5));
  CHECK(b.loop->supervisor().mode == Mode::kNominal);
  // Tilted past 60 degrees: safe-stop naming the signal.
  b.quat[0] = std::cos(0.6);
  b.quat[1] = std::sin(0.6);
  b.Step();
  CHECK(b.loop->supervisor().mode == Mode::kSafeStop);
  CHECK(b.loop->supervisor().entered[2].cause == safety::Cause::kSignalLimit);
}

TEST_CASE("loop: stopping, the operator's silent stream is no stale sample - damping, motor off, mode nominal") {
  auto loaded = robot::LoadRobotModel(WalkingRobot("walking_stop"));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error().message);
  const robot::RobotModel& m = *loaded;
  const std::uint32_t op = static_cast<std::uint32_t>(m.StreamIndex("velocity_command"));
  REQUIRE(m.phases.damping_ticks > m.streams[op].stale_degraded_ticks);  // silent long enough to be stale
  const RandomPolicy p(m, *m.io, 16, 4);
  REQUIRE(p.source.ok());
  Bench b(m, p.source->get());
  const double command[3] = {0.3, 0.0, 0.0};
  b.loop->Arm();
  for (int k = 0; k < 1600; ++k) {
    if (b.tick % 20 == 0) b.t.Put(m, op, command);
    b.Step();
  }
  REQUIRE(b.loop->phase() == Phase::kRun);
  // The command source's end (a schedule played out) stops the run and its stream falls silent.
  b.loop->RequestStop();
  for (int k = 0; k < 1200 && b.loop->phase() != Phase::kDone; ++k) b.Step();
  CHECK(b.loop->phase() == Phase::kDone);
  CHECK(b.loop->supervisor().mode == Mode::kNominal);
  CHECK(b.loop->supervisor().counts[safety::Cause::kStaleSample] == 0);
  // Running, the same silence is a stale sample.
  const RandomPolicy q(m, *m.io, 16, 4);
  Bench c(m, q.source->get());
  c.loop->Arm();
  for (int k = 0; k < 2000; ++k) {
    if (c.tick % 20 == 0 && k < 1400) c.t.Put(m, op, command);
    c.Step();
  }
  CHECK(c.loop->phase() == Phase::kRun);
  CHECK(c.loop->supervisor().counts[safety::Cause::kStaleSample] > 0);
}

TEST_CASE("loop: a recurrent policy switched back to starts from its clean state, not the one it left") {
  auto loaded = robot::LoadRobotModel(WalkingRobot("walking_switch"));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error().message);
  const robot::RobotModel& m = *loaded;
  // Two recurrent policies for the layout: an LSTM 16 and a GRU 16, each before a dense layer.
  const auto make = [&](policy::LayerKind kind, std::uint64_t seed) {
    policy::PolicySpec spec = policy::MakeRandomRecurrentSpec({m.io->observation_size(), 16, m.io->action_size()},
                                                              policy::Activation::kTanh, 0, kind, true, seed);
    robot::ApplyLayoutToSpec(*m.io, spec);
    auto model = policy::PolicyModel::FromSpec(spec);
    REQUIRE_MESSAGE(model.ok(), model.error().message);
    return std::move(*model);
  };
  const policy::PolicyModel lstm = make(policy::LayerKind::kLstm, 5), gru = make(policy::LayerKind::kGru, 6);
  auto a = loop::PolicySource::Create(m, lstm);
  auto b = loop::PolicySource::Create(m, gru);
  REQUIRE(a.ok());
  REQUIRE(b.ok());
  const loop::PolicySource* first = a->get();
  std::vector<std::unique_ptr<loop::CommandSource>> sources;
  sources.push_back(std::move(*a));
  sources.push_back(std::move(*b));
  loop::PolicySet set(m, std::move(sources));
  Bench bench(m, &set);
  const std::uint32_t op = static_cast<std::uint32_t>(m.StreamIndex("velocity_command"));
  const double command[3] = {0.5, 0.0, 0.0};
  const auto step = [&] {
    if (bench.tick % 20 == 0) bench.t.Put(m, op, command);
    bench.Step();
  };
  bench.loop->Arm();
  for (int k = 0; k < 1400 && bench.loop->phase() != Phase::kRun; ++k) step();
  REQUIRE(bench.loop->phase() == Phase::kRun);
  for (int k = 0; k < 400; ++k) step();  // 20 runs of the LSTM: its state far from zero
  set.Switch();
  for (int k = 0; k < 200; ++k) step();  // the GRU
  set.Switch();
  const std::uint64_t runs = first->runs();
  while (first->runs() == runs) step();  // the LSTM's first run after the switch back
  CHECK(set.switches() == 2);
  CHECK(set.current() == 0);
  // The same observation through the same model from a clean state gives the same action; the
  // same observation again (the state now carried) gives another: the state matters, and was clean.
  auto fresh = policy::MakePolicyData(lstm);
  REQUIRE(fresh.ok());
  std::copy(first->observation().begin(), first->observation().end(), fresh->observation().begin());
  REQUIRE(policy::Forward(lstm, *fresh) == policy::ForwardStatus::kOk);
  const std::vector<float> clean(fresh->action().begin(), fresh->action().end());
  CHECK(std::vector<float>(first->action().begin(), first->action().end()) == clean);
  REQUIRE(policy::Forward(lstm, *fresh) == policy::ForwardStatus::kOk);
  CHECK(std::vector<float>(fresh->action().begin(), fresh->action().end()) != clean);
}

TEST_CASE("loop: a policy on velocity-commanded wheels - speeds as actions, a position target refused") {
  const robot::RobotModel& m = test::DiffbotRobot();
  const RandomPolicy p(m, *m.io, 16, 5);
  REQUIRE_MESSAGE(p.source.ok(), p.source.error().message);
  const auto& source = p.source;
  Bench b(m, source->get());
  b.loop->Arm();
  b.Until(Phase::kRun, 300);
  for (int k = 0; k < 200; ++k) b.Step();
  CHECK((*source)->runs() == 20);  // every 10 ticks
  const robot::MotorSpec& left = m.motors[0];
  // The action is the wheel's speed (scale 8, clamped to [-15, 15]); its kd stays the velocity gain
  // (a policy's gains are a position-commanded motor's).
  CHECK(b.t.command[left.dq] != 0.0);
  CHECK(std::abs(b.t.command[left.dq]) <= 15.0);
  CHECK(b.t.command[left.kd] == 0.3);
  CHECK(b.loop->supervisor().mode == Mode::kNominal);
  // A layout giving a wheel a position target is refused naming the action and the joint.
  robot::RobotModel with = m;
  with.io->actions[0].command = "q_des_left_wheel";
  const RandomPolicy refused(with, *with.io, 16, 5);
  REQUIRE_FALSE(refused.source.ok());
  CHECK(refused.source.error().message ==
        "io layout 'diffbot': actions[0] 'left_wheel': command 'q_des_left_wheel': joint 'left_wheel' is "
        "velocity-commanded (continuous): it takes no position target (command dq_des_left_wheel)");
}

namespace {

// A source that fails as a policy whose Forward returned non-finite actions.
class Failing final : public loop::CommandSource {
 public:
  void Start(const robot::RobotModel&, const robot::RobotData&, loop::LoopData&) noexcept override {}
  bool Compute(const robot::RobotModel&, const robot::RobotData& d, loop::LoopData&,
               std::span<double>) noexcept override {
    fail = d.tick >= 5;
    return true;
  }
  const char* failure() const noexcept override { return fail ? "non-finite action" : nullptr; }
  bool fail = false;
};

}  // namespace

TEST_CASE("loop: the command source's failure (the inference status) is a named supervisor cause") {
  const robot::RobotModel& m = test::AuvRobot();
  Failing source;
  Bench b(m, &source);
  b.loop->Arm();
  for (int k = 0; k < 8; ++k) {
    b.t.PutField(m, static_cast<std::uint32_t>(m.FieldIndex("sonar_beams")), 16.0);  // a valid sample
    b.Step();
  }
  const auto& s = b.loop->supervisor();
  CHECK(s.mode == Mode::kSafeStop);
  CHECK(s.entered[2].cause == safety::Cause::kInferenceFailed);
  CHECK(safety::Describe(m.supervisor_model, s.entered[2]) == "safe-stop: inference failed: non-finite action");
  CHECK(s.counts[safety::Cause::kInferenceFailed] == 3);
}

TEST_CASE("signals: gravity in the IMU's frame, wrapped angles, the least of fields, last actions, unknown names") {
  const robot::RobotModel& m = test::QuadrupedRobot();
  auto p = robot::SignalProgram::Create(
      m, {"projected_gravity_x", "projected_gravity_y", "projected_gravity_z", "base_ang_vel_y", "q_RH_KFE"});
  REQUIRE_MESSAGE(p.ok(), p.error().message);
  std::vector<double> f(m.fields.size(), 0.0), out(5);
  const int qw = m.FieldIndex("base_imu_qw");
  // A pitch of 0.3 rad about y (unnormalised: scaled by 2): gravity (sin 0.3, 0, -cos 0.3).
  f[static_cast<std::size_t>(qw)] = 2 * std::cos(0.15);
  f[static_cast<std::size_t>(qw) + 2] = 2 * std::sin(0.15);
  f[static_cast<std::size_t>(m.FieldIndex("base_imu_gyro_y"))] = 0.7;
  f[static_cast<std::size_t>(m.FieldIndex("q_RH_KFE"))] = 1.25;
  p->Compute(f, {}, out.data());
  CHECK(out[0] == doctest::Approx(std::sin(0.3)));
  CHECK(out[1] == doctest::Approx(0.0));
  CHECK(out[2] == doctest::Approx(-std::cos(0.3)));
  CHECK(out[3] == 0.7);
  CHECK(out[4] == 1.25);
  const robot::RobotModel& auv = test::AuvRobot();
  auto a = robot::SignalProgram::Create(auv, {"yaw", "nearest_echo", "depth_error", "cos_route_bearing"});
  REQUIRE(a.ok());
  std::vector<double> g(auv.fields.size(), 10.0), o(4);
  g[static_cast<std::size_t>(auv.FieldIndex("yaw_rad"))] = 3 * 3.14159265358979;  // wrapped to about pi
  g[static_cast<std::size_t>(auv.FieldIndex("sonar_7_m"))] = 2.5;
  g[static_cast<std::size_t>(auv.FieldIndex("depth_m"))] = 6.5;
  g[static_cast<std::size_t>(auv.FieldIndex("route_bearing_rad"))] = 0.5;
  a->Compute(g, {}, o.data());
  CHECK(std::abs(o[0]) == doctest::Approx(3.14159265358979));
  CHECK(o[1] == 2.5);
  CHECK(o[2] == 1.5);  // depth - the mission depth 5 m
  CHECK(o[3] == std::cos(0.5));
  auto bad = robot::SignalProgram::Create(m, {"base_ang_vel_w"});
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("signal 'base_ang_vel_w' is not provided (known: base_ang_vel_x") !=
        std::string::npos);
}

TEST_CASE("loop: more mode and phase changes than the lists keep - every one counted, the first kept in order") {
  // The AUV: armed, its vehicle's samples come for 5 ticks and then stop, so it goes degraded,
  // safe-stop and lost (mode changes); disarmed and reset, it is armed again (phase changes), 20
  // times.
  const robot::RobotModel& m = test::AuvRobot();
  robot::RobotData d = robot::MakeRobotData(m);
  auto l = loop::MakeLoopData(m, nullptr);
  test::ScriptedTransport t(m);
  robot::Transport* ts[] = {&t};
  std::vector<double> sample(m.fields.size(), 0.0);
  sample[static_cast<std::size_t>(m.FieldIndex("sonar_beams"))] = 16;
  for (std::uint32_t i = 0; i < 16; ++i)
    sample[static_cast<std::size_t>(m.FieldIndex(robot::ExpandIndex("sonar_{i}_m", i)))] = 3.0;
  std::uint64_t modes = 0, tick = 0;
  std::vector<std::uint64_t> mode_ticks;
  auto step = [&](bool with_sample) {
    if (with_sample) {
      sample[static_cast<std::size_t>(m.FieldIndex("tick"))] = static_cast<double>(tick);
      t.Put(m, 0, sample);
    }
    const Mode before = l->supervisor().mode;
    rt::TickTiming timing;
    timing.tick = tick++;
    loop::Tick(m, d, *l, ts, timing);
    if (l->supervisor().mode != before) {
      ++modes;
      mode_ticks.push_back(d.tick);
    }
  };
  for (int cycle = 0; cycle < 20; ++cycle) {
    l->Arm();
    for (int k = 0; k < 60; ++k) step(k < 5);
    REQUIRE(l->phase() == Phase::kRun);
    REQUIRE(l->supervisor().mode == Mode::kEStop);
    l->Disarm();
    step(false);
    REQUIRE(l->phase() == Phase::kDisarmed);
    REQUIRE(l->ResetSupervisor());
  }
  REQUIRE(modes > loop::LoopData::kMaxChanges);
  CHECK(l->mode_change_count() == modes);
  CHECK(l->phase_change_count() == 40);
  REQUIRE(l->mode_changes().size() == loop::LoopData::kMaxChanges);
  CHECK(l->phase_changes().size() == loop::LoopData::kMaxChanges);
  for (std::size_t k = 0; k < loop::LoopData::kMaxChanges; ++k) CHECK(l->mode_changes()[k].tick == mode_ticks[k]);
}

namespace {

// The AUV with a recovery rule, its vehicle's samples scripted tick by tick.
struct AuvBench {
  robot::RobotModel m;
  robot::RobotData d;
  std::unique_ptr<loop::LoopData> l;
  test::ScriptedTransport t;
  robot::Transport* ts[1];
  std::vector<double> sample;
  std::uint64_t tick = 0;

  explicit AuvBench(const robot::RecoverySpec& recovery)
      : m(WithRecovery(recovery)), d(robot::MakeRobotData(m)), l(loop::MakeLoopData(m, nullptr)), t(m), ts{&t} {
    sample.assign(m.fields.size(), 0.0);
    sample[static_cast<std::size_t>(m.FieldIndex("sonar_beams"))] = 16;
    for (std::uint32_t i = 0; i < 16; ++i)
      sample[static_cast<std::size_t>(m.FieldIndex(robot::ExpandIndex("sonar_{i}_m", i)))] = 3.0;
  }
  static robot::RobotModel WithRecovery(const robot::RecoverySpec& r) {
    robot::RobotModel m = test::AuvRobot();
    m.supervisor.recovery = r;
    return m;
  }
  // One tick; `with_sample`: the vehicle's sample arrived (`bad`: its depth NaN).
  void Step(bool with_sample, bool bad = false) {
    if (with_sample) {
      sample[static_cast<std::size_t>(m.FieldIndex("tick"))] = static_cast<double>(tick);
      sample[static_cast<std::size_t>(m.FieldIndex("depth_m"))] = bad ? std::nan("") : 5.0;
      t.Put(m, 0, sample);
    }
    rt::TickTiming timing;
    timing.tick = tick++;
    loop::Tick(m, d, *l, ts, timing);
  }
  // The vehicle falls silent for `silent` ticks (lost: e-stop), then answers every tick.
  void LoseAndComeBack(int silent) {
    for (int k = 0; k < silent; ++k) Step(false);
    REQUIRE(l->supervisor().mode == Mode::kEStop);
  }
  std::string LastModeChange() const { return l->mode_changes().back().reason; }
};

robot::RecoverySpec Automatic(std::uint32_t healthy_ticks, std::uint32_t max,
                              std::initializer_list<safety::Cause> causes) {
  robot::RecoverySpec r;
  r.automatic = true;
  r.healthy_ticks = healthy_ticks;
  r.max_automatic = max;
  for (safety::Cause c : causes) r.causes |= 1u << static_cast<unsigned>(c);
  return r;
}

}  // namespace

TEST_CASE("loop recovery: automatic - a vehicle that comes back is run again after the healthy time, at most N times") {
  using safety::Cause;
  AuvBench b(Automatic(10, 2, {Cause::kStaleSample, Cause::kLostPeer}));
  b.l->Arm();
  for (int k = 0; k < 5; ++k) b.Step(true);
  REQUIRE(b.l->phase() == Phase::kRun);
  REQUIRE(b.l->supervisor().mode == Mode::kNominal);
  for (int round = 1; round <= 2; ++round) {
    b.LoseAndComeBack(30);
    // Back: healthy from its first sample on; the 10th healthy tick lets the next tick re-arm.
    for (int k = 0; k < 10; ++k) {
      b.Step(true);
      CHECK(b.l->supervisor().mode == Mode::kEStop);
    }
    CHECK(b.l->healthy_ticks() == 10);
    const std::uint64_t rearm_tick = b.tick;
    b.Step(true);
    CHECK(b.l->supervisor().mode == Mode::kNominal);
    CHECK(b.l->phase() == Phase::kRun);
    CHECK(b.l->recovery().automatic == static_cast<std::uint64_t>(round));
    CHECK(b.l->recovery().last_tick == rearm_tick);
    CHECK(b.LastModeChange() ==
          "nominal: re-armed automatically after 10 healthy ticks (stopped by: stale sample, lost peer)");
    // The phase list: run -> disarmed -> run on the re-arming tick.
    const auto phases = b.l->phase_changes();
    REQUIRE(phases.size() >= 2);
    CHECK(phases[phases.size() - 2].to == Phase::kDisarmed);
    CHECK(phases.back().to == Phase::kRun);
    CHECK(phases.back().tick == rearm_tick);
    for (int k = 0; k < 20; ++k) b.Step(true);
    CHECK(b.l->supervisor().mode == Mode::kNominal);
  }
  // The third time: max_automatic (2) reached, it stays stopped until a person asks.
  b.LoseAndComeBack(30);
  for (int k = 0; k < 50; ++k) b.Step(true);
  CHECK(b.l->supervisor().mode == Mode::kEStop);
  CHECK(b.l->recovery().automatic == 2);
  CHECK(b.l->recovery().stops == 3);  // once per loss (safe-stop, then e-stop: one stop)
  b.l->RequestRearm();
  b.Step(true);
  CHECK(b.l->supervisor().mode == Mode::kNominal);
  CHECK(b.l->recovery().requested == 1);
  CHECK(b.LastModeChange() ==
        "nominal: re-armed on request after 50 healthy ticks (stopped by: stale sample, lost peer)");
  // The supervisor's counters are kept across re-arms.
  CHECK(b.l->supervisor().counts[Cause::kLostPeer] > 0);
}

TEST_CASE("loop recovery: request (the default) - nothing runs again until a person asks, and not too early") {
  AuvBench b(robot::RecoverySpec{});
  REQUIRE_FALSE(b.m.supervisor.recovery.automatic);
  b.m.supervisor.recovery.healthy_ticks = 10;
  b.l->Arm();
  for (int k = 0; k < 5; ++k) b.Step(true);
  // A request with nothing to recover from is refused and said.
  b.l->RequestRearm();
  b.Step(true);
  CHECK(b.l->recovery().refused == 1);
  CHECK(std::string(b.l->recovery().last) == "re-arm request refused: nothing to recover from (run, nominal)");
  b.LoseAndComeBack(30);
  for (int k = 0; k < 200; ++k) b.Step(true);
  CHECK(b.l->supervisor().mode == Mode::kEStop);  // healthy for long, but no request
  CHECK(b.l->recovery().automatic == 0);
  // A NaN depth: unhealthy again; a request 3 ticks later is too early.
  b.Step(true, true);
  for (int k = 0; k < 3; ++k) b.Step(true);
  b.l->RequestRearm();
  b.Step(true);
  CHECK(b.l->supervisor().mode == Mode::kEStop);
  CHECK(b.l->recovery().refused == 2);
  CHECK(std::string(b.l->recovery().last) ==
        "re-arm request refused: healthy for 3 ticks, 10 needed (e-stop: stale sample, lost peer)");
  for (int k = 0; k < 10; ++k) b.Step(true);
  b.l->RequestRearm();
  b.Step(true);
  CHECK(b.l->supervisor().mode == Mode::kNominal);
  CHECK(b.l->phase() == Phase::kRun);
  CHECK(b.l->recovery().requested == 1);
  // The loop's status (another thread's view) tells it.
  const loop::LoopStatus st = b.l->Status();
  CHECK(st.rearms == 1);
  CHECK(st.refused == 2);
  CHECK(std::string(st.recovery).find("re-armed on request") == 0);
}

TEST_CASE("loop recovery: automatic only for the causes the robot file lists - an invalid sample waits for a request") {
  using safety::Cause;
  AuvBench b(Automatic(10, 3, {Cause::kStaleSample, Cause::kLostPeer}));
  b.m.supervisor.recovery.healthy_ticks = 10;
  b.l->Arm();
  for (int k = 0; k < 5; ++k) b.Step(true);
  for (int k = 0; k < 3; ++k) b.Step(true, true);  // invalid_safe_stop 3: safe-stop
  REQUIRE(b.l->supervisor().mode == Mode::kSafeStop);
  for (int k = 0; k < 100; ++k) b.Step(true);
  CHECK(b.l->supervisor().mode == Mode::kSafeStop);
  CHECK(b.l->recovery().automatic == 0);
  // An e-stop request is never healthy: it is released by disarming and a reset only.
  b.l->RequestEStop();
  for (int k = 0; k < 20; ++k) b.Step(true);
  b.l->RequestRearm();
  b.Step(true);
  CHECK(b.l->supervisor().mode == Mode::kEStop);
  CHECK(std::string(b.l->recovery().last).find("re-arm request refused: healthy for 0 ticks") == 0);
  b.l->Disarm();
  b.Step(true);
  b.l->RequestRearm();  // disarmed: a reset and an arm, not a re-arm
  b.Step(true);
  CHECK(std::string(b.l->recovery().last) == "re-arm request refused: not armed (disarmed)");
  REQUIRE(b.l->ResetSupervisor());
  b.l->Arm();
  for (int k = 0; k < 5; ++k) b.Step(true);
  CHECK(b.l->supervisor().mode == Mode::kNominal);
  CHECK(b.l->phase() == Phase::kRun);
}

TEST_CASE("loop recovery: the quadruped re-arms through arming, stand-up and hold, allocating nothing") {
  using safety::Cause;
  robot::RobotModel m = test::QuadrupedRobot();
  m.supervisor.recovery = Automatic(200, 3, {Cause::kStaleSample});
  auto trajectory = loop::RobotTrajectory(m);
  REQUIRE_MESSAGE(trajectory.ok(), trajectory.error().message);
  loop::TrajectorySource source(m, *trajectory);
  Bench b(m, &source);
  b.loop->Arm();
  b.Until(Phase::kRun, 2500);
  for (int k = 0; k < 50; ++k) b.Step();
  // A motor silent for 5 ticks: safe-stop (stale), then it answers again.
  b.silent = 3;
  b.silent_from = b.tick;
  b.Step();
  b.Step();
  b.Step();
  b.Step();
  REQUIRE(b.loop->supervisor().mode == Mode::kSafeStop);
  b.silent_from = ~0ull;
  std::uint64_t rearmed_at = 0;
  {
    AllocationScope scope;
    for (int k = 0; k < 400 && b.loop->recovery().automatic == 0; ++k) b.Step();
    rearmed_at = b.tick - 1;
    CHECK(b.loop->phase() == Phase::kArming);
    b.Until(Phase::kStandUp, 10);
    b.Until(Phase::kHold, 1100);
    b.Until(Phase::kRun, 300);
    CHECK(scope.count() == 0);
  }
  CHECK(b.loop->recovery().automatic == 1);
  CHECK(b.loop->supervisor().mode == Mode::kNominal);
  CHECK(b.loop->recovery().last_tick == rearmed_at);
  CHECK(std::string(b.loop->recovery().last) ==
        "re-armed automatically after 200 healthy ticks (stopped by: stale sample)");
}
