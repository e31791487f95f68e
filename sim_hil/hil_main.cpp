// pbppo-hil: the HIL simulator program.
//
//   pbppo-hil auv --layout easy|medium|hard --seed N [--lockstep | --realtime] [--domain D]
//             [--max-time S] [--trajectory out.csv] [--plot out.png] [--events out.json]
//
// The AUV navigation task over DDS (sim_hil/auv_hil.hpp).
//
//   pbppo-hil quadruped [--scenario FILE | --stand] [--can IF0,IF1] [--lockstep] [--duration S]
//             [--robot models/quadruped/robot.yaml] [--seed N]
//
// The quadruped's plant (on the ground of a scenario, or on the stand) behind its emulated
// drivers and IMU on SocketCAN, for a pbppo-controller in another process. Free-running
// (default): one tick per millisecond of wall time (absolute deadlines); ticks that end after
// their deadline are counted as overruns. --lockstep: a tick starts when the controller's frames
// of its tick have arrived (one per motor on each bus, or after 100 ms), so the simulation
// follows the controller at whatever speed the machine allows.
//
//   pbppo-hil quadruped --in-process --policy BLOB --commands SCHEDULE [--scenario FILE]
//             [--realtime] [--trace out.csv] [--report out.json] [--plot out.png] [--profile out.json]
//             [--settle-s S]
//   pbppo-hil quadruped --in-process --policy BLOB --operator dds [--domain D] [--dds-naming ros2] [--dds-security DIR]
//             (--duration S | --commands SCHEDULE) ...
//
// The controller (runtime/loop, the policy, the schedule as its operator) and the HIL ticked in
// one process over the in-process CAN network: in lock-step (the walking demo and the sim-to-sim
// measurement, with per-phase tracking and the real-time factor) or at 1 kHz on the controller's
// clock (--realtime: its tick latency). --operator dds: the velocity commands come over DDS from
// another process (pbppo-operator, a ROS 2 node with --dds-naming ros2), at real time.
#include <signal.h>

#include <atomic>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "sim_hil/auv_hil.hpp"
#include "sim_hil/quadruped_main.hpp"

namespace {

std::atomic<bool> g_stop{false};
void OnSignal(int) {
  g_stop.store(true);
}

int Usage(const char* why) {
  std::fprintf(stderr,
               "pbppo-hil: %s\nusage: pbppo-hil auv ... (pbppo-hil auv --help)\n"
               "       pbppo-hil quadruped ... (pbppo-hil quadruped --help)\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pbppo;
  if (argc >= 2 && std::strcmp(argv[1], "auv") == 0) {
    const std::vector<std::string> args(argv + 2, argv + argc);
    if (args.size() == 1 && (args[0] == "--help" || args[0] == "-h")) {
      std::printf("usage: %s", sim::AuvHilUsage().c_str());
      return 0;
    }
    auto o = sim::ParseAuvHilArgs(args);
    if (!o.ok()) {
      std::fprintf(stderr, "pbppo-hil auv: %s\nusage: %s", o.error().message.c_str(), sim::AuvHilUsage().c_str());
      return 2;
    }
    signal(SIGINT, OnSignal);
    signal(SIGTERM, OnSignal);
    return sim::RunAuvHil(*o, g_stop);
  }
  if (argc < 2 || std::strcmp(argv[1], "quadruped") != 0)
    return Usage("the first argument must be 'auv' or 'quadruped'");
  signal(SIGINT, OnSignal);
  signal(SIGTERM, OnSignal);
  return sim::RunQuadrupedHil(argc - 1, argv + 1, g_stop);
}
