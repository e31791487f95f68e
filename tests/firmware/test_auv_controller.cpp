// The AUV through runtime/loop, without DDS: the robot model's limits and refusals (errors naming
// file and field, a blob for another layout refused naming the difference, a corrupted blob),
// the one sample check on the AUV's sample (the robot model's fields), observe -> infer ->
// supervise with no allocation over 100,000 ticks, and the loop on a thread over an in-process
// link (a kinematic unicycle stands in for the vehicle) through the fresh, stale-sample,
// lost-peer and shutdown paths.
#include <doctest/doctest.h>

#include <array>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <span>
#include <thread>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/loop/policy_source.hpp"
#include "runtime/loop/runner.hpp"
#include "runtime/policy/blob.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/scripted_transport.hpp"
#include "tests/support/test_paths.hpp"
#include "tests/support/text_edit.hpp"

using namespace pbppo;
using safety::Mode;

namespace {

const robot::RobotModel& Robot() {
  return test::AuvRobot();
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

struct Controller {
  policy::PolicyModel policy;
  std::unique_ptr<loop::PolicySource> source;
  Controller(policy::PolicyModel p) : policy(std::move(p)) {
    auto s = loop::PolicySource::Create(Robot(), policy);
    REQUIRE_MESSAGE(s.ok(), s.error().message);
    source = std::move(*s);
  }
};

std::unique_ptr<Controller> MakeController(const std::string& dir) {
  auto p = policy::PolicyModel::FromFile(WriteBlob(dir, *Robot().io, "auv.blob"));
  REQUIRE(p.ok());
  return std::make_unique<Controller>(std::move(*p));
}

Result<std::unique_ptr<loop::PolicySource>> SourceFor(const std::string& blob, policy::PolicyModel* keep) {
  auto p = policy::PolicyModel::FromFile(blob);
  if (!p) return std::move(p).error();
  *keep = std::move(*p);
  return loop::PolicySource::Create(Robot(), *keep);
}

// The AUV's sensor sample: the robot model's fields (it has no others), set by name.
constexpr std::size_t kMaxFields = 64;
std::uint32_t FieldIndex(const std::string& name) {
  const int k = Robot().FieldIndex(name);
  REQUIRE_MESSAGE(k >= 0, name);
  return static_cast<std::uint32_t>(k);
}
struct AuvSample {
  std::array<double, kMaxFields> f{};
  double& operator[](const std::string& name) { return f[FieldIndex(name)]; }
  double operator[](const std::string& name) const { return f[FieldIndex(name)]; }
  // Into a RobotData's fields.
  void Write(std::span<double> fields) const { std::copy_n(f.begin(), fields.size(), fields.begin()); }
};

AuvSample Sample(std::uint64_t tick) {
  REQUIRE(Robot().fields.size() <= kMaxFields);
  AuvSample s;
  s["tick"] = static_cast<double>(tick);
  s["sonar_beams"] = 16;
  for (std::uint32_t i = 0; i < 16; ++i)
    s[robot::ExpandIndex("sonar_{i}_m", i)] = 5.0 + static_cast<double>((tick + i) % 7);
  s["depth_m"] = 5.0;
  s["x_m"] = 0.01 * static_cast<double>(tick);
  s["yaw_rad"] = 0.3;
  s["target_distance_m"] = 20.0;
  s["target_bearing_rad"] = 0.2;
  s["route_bearing_rad"] = -0.4;
  s["clearance_m"] = 5.0;
  return s;
}

// The loop in this thread over a scripted transport fed with AUV samples.
struct Rig {
  const robot::RobotModel& m = Robot();
  std::unique_ptr<Controller> c;
  robot::RobotData data = robot::MakeRobotData(Robot());
  std::unique_ptr<loop::LoopData> loop;
  test::ScriptedTransport t{Robot()};
  robot::Transport* ts[1] = {&t};
  std::vector<double> values = std::vector<double>(Robot().fields.size());

  explicit Rig(const std::string& dir) : c(MakeController(dir)), loop(loop::MakeLoopData(Robot(), c->source.get())) {}
  void Tick(const AuvSample* s, std::uint64_t tick) {
    if (s != nullptr) {
      s->Write(values);
      t.Put(m, 0, values);
    }
    rt::TickTiming timing;
    timing.tick = tick;
    loop::Tick(m, data, *loop, ts, timing);
  }
  double v() const { return t.command[0]; }
  double w() const { return t.command[1]; }
};

}  // namespace

TEST_CASE("auv controller: limits from robot.yaml - bad fields named with their value") {
  const robot::RobotModel& m = Robot();
  const safety::SupervisorModel& s = m.supervisor_model;
  CHECK(m.tick_period_s == 0.1);
  CHECK(*m.Parameter("depth_m") == 5.0);
  CHECK(s.commands[0].max == 1.5);
  CHECK(s.commands[0].rate == doctest::Approx(0.1));
  CHECK(s.commands[0].stop_rate == doctest::Approx(0.3));
  CHECK(m.FieldIndex("sonar_15_m") >= 0);

  // A copy of the robot's folder with one change in robot.yaml.
  const test::RobotFileEdits edits("auv", "auv_controller_yaml");
  const std::string& p = edits.path();
  auto with = [&](const std::string& from, const std::string& to) { return edits.Error(from, to); };
  CHECK(with("rate_per_s: 2.5", "rate_per_s: fast") == p + ": commands[1].rate_per_s: 'fast' is not a number");
  CHECK(with("invalid_safe_stop: 3", "invalid_safe_stop: 2.5") ==
        p + ": streams[0].invalid_safe_stop: '2.5' is not an integer");
  CHECK(with("range: [0.0, 1.5]", "range: [1.5, 0.0]") == p + ": commands[0].range: low 1.5 is above high 0");
  CHECK(with("stop: {ramp_per_s: 3.0}", "stop: {ramp_per_s: 0.5}") ==
        p + ": supervisor: command 'surge_speed': stop_rate = 0.05: must be > 0 and >= the rate 0.1");
  CHECK(with("invalid_safe_stop: 3", "invalid_safe_stop_typo: 3") ==
        p + ": streams[0].invalid_safe_stop_typo: unknown field");
}

TEST_CASE(
    "auv controller: ticking at 1 kHz the limits keep their time - a sample a tick late is on time, a missed "
    "one is stale") {
  auto at = [](double tick_s) {
    auto m = robot::WithTickPeriod(Robot(), tick_s);
    REQUIRE_MESSAGE(m.ok(), m.error().message);
    return *m;
  };
  const robot::RobotModel same = at(0.1), fast = at(0.001);
  // At the control period nothing changes.
  CHECK(same.streams[0].stale_degraded_ticks == Robot().streams[0].stale_degraded_ticks);
  CHECK(same.streams[0].stale_safe_stop_ticks == Robot().streams[0].stale_safe_stop_ticks);
  CHECK(same.streams[0].lost_ticks == Robot().streams[0].lost_ticks);
  CHECK(same.supervisor_model.commands[0].rate == Robot().supervisor_model.commands[0].rate);
  // 100 ticks per period: stale after 1.5 and 2.5 periods, lost after 20, rates per tick / 100.
  CHECK(fast.streams[0].stale_degraded_ticks == 150);
  CHECK(fast.streams[0].stale_safe_stop_ticks == 250);
  CHECK(fast.streams[0].lost_ticks == 2000);
  CHECK(fast.supervisor_model.commands[0].rate == doctest::Approx(Robot().supervisor_model.commands[0].rate / 100));
  CHECK(fast.policy_period_ticks == 100);
  // The 10 Hz sample due at tick 100 arrives at tick 101 (age 101): on time. One missed (age 151):
  // degraded. Two missed (age 251): safe-stop.
  const auto mode_at = [&](std::uint32_t age) {
    const double command[2] = {0.05, 0.0};
    const safety::StreamState stream{true, age, -1, 0};
    const safety::TransportHealth link;
    safety::SupervisorInput in;
    in.command = command;
    in.streams = {&stream, 1};
    in.transports = {&link, 1};
    safety::SupervisorState s = safety::MakeSupervisorState(fast.supervisor_model);
    std::vector<double> out(2);
    return safety::Supervise(fast.supervisor_model, in, 0, s, out).mode;
  };
  CHECK(mode_at(101) == Mode::kNominal);
  CHECK(mode_at(150) == Mode::kNominal);
  CHECK(mode_at(151) == Mode::kDegraded);
  CHECK(mode_at(251) == Mode::kSafeStop);
}

TEST_CASE("auv controller: a blob for another layout or a corrupted blob is refused, naming why") {
  const std::string dir = test::ScratchDir("auv_controller_blobs");
  policy::PolicyModel keep =
      std::move(policy::PolicyModel::FromSpec(policy::MakeRandomSpec({1, 1}, policy::Activation::kTanh, 1))).value();
  robot::IoLayout other = *Robot().io;
  other.observations[17].scale = 0.5;  // same names, other scale: only the hash differs
  auto c = SourceFor(WriteBlob(dir, other, "scale.blob"), &keep);
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message.find("policy does not fit robot layout 'auv': same names, "
                               "but scales, offsets, clips, units or limits differ (layout hash") != std::string::npos);
  other = *Robot().io;
  other.observations[16].history = 2;
  c = SourceFor(WriteBlob(dir, other, "history.blob"), &keep);
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message.find("the policy takes 25 observations, the layout gives 24") != std::string::npos);
  other = *Robot().io;
  std::swap(other.observations[0], other.observations[1]);
  c = SourceFor(WriteBlob(dir, other, "order.blob"), &keep);
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message.find("observation 0 is 'sonar_1' in the policy, 'sonar_0' in the layout") !=
        std::string::npos);

  const std::string good = WriteBlob(dir, *Robot().io, "good.blob");
  std::vector<char> bytes;
  {
    std::ifstream f(good, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  }
  bytes[bytes.size() / 2] ^= 0x5a;
  std::ofstream(dir + "/corrupt.blob", std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  c = SourceFor(dir + "/corrupt.blob", &keep);
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message.find("corrupt.blob") != std::string::npos);
  c = SourceFor(dir + "/missing.blob", &keep);
  REQUIRE_FALSE(c.ok());
  CHECK(c.error().message.find("missing.blob") != std::string::npos);
}

