// Gamepads through Linux evdev (runtime/transport/evdev): a robot file's axes and buttons read from
// recorded event files (what reading /dev/input/eventN gives) into a stream's fields, the loop's
// operator requests from those fields, and the robot files that get them wrong. A live device is
// exercised as far as this machine has one: a path that is not there, and a FIFO (no axes:
// refused and looked for again).
#include <doctest/doctest.h>
#include <linux/input-event-codes.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/transport/bindings.hpp"
#include "runtime/transport/evdev/evdev_transport.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/scripted_transport.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;
using evdev::EventRecord;

namespace {

// A robot with a gamepad and one command (no motors): 100 Hz.
const char* kRobot = R"(robot: padbot
description: a gamepad's axes and buttons and one speed command
files: {}
timing: {tick_period_s: 0.01, policy_period_s: 0.01}
transports:
  - name: gamepad
    kind: evdev
    device: pad.ev
    stream: pad
    axes:
      vx: {code: ABS_Y, range: [-32768, 32767], scale: -1.0, dead_zone: 0.1, rate_per_s: 2.0}
      yaw: {code: ABS_RX, range: [-32768, 32767], scale: 0.5}
    buttons: {deadman: BTN_TL, arm: BTN_START, stop: BTN_EAST, estop: BTN_SELECT, rearm: BTN_MODE}
streams:
  - name: pad
    transport: gamepad
    period_s: 0.01
    zero_after: 5
    invalid_safe_stop: 1
    fields:
      - {name: vx, min: -1, max: 1}
      - {name: yaw, min: -0.5, max: 0.5}
      - {name: deadman, min: 0, max: 1}
      - {name: arm, min: 0, max: 1}
      - {name: stop, min: 0, max: 1}
      - {name: estop, min: 0, max: 1}
      - {name: rearm, min: 0, max: 1}
commands:
  - name: speed
    unit: m/s
    range: [-1.0, 1.0]
    stop: {ramp_per_s: 3.0}
supervisor:
  command_limit: count
  overrun: {degraded: 2, safe_stop: 5}
  recovery: {rule: request, healthy_s: 0.3}
operator: {arm: arm, stop: stop, estop: estop, rearm: rearm, deadman: deadman}
)";

// Events in time order; Syn closes a report.
struct Pad {
  std::vector<EventRecord> ev;
  Pad& At(double t_s, std::uint16_t type, std::uint16_t code, std::int32_t value) {
    const auto us = static_cast<std::int64_t>(std::llround(t_s * 1e6)) + 1'700'000'000'000'000;  // an epoch time
    ev.push_back(EventRecord{us / 1'000'000, us % 1'000'000, type, code, value});
    return *this;
  }
  Pad& Axis(double t, std::uint16_t code, std::int32_t v) {
    return At(t, EV_ABS, code, v).At(t, EV_SYN, SYN_REPORT, 0);
  }
  Pad& Key(double t, std::uint16_t code, bool down) {
    return At(t, EV_MSC, MSC_SCAN, 0x90001).At(t, EV_KEY, code, down ? 1 : 0).At(t, EV_SYN, SYN_REPORT, 0);
  }
};

struct PadRobot {
  std::string dir;
  robot::RobotModel model;
};

// The robot file (edited by `edit`) in a fresh folder with `pad` as its event file.
PadRobot MakeRobot(const std::string& scratch, const Pad& pad, const std::string& text = kRobot) {
  PadRobot r;
  r.dir = test::ScratchDir(scratch);
  std::ofstream(r.dir + "/robot.yaml") << text;
  REQUIRE(evdev::WriteEventFile(r.dir + "/pad.ev", pad.ev).ok());
  auto m = robot::LoadRobotModel(r.dir + "/robot.yaml");
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  r.model = std::move(*m);
  return r;
}

// The robot (MakeRobot) with its gamepad open on `pad` and the robot's data.
struct OpenPad {
  PadRobot r;
  std::unique_ptr<evdev::EvdevTransport> t;
  robot::RobotData d;
};
OpenPad Open(const std::string& scratch, const Pad& pad) {
  OpenPad o;
  o.r = MakeRobot(scratch, pad);
  auto t = evdev::EvdevTransport::Open(o.r.model, "gamepad");
  REQUIRE_MESSAGE(t.ok(), t.error().message);
  o.t = std::move(*t);
  o.d = robot::MakeRobotData(o.r.model);
  return o;
}

double Field(const robot::RobotModel& m, const robot::RobotData& d, const char* name) {
  return d.fields[static_cast<std::size_t>(m.FieldIndex(name))];
}

// The error of loading kRobot with `from` replaced by `to`.
std::string LoadError(const std::string& scratch, const std::string& from, const std::string& to) {
  std::string text = kRobot;
  const auto at = text.find(from);
  REQUIRE_MESSAGE(at != std::string::npos, from);
  text.replace(at, from.size(), to);
  const std::string dir = test::ScratchDir(scratch);
  std::ofstream(dir + "/robot.yaml") << text;
  auto m = robot::LoadRobotModel(dir + "/robot.yaml");
  REQUIRE_FALSE(m.ok());
  return m.error().message;
}

