// libFuzzer target: the operator's mode machine (runtime/loop/loop.hpp: Operator requests) on the
// quadruped with a gamepad (models/quadruped_gamepad), for any sequence of button presses (sit
// included)
// and releases, stick values (NaN, Inf, out of range), motor replies and IMU samples that come,
// stop or carry bad values, bus faults, and two command sources (switched between by the robot
// file's blend rule) whose commands are anything. After every tick:
//   - every command sent is finite and inside the model's limits (whatever the source asked);
//   - an e-stop press wins: at its tick the mode is e-stop (arming too: the motors are switched
//     off), and while it is, no motor is commanded (an e-stop that damps: only with the stop
//     values, no stiffness);
//   - the command source runs only with the dead-man held in a valid sample, and a run starts
//     only from hold (after a stand-up);
//   - a sit-down starts only from standing (stand-up, hold, run), passive only after a sit-down
//     (half the inputs on a robot that also sits down after the dead-man's release and whose
//     operator.from takes sit only in hold and arm only disarmed: then only from there; and
//     which is left passive when re-armed and whose e-stop damps).
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "runtime/loop/loop.hpp"
#include "runtime/loop/policy_set.hpp"
#include "runtime/robot/robot_model.hpp"
#include "tests/fuzz/gamepad_robot.hpp"
#include "tests/fuzz/supervisor_fuzz_common.hpp"

namespace {

using namespace pbppo;

// Commands from the bytes, drawn once per run of ticks (Draw): anything (special values, raw
// bits), small offsets from the phase's neutral command, or the neutral command; 255: finished.
class FuzzSource final : public loop::CommandSource {
 public:
  explicit FuzzSource(std::size_t commands) : values_(commands, 0.0) {}
  void Draw(fuzz::Bytes& b) {
    how_ = b.U8();
    if (how_ % 4 == 0)
      for (double& v : values_) v = b.Real();
    if (how_ % 4 == 1)
      for (double& v : values_) v = static_cast<double>(static_cast<std::int8_t>(b.U8())) / 64.0;
  }
  void Start(const robot::RobotModel&, const robot::RobotData&, loop::LoopData&) noexcept override { ++starts; }
  bool Compute(const robot::RobotModel&, const robot::RobotData&, loop::LoopData&,
               std::span<double> desired) noexcept override {
    ++runs;
    for (std::size_t k = 0; k < desired.size(); ++k) {
      if (how_ % 4 == 0) desired[k] = values_[k];
      if (how_ % 4 == 1) desired[k] += values_[k];
    }
    return how_ != 255;
  }
  std::uint64_t starts = 0, runs = 0;