TEST_CASE("auv controller: the one sample check names the field - the sample's beams and bearings included") {
  const robot::RobotModel& m = Robot();
  robot::RobotData d = robot::MakeRobotData(m);
  auto check = [&](const AuvSample& s) {
    s.Write(d.fields);
    d.fresh[0] = 1;
    loop::CheckSample(m, d);
    const std::int32_t k = d.streams[0].invalid_input;
    return k < 0 ? std::string("valid") : m.fields[static_cast<std::size_t>(k)].name;
  };
  AuvSample s = Sample(1);
  CHECK(check(s) == "valid");
  s["sonar_beams"] = 8;
  CHECK(check(s) == "sonar_beams");
  CHECK(d.streams[0].invalid_value == 8.0);
  s = Sample(1);
  s["route_bearing_rad"] = std::numeric_limits<double>::quiet_NaN();
  CHECK(check(s) == "route_bearing_rad");
  s = Sample(1);
  s["surge_mps"] = 9.0;  // beyond 5 m/s
  CHECK(check(s) == "surge_mps");
  s = Sample(1);
  s["sonar_5_m"] = std::numeric_limits<double>::infinity();
  CHECK(check(s) == "sonar_5_m");
  s = Sample(1);
  s["sonar_3_m"] = -1.0;
  CHECK(check(s) == "sonar_3_m");
  s = Sample(1);
  s["x_m"] = std::numeric_limits<double>::quiet_NaN();
  CHECK(check(s) == "x_m");
  // Angles are wrapped to [-pi, pi]: the route bearing like the target bearing and the yaw.
  for (const char* field : {"route_bearing_rad", "target_bearing_rad", "yaw_rad"}) {
    s = Sample(1);
    s[field] = 3.14159265;
    CHECK(check(s) == "valid");
    s[field] = -3.5;
    CHECK(check(s) == field);
    CHECK(d.streams[0].invalid_value == -3.5);
  }
}

