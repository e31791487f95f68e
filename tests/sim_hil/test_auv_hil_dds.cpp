// The AUV HIL simulator as a separate process (`pbppo-hil auv`) driven over DDS by a scripted
// controller in this test through the robot's DDS transport as its robot file declares it
// (dds::DdsLink, the robot's side), on the robot's loopback profile and a domain of this test's own.
#include <doctest/doctest.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "runtime/core/clock.hpp"
#include "runtime/transport/dds/dds_link.hpp"
#include "tests/support/dds_domain.hpp"
#include "tests/support/robot_models.hpp"

extern char** environ;

using namespace pbppo;

namespace {

constexpr std::int64_t kSecond = 1'000'000'000;

std::string ReadFile(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// pbppo-hil auv as a child process; stdout and stderr go to `log`.
struct Hil {
  pid_t pid = -1;
  std::string log;
  Hil(const std::vector<std::string>& extra, const std::string& log_path) : log(log_path) {
    std::vector<std::string> args = {PBPPO_HIL_EXE, "auv", "--robot", test::SourcePath("models/auv/robot.yaml")};
    args.insert(args.end(), extra.begin(), extra.end());
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    REQUIRE_MESSAGE(rc == 0, "cannot start ", args[0]);
  }
  // Exit code, or 128 + signal; -1 if it did not end within the timeout.
  int Wait(std::int64_t timeout_ns = 20 * kSecond) {
    const std::int64_t end = MonotonicNs() + timeout_ns;
    int status = 0;
    while (MonotonicNs() < end) {
      if (waitpid(pid, &status, WNOHANG) == pid) {
        pid = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return -1;
  }
  ~Hil() {
    if (pid > 0) {
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
  }
};

// The robot's side of the AUV's DDS transport: the sensor sample in, commands out (the writer
// thread), as pbppo-controller opens it.
struct Controller {
  std::unique_ptr<dds::DdsLink> link;
  std::size_t sensor = 0, command = 0;
  std::optional<dds::DdsSample> sample, out;
  std::uint64_t version = 0;
  explicit Controller(int domain) {
    dds::DdsLinkOptions o;
    o.domain_id = domain;
    auto r = dds::DdsLink::Open(test::AuvRobot(), "dds", dds::DdsSide::kRobot, o);
    REQUIRE_MESSAGE(r.ok(), r.error().message);
    link = std::move(*r);
    sensor = link->MessageIndex("sensor_state").value();
    command = link->MessageIndex("command").value();
    sample.emplace(link->message(sensor).type);
    out.emplace(link->message(command).type);
  }
  double In(const char* leaf) const { return sample->Get(leaf).value(); }
  // Waits for a sample newer than the last one read; false on timeout.
  bool Next(std::int64_t timeout_ns) {
    dds::DdsReader& r = *link->reader(sensor);
    if (!r.WaitNewer(version, timeout_ns)) return false;
    version = r.Read(sample->bytes(), nullptr);
    return true;
  }
  void Send(double tick, double answers, double v, double w) {
    REQUIRE(out->Set("tick", tick).ok());
    REQUIRE(out->Set("answers", answers).ok());
    REQUIRE(out->Set("surge_speed_mps", v).ok());
    REQUIRE(out->Set("yaw_rate_radps", w).ok());
    REQUIRE(link->writer(command)->Push(out->bytes()));
  }
  std::int32_t matched_writers() const { return link->reader(sensor)->matched_writers(); }
  std::int32_t matched_readers() const { return link->writer(command)->matched_readers(); }
  std::int64_t last_receive_age_ns() const { return MonotonicNs() - link->reader(sensor)->last_receive_ns(); }
};

// Lock-step scripted controller: answers every new sample with 1 m/s and a yaw rate turning
// towards the target (a pure function of the sample, so runs repeat exactly) until the
// vehicle's episode ends or `max_ticks` samples were answered. The last sample stays in c.sample.
void Drive(Controller& c, std::uint64_t max_ticks, bool send_stray_first) {
  REQUIRE(c.link->WaitForPeer(20 * kSecond));
  if (send_stray_first) c.Send(0, 999'999, 1.5, -0.5);  // answers no sample: the simulator must ignore it
  for (std::uint64_t k = 0;; ++k) {
    REQUIRE_MESSAGE(c.Next(10 * kSecond), "no sample after tick ", k);
    REQUIRE(c.In("tick") == static_cast<double>(k));  // lock-step: one sample per answered tick, none skipped
    if (c.In("episode_end") != 0 || k >= max_ticks) return;
    c.Send(static_cast<double>(k + 1), c.In("tick"), 1.0, std::clamp(c.In("target_bearing_rad"), -0.5, 0.5));
  }
}

}  // namespace

TEST_CASE("auv hil: lock-step runs with the same seed give identical trajectories, stray commands ignored") {
  const std::string dir = test::ScratchDir("auv_hil_lockstep");
  std::string csv[2];
  for (int run = 0; run < 2; ++run) {
    const int domain = test::TestDomain(20 + run);
    csv[run] = dir + "/traj" + std::to_string(run) + ".csv";
    const std::string events = dir + "/events" + std::to_string(run) + ".json";
    Hil hil({"--layout", "easy", "--seed", "7", "--lockstep", "--domain", std::to_string(domain), "--max-time", "30",
             "--trajectory", csv[run], "--events", events},
            dir + "/hil" + std::to_string(run) + ".log");
    Controller c(domain);
    Drive(c, 100000, /*send_stray_first=*/run == 1);
    CHECK(c.In("episode_end") == 1);
    REQUIRE_MESSAGE(hil.Wait() == 0, ReadFile(hil.log));
    const std::string log = ReadFile(hil.log);
    INFO(log);
    CHECK(log.find(run == 1 ? "ignored 1" : "ignored 0") != std::string::npos);
    const std::string ev = ReadFile(events);
    CHECK(ev.find("\"seed\": 7") != std::string::npos);
    CHECK(ev.find("\"index\": 0") != std::string::npos);  // steering to the target reaches the first one
    CHECK(ev.find("\"mode\": \"lockstep\"") != std::string::npos);
  }
  const std::string a = ReadFile(csv[0]), b = ReadFile(csv[1]);
  REQUIRE(!a.empty());
  CHECK(a == b);
  // 30 s at 10 Hz: the header, tick 0 and up to 300 periods (fewer if the episode ended).
  const auto lines = std::count(a.begin(), a.end(), '\n');
  CHECK(lines >= 100);
  CHECK(lines <= 302);
  // The last row applied the controller's speed (column v_cmd_mps).
  std::stringstream last_row(a.substr(a.rfind('\n', a.size() - 2) + 1));
  std::string field;
  for (int col = 0; col < 5; ++col) std::getline(last_row, field, ',');
  CHECK(field == "1");
}

TEST_CASE("auv hil: a killed simulator is seen by the controller as a lost peer and an ageing sample") {
  const std::string dir = test::ScratchDir("auv_hil_kill");
  const int domain = test::TestDomain(30);
  Hil hil({"--layout", "easy", "--seed", "1", "--domain", std::to_string(domain)}, dir + "/hil.log");
  Controller c(domain);
  Drive(c, 20, false);
  CHECK(c.matched_writers() == 1);
  kill(hil.pid, SIGKILL);
  CHECK(hil.Wait() == 128 + SIGKILL);
  // No goodbye from a killed process: the participant's lease (2 s in the profile) runs out.
  const std::int64_t end = MonotonicNs() + 8 * kSecond;
  while (c.matched_writers() > 0 && MonotonicNs() < end) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  CHECK(c.matched_writers() == 0);
  CHECK(c.matched_readers() == 0);
  CHECK(c.last_receive_age_ns() > kSecond);
}

TEST_CASE("auv hil: SIGTERM ends a run cleanly with its outputs written") {
  const std::string dir = test::ScratchDir("auv_hil_term");
  const int domain = test::TestDomain(40);
  const std::string csv = dir + "/traj.csv", events = dir + "/events.json";
  Hil hil(
      {"--layout", "hard", "--seed", "3", "--domain", std::to_string(domain), "--trajectory", csv, "--events", events},
      dir + "/hil.log");
  Controller c(domain);
  Drive(c, 15, false);
  kill(hil.pid, SIGTERM);
  REQUIRE_MESSAGE(hil.Wait() == 0, ReadFile(hil.log));
  CHECK(ReadFile(hil.log).find("stopped") != std::string::npos);
  const std::string traj = ReadFile(csv);
  CHECK(std::count(traj.begin(), traj.end(), '\n') >= 16);  // header + ticks 0..14 at least
  CHECK(ReadFile(events).find("\"outcome\": \"stopped\"") != std::string::npos);
}

TEST_CASE("auv hil: bad flags are refused naming the flag and the value") {
  const std::string dir = test::ScratchDir("auv_hil_flags");
  struct Case {
    std::vector<std::string> args;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {{"--layout", "twisty", "--seed", "1"}, "--layout: twisty"},
      {{"--layout", "easy", "--seed", "-4"}, "--seed: '-4'"},
      {{"--layout", "easy", "--seed", "1", "--domain", "300"}, "--domain: Value 300"},
      {{"--layout", "easy", "--seed", "1", "--max-time", "abc"}, "--max-time: 'abc'"},
      {{"--layout", "easy", "--seed", "1", "--fault", "nan@x"}, "--fault: 'nan@x'"},
      {{"--layout", "easy", "--seed", "1", "--fault", "nan@3+"}, "--fault: 'nan@3+' is not KIND@SECONDS[+DURATION]"},
      {{"--layout", "easy", "--seed", "1", "--fault", "range@3+-1"}, "--fault: 'range@3+-1'"},
      {{"--layout", "easy", "--seed", "1", "--dds-naming", "ros3"}, "--dds-naming: 'ros3'"},
      {{"--layout", "easy"}, "--seed is required"},
      {{"--layout", "easy", "--seed", "1", "--frobnicate", "2"}, "--frobnicate"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    Hil hil(cases[i].args, dir + "/case" + std::to_string(i) + ".log");
    CHECK(hil.Wait() == 2);
    CHECK_MESSAGE(ReadFile(hil.log).find(cases[i].expect) != std::string::npos, ReadFile(hil.log));
  }
}

TEST_CASE("auv hil: real-time mode runs at the control period, applies commands and plots the run") {
  const std::string dir = test::ScratchDir("auv_hil_realtime");
  const int domain = test::TestDomain(50);
  const std::string png = dir + "/run.png", csv = dir + "/traj.csv";
  Hil hil({"--layout", "hard", "--seed", "2", "--realtime", "--domain", std::to_string(domain), "--max-time", "1.5",
           "--trajectory", csv, "--plot", png},
          dir + "/hil.log");
  Controller c(domain);
  REQUIRE(c.link->WaitForPeer(20 * kSecond));
  std::uint64_t samples = 0;
  const std::int64_t t0 = MonotonicNs();
  std::int64_t t_end = t0;
  while (c.Next(5 * kSecond)) {
    ++samples;
    c.Send(0, c.In("tick"), 0.5, 0.0);
    if (c.In("episode_end") != 0) {
      t_end = MonotonicNs();
      break;
    }
  }
  REQUIRE(c.In("episode_end") == 1);
  CHECK(c.In("tick") == 15);
  // Paced by the wall clock: 15 periods of 0.1 s after the first sample.
  const double wall_s = static_cast<double>(t_end - t0) * 1e-9;
  CHECK(wall_s > 1.3);
  CHECK(wall_s < 3.0);
  CHECK(samples >= 10);
  REQUIRE_MESSAGE(hil.Wait() == 0, ReadFile(hil.log));
  const std::string log = ReadFile(hil.log);
  INFO(log);
  CHECK(log.find("max_time") != std::string::npos);
  // Commands arrived and moved the vehicle: the last rows carry v_cmd 0.5.
  const std::string traj = ReadFile(csv);
  CHECK(traj.find(",0.5,0,") != std::string::npos);
  const std::string img = ReadFile(png);
  REQUIRE(img.size() > 1000);
  CHECK(img.substr(1, 3) == "PNG");
}
