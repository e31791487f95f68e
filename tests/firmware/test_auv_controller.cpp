// The AUV controller core and its loop: loading (errors naming file and field, a blob for another
// layout refused naming the difference, a corrupted blob refused), observe -> infer -> supervise
// with no allocation over 100,000 ticks, and the loop over an in-process link (a kinematic
// unicycle stands in for the vehicle) through the fresh, stale-sample, lost-peer and shutdown paths.
#include <doctest/doctest.h>

#include <array>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <thread>
#include <vector>

#include "firmware/auv/auv_controller.hpp"
#include "firmware/auv/controller_loop.hpp"
#include "runtime/core/alloc_probe.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/robot/auv_signals.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;
using firmware::AuvController;

namespace {

const std::string kRobotYaml = test::SourcePath("models/auv/robot.yaml");

robot::IoLayout Layout() {
  return *test::AuvRobot().io;
}

// A blob with random weights whose names, hash and action map are the given layout's.
std::string WriteBlob(const std::string& dir, const robot::IoLayout& layout, const char* name, std::uint64_t seed = 1) {
  policy::PolicySpec spec = policy::MakeRandomSpec({layout.observation_size(), 64, 64, layout.action_size()},
                                                   policy::Activation::kTanh, seed);
  robot::ApplyLayoutToSpec(layout, spec);
  const std::string path = dir + "/" + name;
  auto st = policy::WriteBlobFile(path, spec);
  REQUIRE_MESSAGE(st.ok(), st.error().message);
  return path;
}

std::unique_ptr<AuvController> MakeController(const std::string& dir) {
  auto c = AuvController::Create(test::AuvRobot(), WriteBlob(dir, Layout(), "auv.blob"));
  REQUIRE_MESSAGE(c.ok(), c.error().message);
  return std::move(*c);
}

robot::AuvSensorSample Sample(std::uint64_t tick) {
  robot::AuvSensorSample s;
  s.tick = tick;
  s.stamp_ns = static_cast<std::int64_t>(tick) * 100000000;
  s.sonar_beams = 16;
  for (std::uint32_t i = 0; i < 16; ++i) s.sonar_m[i] = 5.0f + static_cast<float>((tick + i) % 7);
  s.depth_m = 5.0;
  s.x_m = 0.01 * static_cast<double>(tick);
  s.yaw_rad = 0.3;
  s.target_distance_m = 20.0;
  s.target_bearing_rad = 0.2;
  s.route_bearing_rad = -0.4;
  s.clearance_m = 5.0;
  return s;
}

}  // namespace

TEST_CASE("auv controller: configuration from robot.yaml - bad fields named with their value") {
  auto c = firmware::AuvControllerConfigOf(test::AuvRobot());
  REQUIRE_MESSAGE(c.ok(), c.error().message);
  CHECK(c->control_period_s == 0.1);
  CHECK(c->depth_setpoint_m == 5.0);
  CHECK(c->supervisor.v_max_mps == 1.5);
  CHECK(c->supervisor.dv_max_mps == doctest::Approx(0.1));
  CHECK(c->supervisor.stop_dv_mps == doctest::Approx(0.3));
  CHECK(c->supervisor.sonar_beams == 16);

  // A copy of the robot's folder with one change in robot.yaml.
  const std::string dir = test::ScratchDir("auv_controller_yaml") + "/auv";
  std::filesystem::copy(test::SourcePath("models/auv"), dir, std::filesystem::copy_options::recursive);
  std::ifstream in(kRobotYaml);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string p = dir + "/robot.yaml";
  auto with = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    const auto at = t.find(from);
    REQUIRE(at != std::string::npos);
    t.replace(at, from.size(), to);
    std::ofstream(p) << t;
    auto m = robot::LoadRobotModel(p);
    auto r = m ? firmware::AuvControllerConfigOf(*m) : Result<firmware::AuvControllerConfig>(m.error());
    REQUIRE_FALSE(r.ok());
    return r.error().message;
  };
  CHECK(with("rate_per_s: 2.5", "rate_per_s: fast") == p + ": commands[1].rate_per_s: 'fast' is not a number");
  CHECK(with("invalid_safe_stop: 3", "invalid_safe_stop: 2.5") ==
        p + ": streams[0].invalid_safe_stop: '2.5' is not an integer");
  CHECK(with("range: [0.0, 1.5]", "range: [1.5, 0.0]") == p + ": commands[0].range: low 1.5 is above high 0");
  CHECK(with("stop: {ramp_per_s: 3.0}", "stop: {ramp_per_s: 0.5}")
            .find("supervisor: stop_dv_mps = 0.05: must be >= "
                  "dv_max_mps") != std::string::npos);
  CHECK(with("invalid_safe_stop: 3", "invalid_safe_stop_typo: 3") ==
        p + ": streams[0].invalid_safe_stop_typo: unknown field");
}