TEST_CASE("auv controller: the tick observes the sample through the layout, infers, and stays within limits") {
  Rig r(test::ScratchDir("auv_controller_tick"));
  const AuvSample s = Sample(1);
  r.Tick(&s, 0);  // disarmed: zero
  CHECK(r.v() == 0.0);
  CHECK(r.c->source->runs() == 0);
  r.loop->Arm();
  const AuvSample s2 = Sample(2);
  r.Tick(&s2, 2);
  CHECK(r.c->source->runs() == 1);
  // The observation is the layout's: sonar_0 / 15, target distance / 40, the nearest echo / 5
  // (5 m here: clipped at 1), the route bearing / pi and its cos/sin.
  const auto obs = r.c->source->observation();
  CHECK(obs[0] == doctest::Approx(s2["sonar_0_m"] / 15.0));
  CHECK(obs[16] == doctest::Approx(0.5));
  CHECK(obs[20] == 1.0f);
  CHECK(obs[21] == doctest::Approx(-0.4 / 3.14159265358979));
  CHECK(obs[22] == doctest::Approx(std::cos(-0.4)));
  CHECK(obs[23] == doctest::Approx(std::sin(-0.4)));
  CHECK(r.t.tick == 2);
  CHECK(r.t.mode == Mode::kNominal);
  CHECK(std::abs(r.v()) <= 0.1 + 1e-12);  // the first step from rest is rate limited
  double v_prev = r.v();
  for (std::uint64_t k = 3; k < 50; ++k) {
    const AuvSample sk = Sample(k);
    r.Tick(&sk, k);
    CHECK(r.v() >= 0.0);
    CHECK(r.v() <= 1.5);
    CHECK(std::abs(r.w()) <= 0.5);
    CHECK(std::abs(r.v() - v_prev) <= 0.1 + 1e-12);
    v_prev = r.v();
  }
  CHECK(r.loop->supervisor().mode == Mode::kNominal);
  // The stop command: zero speed, zero yaw rate, e-stop mode.
  robot::Transport* ts[] = {&r.t};
  robot::RobotData copy = r.data;
  loop::Shutdown(r.m, copy, *r.loop, ts, 99);
  CHECK(r.v() == 0.0);
  CHECK(r.w() == 0.0);
  CHECK(r.t.mode == Mode::kEStop);
  // Reset only while disarmed.
  auto rig = Rig(test::ScratchDir("auv_controller_reset"));
  rig.loop->Arm();
  rig.loop->RequestEStop();
  rig.Tick(&s, 0);
  CHECK(rig.loop->supervisor().mode == Mode::kEStop);
  CHECK_FALSE(rig.loop->ResetSupervisor());
  rig.loop->Disarm();
  rig.Tick(&s, 1);
  CHECK(rig.loop->ResetSupervisor());
  CHECK(rig.loop->supervisor().mode == Mode::kNominal);
}