// The gamepad robot's loop fed every tick with nominal samples (the IMU upright, every other field
// 0 inside its range) whose operator fields a test sets; per tick its phase and the first motor's
// (LF_HFE's) position command.
struct GamepadLoop {
  explicit GamepadLoop(const robot::RobotModel& model = test::GamepadRobot()) : m(model) {
    for (const robot::FieldSpec& f : m.fields)
      nominal.push_back(f.name == "base_imu_qw" ? 1.0 : std::clamp(0.0, f.min, f.max));
  }
  const robot::RobotModel& m;
  test::ScriptedTransport feed{m};
  robot::RobotData d = robot::MakeRobotData(m);
  std::unique_ptr<loop::LoopData> l = loop::MakeLoopData(m, nullptr, loop::LoopOptions{});
  std::vector<double> nominal;
  std::vector<loop::Phase> phase;
  std::vector<double> q;

  // As a simulator in lock-step does: a motor answers only the tick after it was sent something,
  // and the IMU samples only when the plant stepped on a command (once at the start); else every
  // stream every tick.
  bool motors_answer_commands = false;

  void Set(std::int32_t field, double v) { nominal[static_cast<std::size_t>(field)] = v; }
  bool Silent(std::uint32_t stream) const {
    if (!motors_answer_commands) return false;
    bool commanded = false;
    for (std::size_t k = 0; k < m.motors.size(); ++k)
      commanded = commanded || d.motors[k] != robot::MotorCommand::kNone;
    if (m.streams[stream].kind == robot::StreamKind::kImu) return !commanded && !phase.empty();
    for (std::size_t k = 0; k < m.motors.size(); ++k)
      if (m.motors[k].stream == stream) return d.motors[k] == robot::MotorCommand::kNone;
    return false;
  }
  void Run(std::uint64_t ticks) {
    robot::Transport* ts[] = {&feed};
    for (std::uint64_t k = 0; k < ticks; ++k) {
      for (std::uint32_t s = 0; s < m.streams.size(); ++s) {
        const robot::StreamSpec& sp = m.streams[s];
        if (!Silent(s)) feed.Put(m, s, std::span<const double>(nominal.data() + sp.first_field, sp.field_count));
      }
      rt::TickTiming t;
      t.tick = phase.size();
      loop::Tick(m, d, *l, ts, t);
      phase.push_back(l->phase());
      q.push_back(d.command[m.motors[1].q]);
    }
  }
  std::string Last() const { return l->operator_status().last; }
};