TEST_CASE(
    "auv controller: ticking at 1 kHz the limits keep their time - a sample a tick late is on time, a missed "
    "one is stale") {
  auto at = [](double tick_s) {
    auto m = robot::WithTickPeriod(test::AuvRobot(), tick_s);
    REQUIRE_MESSAGE(m.ok(), m.error().message);
    auto config = firmware::AuvControllerConfigOf(*m);
    REQUIRE_MESSAGE(config.ok(), config.error().message);
    return *config;
  };
  const auto c = std::optional(at(0.1));
  // At the control period nothing changes.
  const auto same = at(c->control_period_s);
  CHECK(same.supervisor.stale_degraded_ticks == c->supervisor.stale_degraded_ticks);
  CHECK(same.supervisor.stale_safe_stop_ticks == c->supervisor.stale_safe_stop_ticks);
  CHECK(same.supervisor.lost_peer_ticks == c->supervisor.lost_peer_ticks);
  CHECK(same.supervisor.dv_max_mps == c->supervisor.dv_max_mps);
  // 100 ticks per period: stale after 1.5 and 2.5 periods, lost after 20, rates per tick / 100.
  const auto fast = at(0.001);
  CHECK(fast.supervisor.stale_degraded_ticks == 150);
  CHECK(fast.supervisor.stale_safe_stop_ticks == 250);
  CHECK(fast.supervisor.lost_peer_ticks == 2000);
  CHECK(fast.supervisor.dv_max_mps == doctest::Approx(c->supervisor.dv_max_mps / 100));
  char why[256];
  CHECK(safety::ValidateAuvSupervisorConfig(fast.supervisor, why, sizeof why));
  // The 10 Hz sample due at tick 100 arrives at tick 101 (age 101): on time. One missed (age 151):
  // degraded. Two missed (age 251): safe-stop.
  const robot::AuvSensorSample sample = Sample(1);
  safety::AuvSupervisorInput in;
  in.sample = &sample;
  in.v_mps = 0.05;
  const auto mode_at = [&](std::uint32_t age) {
    in.sample_age_ticks = age;
    return safety::SuperviseAuv(fast.supervisor, in, safety::AuvSupervisorState{}).state.mode;
  };
  CHECK(mode_at(101) == safety::AuvMode::kNominal);
  CHECK(mode_at(150) == safety::AuvMode::kNominal);
  CHECK(mode_at(151) == safety::AuvMode::kDegraded);
  CHECK(mode_at(251) == safety::AuvMode::kSafeStop);
}

TEST_CASE("auv controller: a blob for another layout or a corrupted blob is refused, naming why") {
  const std::string dir = test::ScratchDir("auv_controller_blobs");
  robot::IoLayout other = Layout();
  other.observations[17].scale = 0.5;  // same names, other scale: only the hash differs
  auto c = AuvController::Create(test::AuvRobot(), WriteBlob(dir, other, "scale.blob"));
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message.find("scale.blob on " + test::AuvRobot().path +
                               ": policy does not fit robot layout 'auv': same names, "
                               "but scales, offsets, clips, units or limits differ (layout hash") != std::string::npos);
  other = Layout();
  other.observations[16].history = 2;
  c = AuvController::Create(test::AuvRobot(), WriteBlob(dir, other, "history.blob"));
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message.find("the policy takes 25 observations, the layout gives 24") != std::string::npos);
  other = Layout();
  std::swap(other.observations[0], other.observations[1]);
  c = AuvController::Create(test::AuvRobot(), WriteBlob(dir, other, "order.blob"));
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message.find("observation 0 is 'sonar_1' in the policy, 'sonar_0' in the layout") !=
        std::string::npos);

  const std::string good = WriteBlob(dir, Layout(), "good.blob");
  std::vector<char> bytes;
  {
    std::ifstream f(good, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  }
  bytes[bytes.size() / 2] ^= 0x5a;
  std::ofstream(dir + "/corrupt.blob", std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  c = AuvController::Create(test::AuvRobot(), dir + "/corrupt.blob");
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message.find("corrupt.blob") != std::string::npos);
  c = AuvController::Create(test::AuvRobot(), dir + "/missing.blob");
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message.find("missing.blob") != std::string::npos);
}