TEST_CASE("auv controller: 100,000 ticks allocate nothing - the profiler saw every stage") {
  Rig r(test::ScratchDir("auv_controller_alloc"));
  r.loop->Arm();
  std::vector<AuvSample> samples;
  for (std::uint64_t k = 0; k < 64; ++k) samples.push_back(Sample(k));
  const std::uint32_t tick = FieldIndex("tick");
  std::uint64_t nominal = 0;
  {
    AllocationScope scope;
    for (std::uint64_t k = 0; k < 100000; ++k) {
      AuvSample& s = samples[k % 64];
      s.f[tick] = static_cast<double>(k);
      r.Tick(&s, k);
      nominal += r.t.mode == Mode::kNominal;
    }
    CHECK(scope.count() == 0);
  }
  CHECK(nominal == 100000);
  CHECK(r.c->source->runs() == 100000);
  CHECK(r.loop->profiler().histogram(rt::Stage::kInfer).Snapshot().count() == 100000);
}

namespace {

// In-process link: a vehicle thread (kinematic unicycle) and the loop exchange the newest sample
// and every command through seqlocks and a preallocated log (no lock, no allocation either side).
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

struct Sent {
  std::uint64_t tick = 0, answers = 0;
  double v = 0, w = 0;
  std::uint64_t mode = 0;
};

class TestLink final : public robot::Transport {
 public:
  TestLink() : tick_(FieldIndex("tick")) {}
  void Read(const robot::RobotModel&, robot::RobotData& d) noexcept override {
    if (samples.Get(sample_) && (!have_ || sample_.f[tick_] != last_)) {
      have_ = true;
      last_ = sample_.f[tick_];
      std::copy_n(sample_.f.begin(), d.fields.size(), d.fields.begin());
      d.fresh[0] = 1;
    }
    d.transports[0].lost = peer_lost.load(std::memory_order_relaxed);
  }
  void Write(const robot::RobotModel&, robot::RobotData& d) noexcept override {
    const Sent s{d.tick, static_cast<std::uint64_t>(d.fields[tick_]), d.command[0], d.command[1],
                 static_cast<std::uint64_t>(d.mode)};
    const std::uint64_t n = sent.load(std::memory_order_relaxed);
    if (n < log.size()) log[n] = s;  // every command kept (lock-step tests), in a preallocated log
    commands.Put(s);
    sent.store(n + 1, std::memory_order_release);
  }

