// A virtual gamepad through the kernel: Linux uinput makes an Xbox-like pad whose events the
// kernel's evdev hands to the evdev transport as from a real one (/dev/input/eventN, read without
// blocking, its axis ranges read with EVIOCGABS, its state with EVIOCGKEY). Needs /dev/uinput:
// label vcan, so the test command runs it inside the test VM (tests/vm/vcan-vm loads evdev and
// uinput), or natively where the machine has SocketCAN and uinput.
//   - the live device: buttons and axes reach the fields at the next tick; unplugged (the device
//     destroyed): every field 0 at once, then silence; plugged in again: found at the next look;
//     a pad whose axis ranges differ: refused, naming the axis and both ranges;
//   - the demo session (models/quadruped_gamepad/sessions/demo.ev: stand, walk, the dead-man
//     released, e-stop with the motors damped, re-arm to passive, stand, the pad lost) and the
//     policy-switch session (switch.ev) written into the virtual pad tick by tick give the loop the
//     same operator samples, bit for bit, as the recorded files read directly, so the same HIL
//     commands (tests/sim_hil/test_gamepad_hil.cpp drives the walking quadruped with the files).
#include <doctest/doctest.h>
#include <fcntl.h>
#include <linux/uinput.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "runtime/transport/bindings.hpp"
#include "runtime/transport/evdev/evdev_transport.hpp"
#include "tests/support/robot_models.hpp"

using namespace pbppo;
using evdev::EventRecord;