TEST_CASE("auv controller: the tick observes the sample through the layout, infers, and stays within limits") {
  auto c = MakeController(test::ScratchDir("auv_controller_tick"));
  robot::AuvCommand cmd;
  const robot::AuvSensorSample s = Sample(1);
  c->Tick(&s, 0, cmd);  // disarmed: zero
  CHECK(cmd.surge_speed_mps == 0.0);
  CHECK(c->policy_runs() == 0);
  c->Arm();
  c->Tick(&s, 1, cmd);
  CHECK(c->policy_runs() == 1);
  // The observation is the layout's: sonar_0 / 15, target distance / 40, the nearest echo / 5
  // (5 m here: clipped at 1), the route bearing / pi and its cos/sin.
  CHECK(c->observation()[0] == doctest::Approx(s.sonar_m[0] / 15.0));
  CHECK(c->observation()[16] == doctest::Approx(0.5));
  CHECK(c->observation()[20] == 1.0f);
  CHECK(c->observation()[21] == doctest::Approx(-0.4 / 3.14159265358979));
  CHECK(c->observation()[22] == doctest::Approx(std::cos(-0.4)));
  CHECK(c->observation()[23] == doctest::Approx(std::sin(-0.4)));
  CHECK(cmd.answers == 1);
  CHECK(cmd.tick == 1);
  CHECK(cmd.mode == 0);
  CHECK(std::abs(cmd.surge_speed_mps) <= 0.1 + 1e-12);  // the first step from rest is rate limited
  double v_prev = cmd.surge_speed_mps;
  for (std::uint64_t k = 2; k < 50; ++k) {
    const robot::AuvSensorSample sk = Sample(k);
    c->Tick(&sk, k, cmd);
    CHECK(cmd.surge_speed_mps >= 0.0);
    CHECK(cmd.surge_speed_mps <= 1.5);
    CHECK(std::abs(cmd.yaw_rate_radps) <= 0.5);
    CHECK(std::abs(cmd.surge_speed_mps - v_prev) <= 0.1 + 1e-12);
    v_prev = cmd.surge_speed_mps;
  }
  CHECK(c->supervisor().mode == safety::AuvMode::kNominal);
  // A shutdown command is zero speed, e-stop mode.
  c->ShutdownCommand(99, cmd);
  CHECK(cmd.surge_speed_mps == 0.0);
  CHECK(cmd.yaw_rate_radps == 0.0);
  CHECK(cmd.mode == 3);
  // Reset only while disarmed.
  c->RequestEStop();
  c->Tick(&s, 50, cmd);
  CHECK(c->supervisor().mode == safety::AuvMode::kEStop);
  CHECK_FALSE(c->ResetSupervisor());
  c->Disarm();
  CHECK(c->ResetSupervisor());
  CHECK(c->supervisor().mode == safety::AuvMode::kNominal);
}

TEST_CASE("auv controller: 100,000 ticks allocate nothing - the profiler saw every stage") {
  auto c = MakeController(test::ScratchDir("auv_controller_alloc"));
  c->Arm();
  robot::AuvCommand cmd;
  std::vector<robot::AuvSensorSample> samples;
  for (std::uint64_t k = 0; k < 64; ++k) samples.push_back(Sample(k));
  std::uint64_t nominal = 0;
  {
    AllocationScope scope;
    for (std::uint64_t k = 0; k < 100000; ++k) {
      robot::AuvSensorSample& s = samples[k % 64];
      s.tick = k;
      c->Tick(&s, k, cmd);
      nominal += cmd.mode == 0;
    }
    CHECK(scope.count() == 0);
  }
  CHECK(nominal == 100000);
  CHECK(c->policy_runs() == 100000);
  CHECK(c->profiler().histogram(rt::Stage::kInfer).Snapshot().count() == 100000);
}