  SeqBox<AuvSample> samples;
  SeqBox<Sent> commands;
  std::array<Sent, 256> log{};
  std::atomic<std::uint64_t> sent{0};
  std::atomic<bool> peer_lost{false};

 private:
  std::uint32_t tick_;
  AuvSample sample_;
  bool have_ = false;
  double last_ = 0;
};

// The vehicle in lock-step: publish the state, let the loop tick, wait for its command, integrate
// a unicycle over one period. `publish_until`: later ticks publish nothing new.
struct Vehicle {
  TestLink& link;
  rt::LockStepClock& clock;
  std::uint64_t ticks, publish_until;
  std::vector<Sent> seen;
  double x = 0, y = 0, yaw = 0;
  std::uint64_t lose_peer_at = ~std::uint64_t{0};  // from this tick on the link reports the peer lost

  void Run() {
    AuvSample s = Sample(0);
    for (std::uint64_t k = 0; k < ticks; ++k) {
      if (k < publish_until) {
        s["tick"] = static_cast<double>(k);
        s["x_m"] = x;
        s["y_m"] = y;
        s["yaw_rad"] = robot::WrapAngleRad(yaw);
        link.samples.Put(s);
      }
      if (k == lose_peer_at) link.peer_lost.store(true);
      const std::uint64_t before = link.sent.load(std::memory_order_acquire);
      clock.Advance();
      while (link.sent.load(std::memory_order_acquire) == before) std::this_thread::yield();
      const Sent c = link.log[before];
      seen.push_back(c);
      yaw += c.w * 0.1;
      x += c.v * std::cos(yaw) * 0.1;
      y += c.v * std::sin(yaw) * 0.1;
    }
  }
};

// The loop on its own thread against the vehicle on this one, for `ticks` lock-step ticks.
loop::RunResult RunLockStep(Controller& c, TestLink& link, rt::LockStepClock& clock, Vehicle& vehicle,
                            std::unique_ptr<loop::LoopData>& l) {
  loop::ClearStop();
  const robot::RobotModel& m = Robot();
  robot::RobotData d = robot::MakeRobotData(m);
  l = loop::MakeLoopData(m, c.source.get());
  robot::Transport* ts[] = {&link};
  loop::RunResult r;
  std::thread thread([&] { r = loop::Run(m, d, *l, ts, clock, {vehicle.ticks, true}); });
  vehicle.Run();
  thread.join();
  return r;
}

}  // namespace

