// libFuzzer target: any bytes as a recorded gamepad event file (runtime/transport/evdev), read
// through the shipped gamepad robot's mapping (models/quadruped_gamepad) for as many ticks as the
// file lasts: refused naming the file (not whole records, times that run backwards), or played;
// every tick each axis's field is within its scale or NaN (a raw value outside the pad's range),
// each button's 0 or 1, and the stream is fresh while the file lasts.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "runtime/robot/robot_model.hpp"
#include "runtime/transport/evdev/evdev_transport.hpp"
#include "tests/fuzz/gamepad_robot.hpp"

namespace {

using namespace pbppo;

const std::string& EventFile() {
  static const std::string* path = new std::string(
      (std::filesystem::temp_directory_path() / ("pbppo_evdev_events_fuzz_" + std::to_string(::getpid()) + ".ev"))
          .string());
  static const bool cleanup = [] {
    std::atexit([] { std::remove(EventFile().c_str()); });
    return true;
  }();
  (void)cleanup;
  return *path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const robot::RobotModel& m = fuzz::GamepadRobot();
  {
    std::ofstream out(EventFile(), std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  const int t = m.TransportIndex("gamepad");
  auto pad = evdev::EvdevTransport::Open(m, "gamepad", {EventFile()});
  if (!pad) {
    if (pad.error().message.find(EventFile()) == std::string::npos) std::abort();  // names the file
    return 0;
  }
  const robot::EvdevTransportSpec& spec = m.transports[static_cast<std::size_t>(t)].evdev;
  robot::RobotData d = robot::MakeRobotData(m);
  for (std::uint64_t tick = 0; tick < 3000 && ((*pad)->present() || tick == 0); ++tick) {
    d.tick = tick;
    d.fresh[spec.stream] = 0;
    (*pad)->Read(m, d);
    if ((*pad)->present() && d.fresh[spec.stream] == 0) std::abort();
    for (const robot::EvdevAxisSpec& a : spec.axes) {
      const double v = d.fields[a.field];
      if (!std::isnan(v) && !(std::abs(v) <= std::abs(a.shape.scale) + 1e-12)) std::abort();
    }
    for (const robot::EvdevButtonSpec& b : spec.buttons)
      if (d.fields[b.field] != 0.0 && d.fields[b.field] != 1.0) std::abort();
  }
  return 0;
}