 private:
  std::vector<double> values_;
  std::uint8_t how_ = 2;
};

// Every stream's fields from the test, every tick it says, and link health.
class Feed final : public robot::Transport {
 public:
  explicit Feed(const robot::RobotModel& m) : values(m.fields.size(), 0.0), fresh(m.streams.size(), 0) {}
  void Read(const robot::RobotModel& m, robot::RobotData& d) noexcept override {
    for (std::size_t s = 0; s < fresh.size(); ++s) {
      if (fresh[s] == 0) continue;
      const robot::StreamSpec& spec = m.streams[s];
      for (std::uint32_t f = spec.first_field; f < spec.first_field + spec.field_count; ++f) d.fields[f] = values[f];
      d.fresh[s] = 1;
    }
    for (std::size_t k = 0; k < d.transports.size() && k < 2; ++k) d.transports[k] = health[k];
  }
  void Write(const robot::RobotModel&, robot::RobotData&) noexcept override {}
  std::vector<double> values;
  std::vector<std::uint8_t> fresh;
  safety::TransportHealth health[2];
};

[[noreturn]] void Fail(const char* what, std::uint64_t tick) {
  std::fprintf(stderr, "operator_loop_fuzz: tick %llu: %s\n", static_cast<unsigned long long>(tick), what);
  std::abort();
}

// The gamepad robot as shipped (an e-stop that damps, re-armed to passive) with deadman_sit_after_s
// (0.2 s: sits down when the dead-man's release is not followed by a press within 0.2 s of the
// hold) and operator.from; and the same with the defaults instead (motors off at an e-stop,
// standing up at a re-arm, every request in every phase the controller takes it in).
const robot::RobotModel& Robot(bool sit_after_release) {
  static const robot::RobotModel* sitting = [] {
    auto* m = new robot::RobotModel(fuzz::GamepadRobot());
    if (!m->op.rearm_to_passive || !m->supervisor_model.estop_damps) std::abort();  // as shipped
    m->op.deadman_sit_after_s = 0.2;
    m->op.deadman_sit_after_ticks = 200;
    m->op.from_sit = robot::Phases({robot::Phase::kHold});  // operator.from: sit only from hold
    m->op.from_arm = robot::Phases({robot::Phase::kDisarmed});
    return m;
  }();
  static const robot::RobotModel* plain = [] {
    auto* m = new robot::RobotModel(fuzz::GamepadRobot());
    m->op.rearm_to_passive = false;           // re-armed: stand up
    m->supervisor_model.estop_damps = false;  // supervisor.estop: motors_off
    return m;
  }();
  return sit_after_release ? *sitting : *plain;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const robot::RobotModel& m = Robot(size % 2 == 1);
  fuzz::Bytes b(data, size);
  // Two sources the switch request moves between (a PolicySet, the robot file's blend rule).
  auto first = std::make_unique<FuzzSource>(m.commands.size()),
       second = std::make_unique<FuzzSource>(m.commands.size());
  FuzzSource* sources[2] = {first.get(), second.get()};
  std::vector<std::unique_ptr<loop::CommandSource>> owned;
  owned.push_back(std::move(first));
  owned.push_back(std::move(second));
  loop::PolicySet set(m, std::move(owned));
  auto l = loop::MakeLoopData(m, &set, loop::LoopOptions{});
  robot::RobotData d = robot::MakeRobotData(m);
  Feed feed(m);
  // Nominal samples: every field at 0 inside its range, the IMU upright.
  for (std::size_t f = 0; f < m.fields.size(); ++f) {
    const robot::FieldSpec& s = m.fields[f];
    feed.values[f] = std::fmin(std::fmax(0.0, s.min), s.max);
    if (s.name == "base_imu_qw") feed.values[f] = 1.0;
  }
  const robot::OperatorSpec& op = m.op;
  const std::uint32_t pad = m.fields[static_cast<std::size_t>(op.deadman)].stream;
  const std::int32_t buttons[8] = {op.deadman, op.arm, op.walk, op.estop, op.rearm, op.stop, op.switch_policy, op.sit};
  robot::Transport* transports[] = {&feed};
  double estop_level = 0;
  loop::Phase before = loop::Phase::kDisarmed;
  // Ticks in runs of the same inputs (a byte: how many), so that stand-up and hold can finish.
  for (std::uint64_t tick = 0; tick < 6000 && !b.empty();) {
    const std::uint8_t flags = b.U8();
    const std::uint32_t repeat = 1u + (b.U8() % 4 == 0 ? 1000u : b.U8());
    // The pad: buttons pressed or released, sticks.
    if (flags & 1) {  // which buttons change, and to what (pressed 1, released 0; or any value)
      const std::uint8_t change = b.U8(), value = b.U8();
      for (std::size_t i = 0; i < 7; ++i)
        if ((change >> i) & 1)
          feed.values[static_cast<std::size_t>(buttons[(i + (value >> 7)) % 8])] = (value >> i) & 1 ? 1.0 : 0.0;
      if (change & 0x80) feed.values[static_cast<std::size_t>(buttons[b.U8() % 8])] = b.Real();
    }
    if (flags & 2) {
      const std::uint32_t first = m.streams[pad].first_field;
      feed.values[first + b.U8() % 3] =
          (flags & 4) ? b.Real() : static_cast<double>(static_cast<std::int8_t>(b.U8())) / 100.0;
    }
    // Other streams: a bad value, silence, health.
    if (flags & 8) {
      const std::size_t f = b.U8() % m.fields.size();
      if (m.fields[f].stream != pad) feed.values[f] = b.Real();
    }
    const std::uint8_t silence = (flags & 16) ? b.U8() : 0;
    for (std::size_t s = 0; s < feed.fresh.size(); ++s)
      feed.fresh[s] = static_cast<std::uint8_t>(s == pad ? (silence & 1) == 0 : (silence & 2) == 0);
    if (flags & 32) {
      const std::uint8_t h = b.U8();
      feed.health[0] = {(h & 1) != 0, (h & 2) != 0, (h & 4) != 0};
      feed.health[1] = {(h & 8) != 0, (h & 16) != 0, false};
    }
    if (flags & 64) l->RequestStop();
    for (FuzzSource* f : sources) f->Draw(b);
    for (std::uint32_t r = 0; r < repeat && tick < 6000; ++r, ++tick) {
      rt::TickTiming timing;
      timing.tick = tick;
      timing.consecutive_misses = (flags & 128) ? b.U8() % 8 : 0;
      const double estop_now = feed.fresh[pad] != 0 ? feed.values[static_cast<std::size_t>(op.estop)] : estop_level;
      const bool press = feed.fresh[pad] != 0 && std::isfinite(estop_now) && estop_now >= 0.5 && !(estop_level >= 0.5);
      (void)loop::Tick(m, d, *l, transports, timing);
      estop_level = d.fields[static_cast<std::size_t>(op.estop)];
      for (std::size_t k = 0; k < m.commands.size(); ++k) {
        const safety::CommandLimit& c = m.supervisor_model.commands[k];
        if (!(d.command[k] >= c.min && d.command[k] <= c.max)) Fail("a command outside its limits", tick);
      }
      // (A run that failed to arm is over: its motors are switched off every tick, unsupervised.)
      if (press && l->phase() != loop::Phase::kFailed && l->supervisor().mode != safety::Mode::kEStop)
        Fail("an e-stop press did not win", tick);
      if (l->supervisor().mode == safety::Mode::kEStop)
        for (std::size_t k = 0; k < d.motors.size(); ++k) {
          if (d.motors[k] != robot::MotorCommand::kCommand) continue;
          if (!m.supervisor_model.estop_damps) Fail("a motor commanded in e-stop", tick);
          const std::uint32_t kp = m.motors[k].kp;  // e-stop that damps: the stop values, no stiffness
          if (kp < d.command.size() && d.command[kp] != m.supervisor_model.commands[kp].stop_value)
            Fail("an e-stop that does not damp", tick);
        }
      const loop::Phase now = l->phase();
      if (now == loop::Phase::kRun) {
        const auto dm = static_cast<std::size_t>(op.deadman);
        if (!(d.fields[dm] >= 0.5) || d.streams[pad].invalid_input >= 0) Fail("running without the dead-man", tick);
        if (before != loop::Phase::kRun && before != loop::Phase::kHold) Fail("a run not from hold", tick);
      }
      if (now == loop::Phase::kSitDown && before != loop::Phase::kSitDown && before != loop::Phase::kStandUp &&
          before != loop::Phase::kHold && before != loop::Phase::kRun)
        Fail("a sit-down not from standing", tick);
      if (op.from_sit != 0 && now == loop::Phase::kSitDown && before != loop::Phase::kSitDown &&
          before != loop::Phase::kHold)
        Fail("a sit-down from a phase operator.from.sit does not name", tick);
      if (op.from_arm != 0 && before == loop::Phase::kPassive && now == loop::Phase::kStandUp)
        Fail("a stand-up from passive that operator.from.arm does not name", tick);
      if (now == loop::Phase::kPassive && before != loop::Phase::kPassive && before != loop::Phase::kSitDown &&
          !(op.rearm_to_passive && before == loop::Phase::kArming))
        Fail("passive not after a sit-down (or a re-arm's arming, rearm_to: passive)", tick);
      before = now;
      if (now == loop::Phase::kDone || now == loop::Phase::kFailed) return 0;
    }
  }
  return 0;
}