// The gamepad robot's file (models/quadruped_gamepad) with `from` replaced by `to`, loaded from a
// scratch copy beside the quadruped's files.
Result<robot::RobotModel> GamepadWith(const std::string& scratch, const std::string& from, const std::string& to) {
  const std::string quadruped = test::CopyRobotFolder("quadruped", scratch);
  std::ifstream in(test::SourcePath("models/quadruped_gamepad/robot.yaml"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = text.find(from);
  REQUIRE_MESSAGE(at != std::string::npos, from);
  text.replace(at, from.size(), to);
  const std::string dir = quadruped + "/../gamepad";
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/robot.yaml") << text;
  return robot::LoadRobotModel(dir + "/robot.yaml");
}

// START, the stand-up and the hold, then the e-stop pressed: the loop at the press's tick.
void HoldThenEStop(GamepadLoop& g) {
  g.Set(g.m.op.arm, 1);
  g.Run(1300);
  REQUIRE(g.phase.back() == loop::Phase::kHold);
  g.Set(g.m.op.arm, 0);
  g.Set(g.m.op.estop, 1);
  g.Run(1);
  CHECK(g.l->supervisor().mode == safety::Mode::kEStop);
}
}  // namespace

TEST_CASE("evdev: a recorded file's axes and buttons at their times - dead zone, scale, rate limit, reports") {
  Pad pad;
  pad.Axis(0.0, ABS_Y, 0)               // centred
      .At(0.10, EV_ABS, ABS_Y, -32768)  // full forward (evdev's y grows downwards) ...
      .At(0.15, EV_ABS, ABS_RX, 32767)  // ... and the yaw stick, in one report ...
      .At(0.20, EV_SYN, SYN_REPORT, 0)  // ... applied together at its SYN_REPORT
      .Axis(1.00, ABS_Y, -1638)         // inside the 10 % dead zone
      .Key(1.10, BTN_TL, true)
      .At(1.20, EV_KEY, BTN_TL, 2)  // auto-repeat: still pressed
      .At(1.20, EV_SYN, SYN_REPORT, 0)
      .Key(1.30, BTN_TR, true)  // no field: counted, not applied
      .Axis(1.40, ABS_Z, 200)   // no field either
      .Key(1.50, BTN_TL, false);
  OpenPad o = Open("evdev_mapping", pad);
  const robot::RobotModel& m = o.r.model;
  auto& t = o.t;
  robot::RobotData& d = o.d;
  std::vector<double> vx, yaw, deadman;
  std::vector<std::uint8_t> fresh;
  for (std::uint64_t k = 0; k < 200; ++k) {
    d.tick = 1000 + k;  // the file's clock starts at the first Read, whatever the tick
    std::fill(d.fresh.begin(), d.fresh.end(), std::uint8_t{0});
    t->Read(m, d);
    vx.push_back(Field(m, d, "vx"));
    yaw.push_back(Field(m, d, "yaw"));
    deadman.push_back(Field(m, d, "deadman"));
    fresh.push_back(d.fresh[0]);
  }
  // The report of 0.10-0.20 s applies at tick 20 (not at 10 or 15): the yaw at once (no rate
  // limit, 0.5 x full), vx ramps at 2 /s (0.02 per tick) towards 1 (full, past the dead zone).
  CHECK(std::abs(yaw[19]) < 1e-5);  // centred: -1 of [-32768, 32767], no dead zone
  CHECK(std::abs(yaw[20] - 0.5) < 1e-12);
  CHECK(vx[19] == 0.0);
  CHECK(std::abs(vx[20] - 0.02) < 1e-12);
  CHECK(std::abs(vx[30] - 0.22) < 1e-12);
  CHECK(std::abs(vx[68] - 0.98) < 1e-9);
  CHECK(std::abs(vx[69] - 1.0) < 1e-9);
  CHECK(std::abs(vx[99] - 1.0) < 1e-9);
  // Inside the dead zone: 0, reached at the rate limit (1 / 0.02 = 50 ticks).
  CHECK(vx[100] < 1.0);
  CHECK(std::abs(vx[149]) < 1e-9);
  CHECK(deadman[109] == 0.0);
  CHECK(deadman[110] == 1.0);
  CHECK(deadman[120] == 1.0);  // auto-repeat
  CHECK(deadman[149] == 1.0);
  CHECK(deadman[150] == 0.0);
  // Every tick while the file lasts is a sample; its end (1.50 s) is the device going away: one
  // sample of zeros at the next tick, then silence.
  for (std::size_t k = 0; k <= 151; ++k) CHECK(fresh[k] == 1);
  for (std::size_t k = 152; k < fresh.size(); ++k) CHECK(fresh[k] == 0);
  CHECK(vx[151] == 0.0);
  CHECK_FALSE(t->present());
  const evdev::EvdevStats& s = t->stats();
  CHECK(s.unmapped == 2);
  CHECK(s.losses == 1);
  CHECK(s.opens == 1);
  CHECK(s.events == 7);
  CHECK(s.reports == 8);
  const std::string summary = t->Summary();
  CHECK_MESSAGE(summary.find("2 unmapped") != std::string::npos, summary);
  CHECK_MESSAGE(summary.find("lost 1 times") != std::string::npos, summary);
}

TEST_CASE(
    "evdev: an axis value outside its range is no value (the sample check names the field), a dropped report is "
    "discarded") {
  Pad pad;
  pad.Axis(0.0, ABS_Y, 0)
      .Axis(0.05, ABS_Y, -40000)  // beyond the device's range
      .Axis(0.10, ABS_Y, -16000)
      .At(0.20, EV_ABS, ABS_Y, -32768)
      .At(0.20, EV_SYN, SYN_DROPPED, 0)  // the kernel's buffer overflowed: this report is lost ...
      .At(0.21, EV_ABS, ABS_RX, 32767)
      .At(0.22, EV_SYN, SYN_REPORT, 0)  // ... up to and with the next SYN_REPORT
      .Axis(0.30, ABS_RX, 0)
      .Key(5.0, BTN_TL, false);
  OpenPad o = Open("evdev_range", pad);
  const robot::RobotModel& m = o.r.model;
  auto& t = o.t;
  robot::RobotData& d = o.d;
  std::vector<double> vx, yaw;
  std::vector<std::int32_t> invalid;
  for (std::uint64_t k = 0; k < 40; ++k) {
    d.tick = k;
    std::fill(d.fresh.begin(), d.fresh.end(), std::uint8_t{0});
    t->Read(m, d);
    loop::CheckSample(m, d);
    vx.push_back(Field(m, d, "vx"));
    yaw.push_back(Field(m, d, "yaw"));
    invalid.push_back(d.streams[0].invalid_input);
  }
  CHECK(std::isnan(vx[5]));
  CHECK(invalid[5] == m.FieldIndex("vx"));
  CHECK(invalid[4] == -1);
  CHECK(invalid[10] == -1);
  // Back in range: the rate limit starts again from the new value, not from the NaN.
  CHECK(std::abs(vx[10] - (31999.0 / 65535.0 - 0.1) / 0.9) < 1e-12);
  // The dropped report changed nothing; the one after it applies.
  for (std::size_t k = 20; k < 30; ++k) {
    CHECK(std::abs(vx[k] - vx[10]) < 1e-12);
    CHECK(std::abs(yaw[k]) < 1e-5);
  }
  CHECK(t->stats().dropped == 1);
  CHECK(t->stats().out_of_range == 5);
  CHECK_MESSAGE(t->Summary().find("axis ABS_Y gave -40000") != std::string::npos, t->Summary());
}

TEST_CASE(
    "evdev: a device that is not there, then a FIFO without axes - no sample, refused naming the axis, looked for "
    "again") {
  Pad pad;
  pad.Key(0.0, BTN_TL, false);
  PadRobot r = MakeRobot("evdev_device", pad);
  const std::string dev = r.dir + "/event-missing";
  std::string text = kRobot;
  text.replace(text.find("device: pad.ev"), 14, "device: event-missing\n    reopen_s: 0.05");
  std::ofstream(r.dir + "/robot.yaml") << text;
  auto m = robot::LoadRobotModel(r.dir + "/robot.yaml");
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  robot::TransportSpec spec = m->transports[0];
  auto opened = transport::Open(*m, spec, transport::Settings{});  // through the transport table
  REQUIRE_MESSAGE(opened.ok(), opened.error().message);
  robot::Transport& t = **opened;
  auto& e = dynamic_cast<evdev::EvdevTransport&>(t);
  robot::RobotData d = robot::MakeRobotData(*m);
  for (std::uint64_t k = 0; k < 10; ++k) {
    d.tick = k;
    std::fill(d.fresh.begin(), d.fresh.end(), std::uint8_t{0});
    t.Read(*m, d);
    CHECK(d.fresh[0] == 0);
  }
  CHECK_FALSE(e.present());
  CHECK(e.stats().opens == 0);
  REQUIRE(::mkfifo(dev.c_str(), 0600) == 0);
  for (std::uint64_t k = 10; k < 30; ++k) {
    d.tick = k;
    t.Read(*m, d);
  }
  CHECK(e.stats().refused >= 2);  // every 5 ticks
  CHECK(e.stats().refused <= 4);
  CHECK_FALSE(e.present());
  CHECK_MESSAGE(std::string(e.refusal()).find("has no axis ABS_Y") != std::string::npos, e.refusal());
  CHECK_MESSAGE(t.Summary().find("refused") != std::string::npos, t.Summary());
}

TEST_CASE("evdev: Read allocates nothing") {
  Pad pad;
  for (int i = 0; i < 100; ++i) pad.Axis(0.01 * i, ABS_Y, -300 * i).Key(0.01 * i + 0.005, BTN_TL, i % 2 == 0);
  OpenPad o = Open("evdev_alloc", pad);
  AllocationScope scope;
  for (std::uint64_t k = 0; k < 150; ++k) {
    o.d.tick = k;
    o.t->Read(o.r.model, o.d);
  }
  CHECK(scope.count() == 0);
  CHECK_FALSE(o.t->present());
}

TEST_CASE(
    "evdev: a recorded file that is not whole records, is empty, or whose times run backwards, is refused naming it") {
  Pad pad;
  pad.Key(0.0, BTN_TL, true);
  PadRobot r = MakeRobot("evdev_bad_file", pad);
  {
    std::ofstream(r.dir + "/pad.ev", std::ios::app) << "xyz";
    auto t = evdev::EvdevTransport::Open(r.model, "gamepad");
    REQUIRE_FALSE(t.ok());
    CHECK_MESSAGE(
        t.error().message.find("pad.ev has 75 bytes, not a whole number of 24-byte event records") != std::string::npos,
        t.error().message);
  }
  {
    std::ofstream(r.dir + "/pad.ev", std::ios::trunc);
    auto t = evdev::EvdevTransport::Open(r.model, "gamepad");
    REQUIRE_FALSE(t.ok());
    CHECK_MESSAGE(t.error().message.find("pad.ev holds no event") != std::string::npos, t.error().message);
  }
  Pad back;
  back.Key(1.0, BTN_TL, true).Key(0.5, BTN_TL, false);
  REQUIRE(evdev::WriteEventFile(r.dir + "/pad.ev", back.ev).ok());
  auto t = evdev::EvdevTransport::Open(r.model, "gamepad");
  REQUIRE_FALSE(t.ok());
  CHECK_MESSAGE(t.error().message.find("record 3 has time") != std::string::npos, t.error().message);
}

TEST_CASE("evdev: robot files that map a gamepad wrongly are refused naming the field and the value") {
  const std::pair<std::pair<const char*, const char*>, const char*> cases[] = {
      {{"code: ABS_Y", "code: ABS_Q"}, "transports[0].axes.vx.code: 'ABS_Q' is not an axis (ABS_X, ABS_Y"},
      {{"arm: BTN_START", "arm: BTN_PLAY"}, "transports[0].buttons.arm: 'BTN_PLAY' is not a button"},
      {{"code: ABS_RX", "code: ABS_Y"}, "transports[0].axes.yaw.code: ABS_Y drives two fields"},
      {{"stop: BTN_EAST", "stop: BTN_TL"}, "transports[0].buttons.stop: BTN_TL drives two fields"},
      {{"range: [-32768, 32767], scale: -1.0", "range: [5, 5], scale: -1.0"}, "axes.vx.range: [5, 5] is not"},
      {{"range: [-32768, 32767], scale: 0.5", "range: [-32768, 32767], scale: 0.8"},
       "axes.yaw.scale: field 'yaw' has range [-0.5, 0.5], which does not hold [-0.8, 0.8]"},
      {{"dead_zone: 0.1", "dead_zone: 1.5"}, "axes.vx.dead_zone"},
      {{"vx: {code", "speed: {code"}, "axes.speed: 'speed' is not a field of stream 'pad'"},
      {{", rearm: BTN_MODE}", "}"}, "field 'rearm' of stream 'pad' is no axis or button"},
      {{"stream: pad", "stream: pads"}, "transports[0].stream: 'pads' is not a stream of the robot"},
      {{"kind: evdev", "kind: hid"}, "transports[0].kind: 'hid' is not can, dds or evdev"},
      {{"    device: pad.ev\n", ""}, "transports[0]: missing field 'device'"},
      {{"operator: {arm: arm,", "operator: {arm: fire,"}, "operator.arm: 'fire' is not a field of the robot"},
      {{"stop: stop,", "stop: arm,"}, "operator.stop: field 'arm' makes another request already"},
      {{"operator: {arm: arm,", "operator: {walk: arm,"}, "operator.walk: the robot has no motors"},
      {{"operator: {arm: arm,", "operator: {arm: yaw,"}, "operator.arm: field 'yaw' has range [-0.5, 0.5]"},
      {{"operator: {arm: arm,", "operator: {arm: arm, nap: vx,"}, "operator"},
      {{"operator: {arm: arm,", "operator: {arm: arm, sit: vx,"},
       "operator.sit: the robot does not sit: phases.sit_down_s is not given"},
      {{"      vx: {code", "      [vx, vy]: {code"}, "a mapping key that is not a name"},
      {{"operator: {arm: arm,", "operator: {arm: arm, deadman_sit_after_s: 2,"},
       "operator.deadman_sit_after_s: the robot does not sit: phases.sit_down_s is not given"},
      {{"operator: {arm: arm,", "operator: {arm: arm, deadman_sit_after_s: -1,"}, "operator.deadman_sit_after_s"},
      {{"operator: {arm: arm,", "operator: {arm: arm, rearm_to: passive,"},
       "operator.rearm_to: the robot has no motors to leave passive"},
      {{"deadman: deadman}", "deadman_sit_after_s: 2}"},
       "operator.deadman_sit_after_s: no dead-man to release (operator.deadman is not given)"},
  };
  for (const auto& [edit, expected] : cases) {
    INFO(std::string(edit.second));
    const std::string message = LoadError("evdev_bad_robot", edit.first, edit.second);
    CHECK_MESSAGE(message.find(expected) != std::string::npos, message);
  }
}

TEST_CASE(
    "evdev operator: buttons arm, the dead-man holds the run, e-stop latches and wins, rearm, stop - in the loop") {
  Pad pad;
  pad.Key(0.0, BTN_TL, false)
      .Key(0.10, BTN_START, true)  // arm without the dead-man: runs, and disarms at once
      .Key(0.20, BTN_START, false)
      .Key(0.30, BTN_TL, true)
      .Key(0.40, BTN_START, true)  // arm with it held: runs
      .Key(0.50, BTN_START, false)
      .Key(0.60, BTN_TL, false)  // released: disarmed
      .Key(0.70, BTN_TL, true)
      .Key(0.80, BTN_START, true)   // armed again
      .Key(0.90, BTN_SELECT, true)  // e-stop
      .Key(1.00, BTN_SELECT, false)
      .Key(1.05, BTN_MODE, true)  // too early: refused (healthy_s 0.3)
      .Key(1.06, BTN_MODE, false)
      .Key(1.30, BTN_MODE, true)  // re-armed
      .Key(1.40, BTN_MODE, false)
      .Key(1.45, BTN_START, false)
      .Key(1.46, BTN_START, true)  // arm while running: refused
      .Key(1.50, BTN_EAST, true)   // stop
      .Key(2.00, BTN_EAST, false);
  OpenPad o = Open("evdev_operator", pad);
  const robot::RobotModel& m = o.r.model;
  auto& t = o.t;
  robot::RobotData& d = o.d;
  auto l = loop::MakeLoopData(m, nullptr, loop::LoopOptions{});
  robot::Transport* ts[] = {t.get()};
  std::vector<loop::Phase> phase;
  std::vector<safety::Mode> mode;
  for (std::uint64_t k = 0; k < 220; ++k) {
    rt::TickTiming timing;
    timing.tick = k;
    loop::Tick(m, d, *l, ts, timing);
    phase.push_back(l->phase());
    mode.push_back(l->supervisor().mode);
  }
  using loop::Phase;
  CHECK(phase[9] == Phase::kDisarmed);
  CHECK(phase[10] == Phase::kDisarmed);  // arm and the dead-man's release in the same tick
  CHECK(phase[39] == Phase::kDisarmed);
  CHECK(phase[40] == Phase::kRun);
  CHECK(phase[59] == Phase::kRun);
  CHECK(phase[60] == Phase::kDisarmed);
  CHECK(phase[80] == Phase::kRun);
  CHECK(mode[89] == safety::Mode::kNominal);
  CHECK(mode[90] == safety::Mode::kEStop);   // the press's own tick
  CHECK(mode[129] == safety::Mode::kEStop);  // latched after the release, and the early request refused
  CHECK(l->recovery().refused == 1);
  CHECK(l->recovery().requested == 1);
  CHECK(mode[130] == safety::Mode::kNominal);
  CHECK(phase[130] == Phase::kRun);
  CHECK(phase[150] == Phase::kDone);  // stop: a robot without motors is done
  const loop::OperatorStatus& op = l->operator_status();
  CHECK(op.requests == 8);  // arm 4, e-stop 1, re-arm 2 (the early one is RecoveryStatus's refusal), stop 1
  CHECK(op.refused == 1);
  CHECK_MESSAGE(std::string(op.last) == "arm refused at tick 146: not disarmed (run)", op.last);
  CHECK(loop::Describe(op) == "8 requests, 1 refused; the last: arm refused at tick 146: not disarmed (run)");
}

TEST_CASE(
    "evdev operator: on a robot with motors, walk is taken only in hold with the dead-man held - refusals named") {
  GamepadLoop g;
  const robot::RobotModel& m = g.m;
  const auto set = [&](std::int32_t field, double v) { g.Set(field, v); };
  const auto run = [&](std::uint64_t ticks) { g.Run(ticks); };
  const std::vector<loop::Phase>& phase = g.phase;
  auto& l = g.l;
  set(m.op.arm, 1);
  run(10);  // arming, stand-up (1 s)
  CHECK(phase.back() == loop::Phase::kStandUp);
  set(m.op.walk, 1);
  run(10);
  CHECK(std::string(l->operator_status().last).find("walk refused at tick 10: not holding (stand-up)") == 0);
  set(m.op.walk, 0);
  run(1200);
  CHECK(phase.back() == loop::Phase::kHold);
  set(m.op.walk, 1);  // without the dead-man
  run(10);
  CHECK(phase.back() == loop::Phase::kHold);
  CHECK_MESSAGE(std::string(l->operator_status().last) == "walk refused at tick 1220: the dead-man is not held (hold)",
                l->operator_status().last);
  set(m.op.walk, 0);
  set(m.op.deadman, 1);
  run(10);
  set(m.op.walk, 1);  // no command source here
  run(10);
  CHECK(std::string(l->operator_status().last).find("nothing to run") != std::string::npos);
  set(m.op.switch_policy, 1);  // one command source (none here)
  run(10);
  CHECK(std::string(l->operator_status().last).find("switch refused at tick 1250: one command source (hold)") == 0);
  set(m.op.switch_policy, 0);
  set(m.op.estop, 1);
  run(10);
  CHECK(l->supervisor().mode == safety::Mode::kEStop);
  set(m.op.switch_policy, 1);  // no switch while a fault is latched
  run(10);
  CHECK_MESSAGE(std::string(l->operator_status().last) == "switch refused at tick 1270: e-stop is latched (hold)",
                l->operator_status().last);
  CHECK(l->operator_status().refused == 5);
  CHECK(l->operator_status().requests == 7);
}

TEST_CASE(
    "evdev operator: waiting disarmed for START with the motors and the IMU silent is no fault, arm with an e-stop "
    "latched refused") {
  GamepadLoop g;
  g.motors_answer_commands = true;  // disarmed, nothing is sent: no motor answers
  const robot::RobotModel& m = g.m;
  g.Run(2000);  // 2 s: four times the motors' lost limit
  CHECK(g.phase.back() == loop::Phase::kDisarmed);
  CHECK(g.l->supervisor().mode == safety::Mode::kNominal);
  CHECK(g.l->mode_change_count() == 0);
  g.Set(m.op.arm, 1);  // arming has them answering, then stand-up and hold
  g.Run(1300);
  CHECK(g.phase.back() == loop::Phase::kHold);
  CHECK(g.l->supervisor().mode == safety::Mode::kNominal);
  // Another robot: an e-stop pressed while it waits latches; START is then refused, said.
  GamepadLoop h;
  h.motors_answer_commands = true;
  h.Set(m.op.estop, 1);
  h.Run(10);
  CHECK(h.l->supervisor().mode == safety::Mode::kEStop);
  h.Set(m.op.estop, 0);
  h.Set(m.op.arm, 1);
  h.Run(10);
  CHECK(h.phase.back() == loop::Phase::kDisarmed);
  CHECK_MESSAGE(h.Last() == "arm refused at tick 10: e-stop is latched (disarmed)", h.Last());
}

TEST_CASE("evdev operator: operator.from narrows the phases a request is taken in - refusals said, bad files named") {
  auto model = GamepadWith("evdev_from", "  switch: {rule: blend, duration_s: 0.5}",
                           "  switch: {rule: blend, duration_s: 0.5}\n  from: {sit: [hold], arm: [disarmed]}");
  REQUIRE_MESSAGE(model.ok(), model.error().message);
  REQUIRE(model->op.from_sit == robot::Phases({robot::Phase::kHold}));
  GamepadLoop g(*model);
  const robot::RobotModel& m = g.m;
  using loop::Phase;
  g.Set(m.op.arm, 1);
  g.Run(10);  // stand-up
  g.Set(m.op.arm, 0);
  g.Set(m.op.sit, 1);  // the controller sits from stand-up, this robot file does not
  g.Run(1);
  CHECK(g.phase.back() == Phase::kStandUp);
  CHECK_MESSAGE(g.Last() == "sit refused at tick 10: not a phase operator.from.sit names (stand-up)", g.Last());
  g.Set(m.op.sit, 0);
  g.Run(1300);
  REQUIRE(g.phase.back() == Phase::kHold);
  g.Set(m.op.sit, 1);  // from hold: taken
  g.Run(1600);
  CHECK(g.phase.back() == Phase::kPassive);
  g.Set(m.op.sit, 0);
  g.Set(m.op.arm, 1);  // from passive: the controller stands up, this robot file does not
  g.Run(10);
  CHECK(g.phase.back() == Phase::kPassive);
  CHECK(g.Last().find(": not a phase operator.from.arm names (passive)") != std::string::npos);
  CHECK(g.l->operator_status().refused == 2);
  // Files refused naming the field and the value.
  const std::pair<std::string, std::string> bad[] = {
      {"from: {sit: [sleep]}", "operator.from.sit[0]: 'sleep' is not a phase (disarmed, arming, stand-up"},
      {"from: {sit: [passive]}",
       "operator.from.sit[0]: the controller does not take sit in passive (it does in stand-up, hold, run)"},
      {"from: {estop: [hold]}", "operator.from"},
      {"from: {walk: [hold]}", "operator.from"},
      {"from: {arm: []}", "operator.from.arm: empty"},
      {"from: [sit]", "operator.from: expected a mapping"},
  };
  for (const auto& [edit, want] : bad) {
    CAPTURE(edit);
    auto r = GamepadWith("evdev_from_bad", "  switch: {rule: blend, duration_s: 0.5}",
                         "  switch: {rule: blend, duration_s: 0.5}\n  " + edit);
    REQUIRE_FALSE(r.ok());
    CHECK_MESSAGE(r.error().message.find(want) != std::string::npos, r.error().message);
  }
}

TEST_CASE("evdev operator: operator.rearm_to passive - an e-stopped robot re-armed is left passive, START stands it") {
  // The shipped gamepad robot re-arms to passive; the same file with rearm_to: stand stands up at once.
  const auto estop_then_rearm = [](GamepadLoop& g) {
    const robot::RobotModel& m = g.m;
    HoldThenEStop(g);
    g.Run(9);
    g.Set(m.op.estop, 0);
    g.Run(600);  // healthy 0.5 s
    g.Set(m.op.rearm, 1);
    g.Run(20);  // re-armed: arming (the motors answer), then the phase rearm_to names
    CHECK(g.l->supervisor().mode == safety::Mode::kNominal);
    g.Set(m.op.rearm, 0);
  };
  using loop::Phase;
  GamepadLoop g;
  const robot::RobotModel& m = g.m;
  REQUIRE(m.op.rearm_to_passive);
  estop_then_rearm(g);
  CHECK(g.phase.back() == Phase::kPassive);  // damped, motors commanded
  CHECK(g.d.command[m.motors[1].kp] == 0.0);
  CHECK(g.d.motors[1] == robot::MotorCommand::kCommand);
  g.Set(m.op.arm, 1);  // START stands it up from there
  g.Run(1);
  CHECK(g.phase.back() == Phase::kStandUp);
  g.Run(1100);
  CHECK(g.phase.back() == Phase::kHold);
  auto standing = GamepadWith("evdev_rearm_to", "rearm_to: passive", "rearm_to: stand");
  REQUIRE_MESSAGE(standing.ok(), standing.error().message);
  CHECK_FALSE(standing->op.rearm_to_passive);
  GamepadLoop h(*standing);
  estop_then_rearm(h);
  CHECK(h.phase.back() == Phase::kStandUp);  // standing up at once
  h.Run(1100);
  CHECK(h.phase.back() == Phase::kHold);
  auto bad = GamepadWith("evdev_rearm_to_bad", "rearm_to: passive", "rearm_to: sit");
  REQUIRE_FALSE(bad.ok());
  CHECK_MESSAGE(bad.error().message.find("operator.rearm_to: 'sit' is not stand or passive") != std::string::npos,
                bad.error().message);
}

TEST_CASE("evdev operator: supervisor.estop damping - the e-stop damps with the motors on, latched until a re-arm") {
  GamepadLoop g;  // the shipped gamepad robot: supervisor.estop: damping
  const robot::RobotModel& m = g.m;
  REQUIRE(m.supervisor_model.estop_damps);
  HoldThenEStop(g);  // at the press's tick
  const safety::CommandLimit& kp = m.supervisor_model.commands[m.motors[1].kp];
  const safety::CommandLimit& kd = m.supervisor_model.commands[m.motors[1].kd];
  for (std::size_t k = 0; k < m.motors.size(); ++k) CHECK(g.d.motors[k] == robot::MotorCommand::kCommand);
  CHECK(g.d.command[m.motors[1].kp] == kp.stop_value);
  CHECK(g.d.command[m.motors[1].kd] == kd.stop_value);
  CHECK(kp.stop_value == 0.0);
  CHECK(kd.stop_value > 0.0);
  g.Set(m.op.estop, 0);
  g.Run(600);
  CHECK(g.l->supervisor().mode == safety::Mode::kEStop);  // latched
  CHECK(g.d.motors[1] == robot::MotorCommand::kCommand);
  g.Set(m.op.rearm, 1);
  g.Run(20);
  CHECK(g.l->supervisor().mode == safety::Mode::kNominal);
  // The same file with estop: motors_off: every motor switched off at the press's tick.
  auto off = GamepadWith("evdev_estop_off", "estop: damping", "estop: motors_off");
  REQUIRE_MESSAGE(off.ok(), off.error().message);
  CHECK_FALSE(off->supervisor_model.estop_damps);
  GamepadLoop h(*off);
  HoldThenEStop(h);
  for (std::size_t k = 0; k < m.motors.size(); ++k) CHECK(h.d.motors[k] == robot::MotorCommand::kDisable);
  auto bad = GamepadWith("evdev_estop_bad", "estop: damping", "estop: soft");
  REQUIRE_FALSE(bad.ok());
  CHECK_MESSAGE(bad.error().message.find("supervisor.estop: 'soft' is not motors_off or damping") != std::string::npos,
                bad.error().message);
}

TEST_CASE(
    "evdev operator: sit down from hold to the sit pose, passive (damped), stand up on arm, refusals named, stop from "
    "passive") {
  GamepadLoop g;
  const robot::RobotModel& m = g.m;
  REQUIRE(m.op.sit >= 0);
  REQUIRE(m.phases.sit_down_ticks == 1500);
  const auto set = [&](std::int32_t field, double v) { g.Set(field, v); };
  const auto run = [&](std::uint64_t ticks) { g.Run(ticks); };
  const auto last = [&] { return g.Last(); };
  const std::vector<loop::Phase>& phase = g.phase;
  const std::vector<double>& q0 = g.q;
  const robot::RobotData& d = g.d;
  auto& l = g.l;
  using loop::Phase;
  set(m.op.sit, 1);  // disarmed: nothing to sit from
  run(5);
  CHECK_MESSAGE(last() == "sit refused at tick 0: not standing (disarmed)", last());
  set(m.op.sit, 0);
  set(m.op.arm, 1);
  run(1300);  // arming, stand-up (1 s), hold
  REQUIRE(phase.back() == Phase::kHold);
  set(m.op.arm, 0);
  set(m.op.sit, 1);  // sit: from the measured pose (all 0 here) to the sit pose over 1.5 s
  run(1);
  const std::size_t sat = phase.size() - 1;
  CHECK(phase[sat] == Phase::kSitDown);
  run(1600);
  CHECK(phase[sat + 1499] == Phase::kSitDown);
  CHECK(phase[sat + 1500] == Phase::kPassive);
  CHECK(q0[sat + 1499] == doctest::Approx(m.motors[1].sit_q_rad).epsilon(1e-3));     // LF_HFE 1.2 rad
  CHECK(q0[sat + 750] == doctest::Approx(m.motors[1].sit_q_rad / 2).epsilon(1e-2));  // the smoothstep's middle
  // Passive: the damping values (kp 0), the motors commanded.
  CHECK(d.command[m.motors[1].kp] == 0.0);
  CHECK(d.command[m.motors[1].kd] > 0.0);
  CHECK(d.motors[1] == robot::MotorCommand::kCommand);
  set(m.op.sit, 0);
  set(m.op.deadman, 1);
  set(m.op.walk, 1);  // no walking from passive
  run(10);
  CHECK_MESSAGE(last() == "walk refused at tick 2906: not holding (passive)", last());
  set(m.op.walk, 0);
  set(m.op.sit, 1);
  run(10);
  CHECK_MESSAGE(last() == "sit refused at tick 2916: not standing (passive)", last());
  set(m.op.sit, 0);
  set(m.op.arm, 1);  // stand up from where it sits (the measured pose)
  run(1);
  CHECK(phase.back() == Phase::kStandUp);
  run(1100);
  CHECK(phase.back() == Phase::kHold);
  set(m.op.arm, 0);
  set(m.op.sit, 1);
  run(1600);
  CHECK(phase.back() == Phase::kPassive);
  set(m.op.sit, 0);
  set(m.op.estop, 1);  // e-stop in passive: latched; arm refused until a re-arm
  run(10);
  CHECK(l->supervisor().mode == safety::Mode::kEStop);
  CHECK(d.motors[1] == robot::MotorCommand::kCommand);  // supervisor.estop: damping
  CHECK(d.command[m.motors[1].kp] == 0.0);
  set(m.op.estop, 0);
  set(m.op.arm, 1);
  run(10);
  CHECK(phase.back() == Phase::kPassive);
  CHECK(last().find("arm refused at tick ") == 0);
  CHECK(last().find(": e-stop is latched (passive)") != std::string::npos);
  set(m.op.arm, 0);
  run(600);
  set(m.op.rearm, 1);  // healthy 0.5 s after the e-stop's release: re-armed, passive (rearm_to)
  run(5);
  CHECK(l->supervisor().mode == safety::Mode::kNominal);
  CHECK(l->recovery().requested == 1);
  CHECK(phase.back() == Phase::kPassive);
  set(m.op.rearm, 0);
  set(m.op.arm, 1);  // START stands it up
  run(1300);
  set(m.op.arm, 0);
  CHECK(phase.back() == Phase::kHold);
  set(m.op.sit, 1);
  run(1600);
  CHECK(phase.back() == Phase::kPassive);
  set(m.op.stop, 1);  // stop from passive: damping, motors off, done
  run(1);
  CHECK(phase.back() == Phase::kDamping);
  run(700);
  CHECK(phase.back() == Phase::kDone);
  CHECK(l->operator_status().refused == 4);
}
