// pbppo-hil: the HIL simulator program.
//
//   pbppo-hil auv --layout easy|medium|hard --seed N [--lockstep | --realtime] [--domain D]
//             [--max-time S] [--trajectory out.csv] [--plot out.png] [--events out.json]
//
// The AUV navigation task over DDS (sim_hil/auv_hil.hpp).
//
//   pbppo-hil quadruped --stand --can vcan0,vcan1 [--lockstep] [--duration S]
//             [--robot models/quadruped/robot.yaml]
//             [--drop-rate P --drop-burst N --seed S] [--silent-motor JOINT --silent-from S]
//
// Free-running (default): one tick per millisecond of wall time (absolute deadlines); ticks that
// end after their deadline are counted as overruns. --lockstep: a tick starts when the
// controller's frames of its tick have arrived, so the
// simulation follows the controller at whatever speed the machine allows.
// (A tick then starts when one frame per motor has arrived on each bus, or after 100 ms.)
#include <signal.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/robot/robot_model.hpp"
#include "sim_hil/auv_hil.hpp"
#include "sim_hil/quadruped_stand_hil.hpp"

namespace {

std::atomic<bool> g_stop{false};
void OnSignal(int) {
  g_stop.store(true);
}

std::vector<std::string> Split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(item);
  return out;
}

int Usage(const char* why) {
  std::fprintf(stderr,
               "pbppo-hil: %s\nusage: pbppo-hil auv ... (pbppo-hil auv --help)\n       pbppo-hil quadruped --stand "
               "--can IF0,IF1 [--lockstep] [--duration S]\n"
               "         [--robot FILE] [--drop-rate P] [--drop-burst N] [--seed N]\n"
               "         [--silent-motor JOINT] [--silent-from S]\n",
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
  std::string robot_path = "models/quadruped/robot.yaml";
  std::string silent_joint;
  double duration_s = 0, silent_from_s = 0;
  bool stand = false, lockstep = false;
  sim::StandHilOptions o;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "pbppo-hil: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--stand")
      stand = true;
    else if (a == "--lockstep")
      lockstep = true;
    else if (a == "--can")
      o.interfaces = Split(next());
    else if (a == "--robot")
      robot_path = next();
    else if (a == "--duration")
      duration_s = std::atof(next().c_str());
    else if (a == "--drop-rate")
      o.drop_probability = std::atof(next().c_str());
    else if (a == "--drop-burst")
      o.max_drop_burst = static_cast<std::uint32_t>(std::atoi(next().c_str()));
    else if (a == "--seed")
      o.seed = static_cast<std::uint64_t>(std::atoll(next().c_str()));
    else if (a == "--silent-motor")
      silent_joint = next();
    else if (a == "--silent-from")
      silent_from_s = std::atof(next().c_str());
    else
      return Usage(("unknown option " + a).c_str());
  }
  if (!stand) return Usage("only --stand is implemented (the base welded to a stand)");
  auto model = robot::LoadRobotModel(robot_path);
  if (!model.ok()) return std::fprintf(stderr, "pbppo-hil: %s\n", model.error().message.c_str()), 1;
  if (!model->body || !model->can)
    return std::fprintf(stderr, "pbppo-hil: %s: no description or CAN map\n", robot_path.c_str()), 1;
  const robot::RobotDescription* robot = &*model->body;
  const robot::CanMap* map = &*model->can;
  if (o.interfaces.empty())
    for (const auto& b : map->buses) o.interfaces.push_back(b.interface);
  if (!silent_joint.empty()) {
    for (std::size_t m = 0; m < map->motors.size(); ++m)
      if (map->motors[m].joint == silent_joint) o.silent_motor = static_cast<int>(m);
    if (o.silent_motor < 0)
      return std::fprintf(stderr, "pbppo-hil: --silent-motor '%s' is not a motor\n", silent_joint.c_str()), 1;
    o.silent_from_tick = static_cast<std::uint64_t>(silent_from_s * 1000.0);
  }
  auto hil = sim::StandHil::Make(*robot, *map, o);
  if (!hil.ok()) return std::fprintf(stderr, "pbppo-hil: %s\n", hil.error().message.c_str()), 1;
  signal(SIGINT, OnSignal);
  signal(SIGTERM, OnSignal);
  std::printf("pbppo-hil: quadruped on a stand, %zu joints, %s on %s, %s\n", robot->joint_count(), robot_path.c_str(),
              o.interfaces[0].c_str(), lockstep ? "lock-step" : "free-running at 1 kHz");
  std::fflush(stdout);

  // Lock-step: a tick waits for one frame per motor on each bus (what the controller sends per tick).
  std::vector<std::uint32_t> per_bus(o.interfaces.size(), 0);
  for (const auto& m : map->motors) ++per_bus[m.bus];
  std::uint64_t overruns = 0;
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  const auto t0 = std::chrono::steady_clock::now();
  const std::uint64_t limit = duration_s > 0 ? static_cast<std::uint64_t>(duration_s * 1000.0) : UINT64_MAX;
  bool ok = true;
  while (!g_stop.load() && (*hil)->tick() < limit) {
    if (lockstep) {
      ok = (*hil)->Tick(per_bus.data(), 100'000'000);
    } else {
      ok = (*hil)->Tick(nullptr, 0);
      next.tv_nsec += 1'000'000;
      if (next.tv_nsec >= 1'000'000'000) {
        next.tv_nsec -= 1'000'000'000;
        ++next.tv_sec;
      }
      timespec now{};
      clock_gettime(CLOCK_MONOTONIC, &now);
      if (now.tv_sec > next.tv_sec || (now.tv_sec == next.tv_sec && now.tv_nsec > next.tv_nsec)) ++overruns;
      clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    }
    if (!ok) break;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double sim_s = static_cast<double>((*hil)->tick()) * 1e-3;
  std::printf("pbppo-hil: %.3f s simulated in %.3f s wall (%.3f simulated s per wall s), %llu overruns%s\n", sim_s,
              wall, sim_s / wall, static_cast<unsigned long long>(overruns), ok ? "" : ", PLANT FAILED");
  for (std::size_t m = 0; m < (*hil)->motor_count(); ++m) {
    const auto& s = (*hil)->motor(m);
    std::printf("  %-7s frames %llu replies %llu dropped %llu watchdog %llu motor_mode %d q %.4f\n",
                map->motors[m].joint.c_str(), static_cast<unsigned long long>(s.frames),
                static_cast<unsigned long long>(s.replies), static_cast<unsigned long long>(s.dropped),
                static_cast<unsigned long long>(s.timeouts), s.motor_mode ? 1 : 0,
                (*hil)->plant().q_rad((*hil)->joint_of_motor(m)));
  }
  for (std::size_t b = 0; b < (*hil)->bus_count(); ++b) {
    const auto& s = (*hil)->bus_stats(b);
    std::printf("  bus %s: rx %llu tx %llu unknown ids %llu wrong lengths %llu error frames %llu\n",
                o.interfaces[b].c_str(), static_cast<unsigned long long>(s.rx_frames),
                static_cast<unsigned long long>(s.tx_frames), static_cast<unsigned long long>(s.unknown_ids),
                static_cast<unsigned long long>(s.wrong_lengths), static_cast<unsigned long long>(s.error_frames));
  }
  return ok ? 0 : 1;
}
