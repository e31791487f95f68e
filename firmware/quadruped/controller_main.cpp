// pbppo-controller-quadruped: the quadruped's controller program.
//
//   pbppo-controller-quadruped --can can0,can1 --mode stand-test [--trajectory FILE]
//       [--robot models/quadruped/robot.yaml]
//       [--duration S] [--candump FILE] [--lockstep-wait-ms N] [--rt] [--receive-all]
//
// Arming (enter motor mode, every reply seen), ramp to the default pose, hold, the trajectory's
// sinusoids if given; SIGINT/SIGTERM (or --duration) -> damping -> motor off -> exit. Ticks at
// 1 kHz on absolute deadlines (clock_nanosleep). --lockstep-wait-ms N: each tick first waits up
// to N ms for the replies to the previous tick's frames (a simulator slower than real time).
// --rt: mlockall and SCHED_FIFO 80 (needs the privilege; failure is reported, not fatal).
#include <sched.h>
#include <signal.h>
#include <sys/mman.h>
#include <time.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "firmware/quadruped/stand_controller.hpp"
#include "runtime/robot/robot_model.hpp"

namespace {

pbppo::firmware::StandController* g_controller = nullptr;
void OnSignal(int) {
  if (g_controller != nullptr) g_controller->RequestShutdown();
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
               "pbppo-controller-quadruped: %s\nusage: pbppo-controller-quadruped --can IF0,IF1 --mode stand-test "
               "[--trajectory FILE] [--robot FILE]\n"
               "         [--duration S] [--candump FILE] [--lockstep-wait-ms N] [--rt] [--receive-all]\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pbppo;
  std::string robot_path = "models/quadruped/robot.yaml";
  std::string mode, trajectory_path;
  double duration_s = 0;
  int lockstep_wait_ms = 0;
  bool rt = false;
  firmware::StandControllerOptions o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "pbppo-controller-quadruped: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--can")
      o.interfaces = Split(next());
    else if (a == "--mode")
      mode = next();
    else if (a == "--trajectory")
      trajectory_path = next();
    else if (a == "--robot")
      robot_path = next();
    else if (a == "--duration")
      duration_s = std::atof(next().c_str());
    else if (a == "--candump")
      o.candump_path = next();
    else if (a == "--lockstep-wait-ms")
      lockstep_wait_ms = std::atoi(next().c_str());
    else if (a == "--rt")
      rt = true;
    else if (a == "--receive-all")
      o.receive_all = true;
    else
      return Usage(("unknown option " + a).c_str());
  }
  if (mode != "stand-test") return Usage("--mode must be 'stand-test'");
  auto model = robot::LoadRobotModel(robot_path);
  if (!model.ok()) return std::fprintf(stderr, "pbppo-controller-quadruped: %s\n", model.error().message.c_str()), 1;
  if (!model->body || !model->can)
    return std::fprintf(stderr, "pbppo-controller-quadruped: %s: no description or CAN map\n", robot_path.c_str()), 1;
  const robot::RobotDescription* robot = &*model->body;
  const robot::CanMap* map = &*model->can;
  if (o.interfaces.empty())
    for (const auto& b : map->buses) o.interfaces.push_back(b.interface);
  if (!trajectory_path.empty()) {
    // The robot's own trajectory was read with the robot; another file is read here.
    auto doc = model->Document("stand_trajectory");
    const bool own = doc && std::filesystem::equivalent((*doc)->path, trajectory_path);
    auto t = own ? firmware::ParseTrajectory((*doc)->text, "stand_trajectory.yaml", *robot)
                 : firmware::LoadTrajectory(trajectory_path, *robot);
    if (!t.ok()) return std::fprintf(stderr, "pbppo-controller-quadruped: %s\n", t.error().message.c_str()), 1;
    o.has_trajectory = true;
    o.trajectory = *t;
  }
  auto ctl = firmware::StandController::Make(*robot, *map, o);
  if (!ctl.ok()) return std::fprintf(stderr, "pbppo-controller-quadruped: %s\n", ctl.error().message.c_str()), 1;
  firmware::StandController& c = **ctl;
  if (rt) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) std::perror("pbppo-controller-quadruped: mlockall");
    sched_param sp{};
    sp.sched_priority = 80;
    if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) std::perror("pbppo-controller-quadruped: SCHED_FIFO");
  }
  g_controller = &c;
  struct sigaction sa{};
  sa.sa_handler = OnSignal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::printf("pbppo-controller-quadruped: stand-test on %s,%s%s\n", o.interfaces[0].c_str(),
              o.interfaces.size() > 1 ? o.interfaces[1].c_str() : "", o.has_trajectory ? " with a trajectory" : "");
  std::fflush(stdout);

  const std::size_t buses = c.bus_count();
  std::vector<std::uint32_t> expect(buses, 0);
  const std::uint64_t duration_ticks = duration_s > 0 ? static_cast<std::uint64_t>(duration_s * 1000.0) : UINT64_MAX;
  firmware::Phase last = c.phase();
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  std::uint64_t overruns = 0;
  while (c.phase() != firmware::Phase::kDone && c.phase() != firmware::Phase::kFailed) {
    if (lockstep_wait_ms > 0) {
      // Replies expected: one per frame sent last tick (the IMU's frames come on top).
      for (std::size_t b = 0; b < buses; ++b) expect[b] = c.sent_last_tick(b);
      c.Tick(expect.data(), static_cast<std::int64_t>(lockstep_wait_ms) * 1'000'000);
    } else {
      c.Tick(nullptr, 0);
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
    if (c.tick() == duration_ticks) c.RequestShutdown();
    if (c.phase() != last) {
      std::printf("pbppo-controller-quadruped: tick %llu: %s -> %s (supervisor %s)\n",
                  static_cast<unsigned long long>(c.tick()), firmware::ToString(last), firmware::ToString(c.phase()),
                  safety::ToString(c.supervisor().mode));
      std::fflush(stdout);
      last = c.phase();
    }
  }
  c.Stop();
  const auto& sup = c.supervisor();
  std::printf("pbppo-controller-quadruped: %s after %llu ticks, %llu overruns; supervisor %s, %llu decisions\n",
              firmware::ToString(c.phase()), static_cast<unsigned long long>(c.tick()),
              static_cast<unsigned long long>(overruns), safety::ToString(sup.mode),
              static_cast<unsigned long long>(sup.decisions));
  for (std::size_t m = 1; m < safety::kModeCount; ++m)
    if (sup.ticks_in_mode[m] > 0)
      std::printf("  entered %s at tick %llu: %s\n", safety::ToString(static_cast<safety::Mode>(m)),
                  static_cast<unsigned long long>(sup.entered_tick[m]),
                  safety::Describe(c.supervisor_model(), sup.entered[m]).c_str());
  if (c.trajectory_ticks() > 0)
    std::printf("  trajectory tracking RMS %.4f rad over %llu ticks\n", c.rms_tracking_error_rad(),
                static_cast<unsigned long long>(c.trajectory_ticks()));
  return c.phase() == firmware::Phase::kDone ? 0 : 1;
}