namespace {

// In-process link: a vehicle thread (kinematic unicycle) and the controller exchange the newest
// sample and the newest command through seqlocks (no lock, no allocation on either side).
template <typename T>
class SeqBox {
 public:
  void Put(const T& v) noexcept {
    const std::uint32_t s = seq_.load(std::memory_order_relaxed);
    seq_.store(s + 1, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_release);
    for (std::size_t i = 0; i < kWords; ++i) {
      std::uint64_t w;
      std::memcpy(&w, reinterpret_cast<const char*>(&v) + i * 8, 8);
      words_[i].store(w, std::memory_order_relaxed);
    }
    seq_.store(s + 2, std::memory_order_release);
  }
  bool Get(T& out) const noexcept {
    for (;;) {
      const std::uint32_t s0 = seq_.load(std::memory_order_acquire);
      if (s0 == 0) return false;
      if (s0 & 1) continue;
      for (std::size_t i = 0; i < kWords; ++i) {
        const std::uint64_t w = words_[i].load(std::memory_order_relaxed);
        std::memcpy(reinterpret_cast<char*>(&out) + i * 8, &w, 8);
      }
      std::atomic_thread_fence(std::memory_order_acquire);
      if (seq_.load(std::memory_order_relaxed) == s0) return true;
    }
  }

 private:
  static_assert(sizeof(T) % 8 == 0);
  static constexpr std::size_t kWords = sizeof(T) / 8;
  std::atomic<std::uint32_t> seq_{0};
  std::atomic<std::uint64_t> words_[kWords] = {};
};

class TestLink final : public firmware::AuvLink {
 public:
  bool Latest(robot::AuvSensorSample& out) noexcept override { return samples.Get(out); }
  bool Send(const robot::AuvCommand& c) noexcept override {
    const std::uint64_t n = sent.load(std::memory_order_relaxed);
    if (n < log.size()) log[n] = c;  // every command kept (lock-step tests), in a preallocated log
    commands.Put(c);
    sent.store(n + 1, std::memory_order_release);
    return true;
  }
  firmware::PeerState Peer() noexcept override { return peer.load(std::memory_order_relaxed); }

  SeqBox<robot::AuvSensorSample> samples;
  SeqBox<robot::AuvCommand> commands;
  std::array<robot::AuvCommand, 256> log{};
  std::atomic<std::uint64_t> sent{0};
  std::atomic<firmware::PeerState> peer{firmware::PeerState::kAlive};
};

// The vehicle in lock-step: publish the state, let the controller tick, wait for its command,
// integrate a unicycle over one period. `publish_until`: later ticks publish nothing new.
struct Vehicle {
  TestLink& link;
  rt::LockStepClock& clock;
  std::uint64_t ticks, publish_until;
  std::vector<robot::AuvCommand> seen;
  double x = 0, y = 0, yaw = 0;
  std::uint64_t lose_peer_at = ~std::uint64_t{0};  // from this tick on the link reports the peer lost

  void Run() {
    robot::AuvSensorSample s = Sample(0);
    for (std::uint64_t k = 0; k < ticks; ++k) {
      if (k < publish_until) {
        s.tick = k;
        s.stamp_ns = static_cast<std::int64_t>(k) * 100000000;
        s.x_m = x;
        s.y_m = y;
        s.yaw_rad = robot::WrapAngleRad(yaw);
        link.samples.Put(s);
      }
      if (k == lose_peer_at) link.peer.store(firmware::PeerState::kLost);
      const std::uint64_t before = link.sent.load(std::memory_order_acquire);
      clock.Advance();
      while (link.sent.load(std::memory_order_acquire) == before) std::this_thread::yield();
      const robot::AuvCommand c = link.log[before];
      seen.push_back(c);
      yaw += c.yaw_rate_radps * 0.1;
      x += c.surge_speed_mps * std::cos(yaw) * 0.1;
      y += c.surge_speed_mps * std::sin(yaw) * 0.1;
    }
  }
};

// The loop on its own thread against the vehicle on this one, for `ticks` lock-step ticks.
firmware::LoopResult RunLockStep(AuvController& c, TestLink& link, rt::LockStepClock& clock, Vehicle& vehicle) {
  firmware::ClearLoopStop();
  firmware::LoopResult r;
  std::thread loop([&] { r = firmware::RunAuvControlLoop(c, link, clock, {.max_ticks = vehicle.ticks}); });
  vehicle.Run();
  loop.join();
  return r;
}

}  // namespace