TEST_CASE("auv control loop: lock-step with fresh samples, then stale samples, then a lost peer") {
  auto c = MakeController(test::ScratchDir("auv_loop_stale"));
  TestLink link;
  rt::LockStepClock clock;
  Vehicle vehicle{link, clock, 80, 40, {}};
  std::unique_ptr<loop::LoopData> l;
  const loop::RunResult r = RunLockStep(*c, link, clock, vehicle, l);
  CHECK(r.ticks == 80);
  REQUIRE(vehicle.seen.size() == 80);
  for (std::uint64_t k = 0; k < 40; ++k) {
    CHECK(vehicle.seen[k].mode == 0);
    CHECK(vehicle.seen[k].answers == k);  // each command answers the sample of its tick
  }
  CHECK(std::hypot(vehicle.x, vehicle.y) > 0.0);
  // Last new sample at tick 39: age 2 at tick 41 degrades, age 3 at tick 42 stops, age 21 at
  // tick 60 is a lost peer (e-stop).
  CHECK(vehicle.seen[40].mode == 0);
  CHECK(vehicle.seen[41].mode == 1);
  CHECK(vehicle.seen[43].mode == 2);
  CHECK(vehicle.seen[59].mode == 2);
  CHECK(vehicle.seen[60].mode == 3);
  CHECK(vehicle.seen[50].v == 0.0);  // ramped to zero within 5 stop steps
  CHECK(vehicle.seen[50].w == 0.0);
  Sent last;
  REQUIRE(link.commands.Get(last));  // the stop command after the loop
  CHECK(last.v == 0.0);
  CHECK(last.mode == 3);
  CHECK(l->supervisor().counts[safety::Cause::kStaleSample] > 0);
}

TEST_CASE("auv control loop: the transport reporting the peer lost e-stops at once") {
  auto c = MakeController(test::ScratchDir("auv_loop_peer"));
  TestLink link;
  rt::LockStepClock clock;
  Vehicle vehicle{link, clock, 30, 30, {}};
  vehicle.lose_peer_at = 15;
  std::unique_ptr<loop::LoopData> l;
  (void)RunLockStep(*c, link, clock, vehicle, l);
  CHECK(vehicle.seen[14].mode == 0);
  CHECK(vehicle.seen[15].mode == 3);  // at once
  CHECK(vehicle.seen[29].tick == 29);
  CHECK(vehicle.seen[29].mode == 3);
  CHECK(vehicle.seen[29].v == 0.0);
  const auto& s = l->supervisor();
  CHECK_MESSAGE(s.entered[3].cause == safety::Cause::kLostPeer,
                "mode " << int(s.mode) << " transitions " << s.transitions << " ticks " << s.ticks);
  CHECK(safety::Describe(Robot().supervisor_model, s.entered[3]) ==
        "e-stop: lost peer: transport 'dds' reports the peer gone");
}

TEST_CASE("auv control loop: free-running clock - SIGTERM sends the safe command and ends the loop") {
  auto c = MakeController(test::ScratchDir("auv_loop_signal"));
  TestLink link;
  loop::ClearStop();
  loop::InstallStopSignals();
  std::atomic<bool> done{false};
  std::thread vehicle([&] {  // publishes every 2 ms on its own, not in lock-step
    std::uint64_t k = 0;
    while (!done.load()) {
      AuvSample s = Sample(++k);
      link.samples.Put(s);
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  });
  auto m = robot::WithTickPeriod(Robot(), 0.002);
  REQUIRE(m.ok());
  rt::FreeRunningClock clock(2000000);
  robot::RobotData d = robot::MakeRobotData(*m);
  auto source = loop::PolicySource::Create(*m, c->policy);
  REQUIRE(source.ok());
  auto l = loop::MakeLoopData(*m, source->get());
  robot::Transport* ts[] = {&link};
  loop::RunResult r;
  std::uint64_t allocations = 0;
  std::thread thread([&] {
    AllocationScope scope;
    r = loop::Run(*m, d, *l, ts, clock, {});
    allocations = scope.count();
  });
  while (link.sent.load() < 100) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  std::raise(SIGTERM);
  thread.join();
  done.store(true);
  vehicle.join();
  CHECK(r.stopped);
  CHECK(r.ticks >= 100);
  CHECK(allocations == 0);
  Sent last;
  REQUIRE(link.commands.Get(last));
  CHECK(last.v == 0.0);
  CHECK(last.w == 0.0);
  CHECK(last.mode == 3);
  const rt::ProfileReport rep = rt::TakeReport(l->profiler());
  CHECK(rep.stats[static_cast<std::size_t>(rt::Stage::kTick)].count == r.ticks);
  CHECK(rep.stats[static_cast<std::size_t>(rt::Stage::kJitter)].count == r.ticks);
  MESSAGE(rt::FormatText(rep));
  loop::ClearStop();
  std::signal(SIGTERM, SIG_DFL);
}