namespace {

// A pad made through /dev/uinput, gone when destroyed.
class VirtualPad {
 public:
  explicit VirtualPad(int axis_max = 32767) {
    fd_ = ::open("/dev/uinput", O_WRONLY | O_NONBLOCK | O_CLOEXEC);
    REQUIRE_MESSAGE(fd_ >= 0, "/dev/uinput: " << std::strerror(errno));
    REQUIRE(::ioctl(fd_, UI_SET_EVBIT, EV_KEY) == 0);
    for (int key : {BTN_SOUTH, BTN_EAST, BTN_NORTH, BTN_WEST, BTN_TL, BTN_TR, BTN_SELECT, BTN_START, BTN_MODE})
      REQUIRE(::ioctl(fd_, UI_SET_KEYBIT, key) == 0);
    REQUIRE(::ioctl(fd_, UI_SET_EVBIT, EV_ABS) == 0);
    for (int code : {ABS_X, ABS_Y, ABS_RX, ABS_RY}) {
      REQUIRE(::ioctl(fd_, UI_SET_ABSBIT, code) == 0);
      uinput_abs_setup abs{};
      abs.code = static_cast<__u16>(code);
      abs.absinfo.minimum = -32768;
      abs.absinfo.maximum = axis_max;
      REQUIRE(::ioctl(fd_, UI_ABS_SETUP, &abs) == 0);
    }
    uinput_setup setup{};
    setup.id.bustype = BUS_USB;
    setup.id.vendor = 0x045e;
    setup.id.product = 0x028e;
    std::strncpy(setup.name, "pbppo virtual pad", UINPUT_MAX_NAME_SIZE - 1);
    REQUIRE(::ioctl(fd_, UI_DEV_SETUP, &setup) == 0);
    REQUIRE(::ioctl(fd_, UI_DEV_CREATE) == 0);
    char sysname[64] = {};
    REQUIRE(::ioctl(fd_, UI_GET_SYSNAME(sizeof sysname), sysname) >= 0);
    // /sys/devices/virtual/input/inputN/eventM -> /dev/input/eventM (devtmpfs makes the node).
    const std::filesystem::path sys = std::filesystem::path("/sys/devices/virtual/input") / sysname;
    for (int i = 0; i < 200 && path_.empty(); ++i) {
      for (const auto& e : std::filesystem::directory_iterator(sys))
        if (e.path().filename().string().rfind("event", 0) == 0) path_ = "/dev/input/" + e.path().filename().string();
      if (path_.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    REQUIRE_MESSAGE(!path_.empty(), sys.string() << " has no event node");
    for (int i = 0; i < 200 && !std::filesystem::exists(path_); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    REQUIRE(std::filesystem::exists(path_));
  }
  ~VirtualPad() { Destroy(); }
  void Emit(std::uint16_t type, std::uint16_t code, std::int32_t value) {
    input_event e{};
    e.type = type;
    e.code = code;
    e.value = value;
    REQUIRE(::write(fd_, &e, sizeof e) == static_cast<ssize_t>(sizeof e));
  }
  void Report() { Emit(EV_SYN, SYN_REPORT, 0); }
  void Destroy() {
    if (fd_ < 0) return;
    ::ioctl(fd_, UI_DEV_DESTROY);
    ::close(fd_);
    fd_ = -1;
  }
  const std::string& path() const { return path_; }

 private:
  int fd_ = -1;
  std::string path_;
};

double Field(const robot::RobotModel& m, const robot::RobotData& d, const char* name) {
  return d.fields[static_cast<std::size_t>(m.FieldIndex(name))];
}

}  // namespace

TEST_CASE(
    "gamepad uinput: a live pad's buttons and axes, unplugged and plugged in again, one of another kind refused") {
  const robot::RobotModel& m = test::GamepadRobot();
  auto pad = std::make_unique<VirtualPad>();
  const std::string node = pad->path();
  auto opened = evdev::EvdevTransport::Open(m, "gamepad", {node});
  REQUIRE_MESSAGE(opened.ok(), opened.error().message);
  evdev::EvdevTransport& t = **opened;
  robot::RobotData d = robot::MakeRobotData(m);
  const std::uint32_t stream = m.fields[static_cast<std::size_t>(m.FieldIndex("deadman"))].stream;
  std::uint64_t tick = 0;
  const auto read = [&] {
    d.tick = tick++;
    d.fresh[stream] = 0;
    t.Read(m, d);
  };
  read();
  CHECK(t.present());
  CHECK(d.fresh[stream] == 1);
  CHECK(Field(m, d, "deadman") == 0.0);
  // LB and the left stick full forward, in one report: both at the next tick, the speed ramping
  // at the robot file's 1 m/s per s (0.001 per 1 ms tick).
  pad->Emit(EV_KEY, BTN_TL, 1);
  pad->Emit(EV_ABS, ABS_Y, -32768);
  pad->Report();
  read();
  CHECK(Field(m, d, "deadman") == 1.0);
  CHECK(std::abs(Field(m, d, "command_vx") - 0.001) < 1e-12);
  // An event without its SYN_REPORT is not applied yet.
  pad->Emit(EV_KEY, BTN_START, 1);
  read();
  CHECK(Field(m, d, "arm") == 0.0);
  pad->Report();
  read();
  CHECK(Field(m, d, "arm") == 1.0);
  // Unplugged: every field 0 at once (one sample), then silence.
  pad->Destroy();
  read();
  CHECK_FALSE(t.present());
  CHECK(d.fresh[stream] == 1);
  CHECK(Field(m, d, "deadman") == 0.0);
  CHECK(Field(m, d, "command_vx") == 0.0);
  read();
  CHECK(d.fresh[stream] == 0);
  // Plugged in again (the kernel gives the free node back): found at the next look (reopen_s 0.5 s),
  // its state read from the device (nothing pressed).
  pad = std::make_unique<VirtualPad>();
  REQUIRE(pad->path() == node);
  for (int k = 0; k < 600 && !t.present(); ++k) read();
  CHECK(t.present());
  CHECK(Field(m, d, "deadman") == 0.0);
  CHECK(t.stats().opens == 2);
  CHECK(t.stats().losses == 1);
  // A pad of another kind (its axes' range [-32768, 255]) on the same node: refused, looked for again.
  pad->Destroy();
  read();
  pad = std::make_unique<VirtualPad>(255);
  REQUIRE(pad->path() == node);
  for (int k = 0; k < 600 && t.stats().refused == 0; ++k) read();
  CHECK_FALSE(t.present());
  CHECK(t.stats().refused >= 1);
  CHECK_MESSAGE(
      std::string(t.refusal()).find("axis ABS_Y has range [-32768, 255], the robot file says [-32768, 32767]") !=
          std::string::npos,
      std::string(t.refusal()));
  CHECK(t.Summary().find("refused (the last: ") != std::string::npos);
}

namespace {

// A session (models/quadruped_gamepad/sessions/NAME.ev) written into a virtual pad tick by tick
// gives the loop the same operator samples, bit for bit, as the recorded file read directly: every
// field and the stream's freshness after each tick's read. The loop is a function of its samples
// (the replay tests), so the live pad drives the HIL to the file's commands, which
// tests/sim_hil/test_gamepad_hil.cpp checks tick by tick (stand, walk, damping, the policy switch).
void SameSamplesLive(const std::string& name) {
  const robot::RobotModel& m = test::GamepadRobot();
  const std::string session = test::SourcePath("models/quadruped_gamepad/sessions/" + name + ".ev");
  std::vector<EventRecord> records;
  {
    std::ifstream in(session, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    records.resize(bytes.size() / sizeof(EventRecord));
    std::memcpy(records.data(), bytes.data(), records.size() * sizeof(EventRecord));
  }
  REQUIRE(records.size() > 10);
  const auto us = [&](const EventRecord& e) {
    return static_cast<double>(e.sec - records[0].sec) * 1e6 + static_cast<double>(e.usec - records[0].usec);
  };
  // A second past the file's end: the pad lost, then silence.
  const auto ticks = static_cast<std::uint64_t>(std::llround((us(records.back()) * 1e-6 + 1.0) / m.tick_period_s));
  const std::uint32_t stream = m.fields[static_cast<std::size_t>(m.FieldIndex("deadman"))].stream;
  struct Run {
    std::vector<double> fields;  // each tick's fields, one after another
    std::vector<std::uint8_t> fresh;
    evdev::EvdevStats stats;
  };
  const auto run = [&](const std::string& device, VirtualPad* pad) {
    transport::Settings s;
    s.evdev.device = device;
    auto op = transport::Open(m, m.transports[static_cast<std::size_t>(m.TransportIndex("gamepad"))], s);
    REQUIRE_MESSAGE(op.ok(), op.error().message);
    robot::RobotData d = robot::MakeRobotData(m);
    Run r;
    r.fields.reserve(ticks * d.fields.size());
    r.fresh.reserve(ticks);
    // Into the virtual pad before each tick: the records the file applies at that tick (an event t
    // after the first at the first tick at least t from the start); the pad unplugged where the
    // file ends.
    std::size_t next = 0;
    for (std::uint64_t k = 0; k < ticks; ++k) {
      const double elapsed_us = static_cast<double>(k) * m.tick_period_s * 1e6;
      if (pad != nullptr) {
        for (; next < records.size() && us(records[next]) <= elapsed_us + 0.5; ++next)
          if (records[next].type != EV_MSC) pad->Emit(records[next].type, records[next].code, records[next].value);
        if (next == records.size() && elapsed_us > us(records.back()) + 0.5) pad->Destroy();
      }
      d.tick = k;
      d.fresh[stream] = 0;
      (*op)->Read(m, d);
      r.fields.insert(r.fields.end(), d.fields.begin(), d.fields.end());
      r.fresh.push_back(d.fresh[stream]);
    }
    const auto* evdev_transport = dynamic_cast<const evdev::EvdevTransport*>(op->get());
    REQUIRE(evdev_transport != nullptr);
    r.stats = evdev_transport->stats();
    return r;
  };
  const Run from_file = run(session, nullptr);
  VirtualPad pad;
  const Run live = run(pad.path(), &pad);
  REQUIRE(live.fields.size() == from_file.fields.size());
  std::size_t different = 0, first_different = live.fields.size();
  for (std::size_t i = 0; i < live.fields.size(); ++i) {
    // bit for bit (memcmp: a NaN equals the same NaN, and -0 differs from +0)
    if (std::memcmp(&live.fields[i], &from_file.fields[i], sizeof(double)) != 0) {
      ++different;
      first_different = std::min(first_different, i);
    }
  }
  const std::size_t width = live.fields.size() / ticks;
  MESSAGE(name << ": " << ticks << " ticks x " << width << " fields, " << different << " different"
               << (different > 0 ? " (the first at tick " + std::to_string(first_different / width) + ")" : ""));
  CHECK(different == 0);
  CHECK(live.fresh == from_file.fresh);
  // The session moved the pad (its stick reached the command field) and the pad was lost once.
  std::size_t moving = 0;
  for (std::size_t k = 0; k < ticks; ++k)
    moving += live.fields[k * width + static_cast<std::size_t>(m.FieldIndex("command_vx"))] != 0.0 ? 1 : 0;
  CHECK(moving > 100);
  // The kernel's input core passes on only what changes a device's state, so a report that repeats
  // the state (the file has some) never reaches the live reader: fewer reports, the same samples.
  CHECK(live.stats.reports <= from_file.stats.reports);
  CHECK(live.stats.reports > 10);
  CHECK(live.stats.losses == 1);
  CHECK(live.stats.refused == 0);
  CHECK(live.stats.dropped == 0);
}

}  // namespace

TEST_CASE(
    "gamepad uinput: the demo session through a virtual pad (stand, walk, dead-man, e-stop damping, re-arm to passive, "
    "stand, pad lost) gives the loop the same operator samples as its file") {
  SameSamplesLive("demo");
}

TEST_CASE(
    "gamepad uinput: the policy-switch session through a virtual pad (RB mid-walk and back) gives the loop the same "
    "operator samples as its file") {
  SameSamplesLive("switch");
}