TEST_CASE("auv control loop: lock-step with fresh samples, then stale samples, then a lost peer") {
  auto c = MakeController(test::ScratchDir("auv_loop_stale"));
  TestLink link;
  rt::LockStepClock clock;
  Vehicle vehicle{link, clock, 80, 40, {}};
  const firmware::LoopResult r = RunLockStep(*c, link, clock, vehicle);
  CHECK(r.ticks == 80);
  REQUIRE(vehicle.seen.size() == 80);
  for (std::uint64_t k = 0; k < 40; ++k) {
    CHECK(vehicle.seen[k].mode == 0);
    CHECK(vehicle.seen[k].answers == k);  // each command answers the sample of its tick
  }
  CHECK(std::hypot(vehicle.x, vehicle.y) > 0.0);
  // Last new sample at tick 39: age 2 at tick 41 degrades, age 4 at tick 43 stops, age 21 at
  // tick 60 is a lost peer (e-stop).
  CHECK(vehicle.seen[40].mode == 0);
  CHECK(vehicle.seen[41].mode == 1);
  CHECK(vehicle.seen[43].mode == 2);
  CHECK(vehicle.seen[59].mode == 2);
  CHECK(vehicle.seen[60].mode == 3);
  CHECK(vehicle.seen[50].surge_speed_mps == 0.0);  // ramped to zero within 5 stop steps
  CHECK(vehicle.seen[50].yaw_rate_radps == 0.0);
  CHECK(r.final_mode == safety::AuvMode::kEStop);
  robot::AuvCommand last;
  REQUIRE(link.commands.Get(last));  // the shutdown command after the loop
  CHECK(last.surge_speed_mps == 0.0);
  CHECK(last.mode == 3);
  CHECK(c->supervisor().cause_ticks[4] > 0);  // stale counted
}

TEST_CASE("auv control loop: the transport reporting the peer lost e-stops at once") {
  auto c = MakeController(test::ScratchDir("auv_loop_peer"));
  TestLink link;
  rt::LockStepClock clock;
  Vehicle vehicle{link, clock, 30, 30, {}};
  vehicle.lose_peer_at = 15;
  (void)RunLockStep(*c, link, clock, vehicle);
  CHECK(vehicle.seen[14].mode == 0);
  CHECK(vehicle.seen[15].mode == 3);  // at once
  CHECK(vehicle.seen[29].tick == 29);
  CHECK(vehicle.seen[29].mode == 3);
  CHECK(vehicle.seen[29].surge_speed_mps == 0.0);
  CHECK_MESSAGE(c->supervisor().latched_cause == safety::kAuvCauseLostPeer,
                "mode " << int(c->supervisor().mode) << " transitions " << c->supervisor().transitions << " lost "
                        << c->supervisor().cause_ticks[5] << " ticks " << c->supervisor().ticks);
}

TEST_CASE("auv control loop: free-running clock - SIGTERM sends the safe command and ends the loop") {
  auto c = MakeController(test::ScratchDir("auv_loop_signal"));
  TestLink link;
  firmware::ClearLoopStop();
  firmware::InstallLoopSignalHandlers();
  std::atomic<bool> done{false};
  std::thread vehicle([&] {  // publishes every 2 ms on its own, not in lock-step
    std::uint64_t k = 0;
    while (!done.load()) {
      robot::AuvSensorSample s = Sample(++k);
      link.samples.Put(s);
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  });
  rt::FreeRunningClock clock(2000000);
  firmware::LoopResult r;
  std::uint64_t allocations = 0;
  std::thread loop([&] {
    AllocationScope scope;
    r = firmware::RunAuvControlLoop(*c, link, clock, {});
    allocations = scope.count();
  });
  while (link.sent.load() < 100) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  std::raise(SIGTERM);
  loop.join();
  done.store(true);
  vehicle.join();
  CHECK(r.stopped);
  CHECK(r.ticks >= 100);
  CHECK(allocations == 0);
  robot::AuvCommand last;
  REQUIRE(link.commands.Get(last));
  CHECK(last.surge_speed_mps == 0.0);
  CHECK(last.yaw_rate_radps == 0.0);
  CHECK(last.mode == 3);
  const rt::ProfileReport rep = rt::TakeReport(c->profiler());
  CHECK(rep.stats[static_cast<std::size_t>(rt::Stage::kTick)].count == r.ticks);
  CHECK(rep.stats[static_cast<std::size_t>(rt::Stage::kJitter)].count == r.ticks);
  MESSAGE(rt::FormatText(rep));
  firmware::ClearLoopStop();
  std::signal(SIGTERM, SIG_DFL);
}
