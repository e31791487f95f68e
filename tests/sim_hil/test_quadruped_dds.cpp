// The quadruped driven by velocity commands over DDS while it walks in the HIL: the controller's
// operator transport (the robot file's DDS messages, dds::DdsTransport) on a real Fast DDS participant,
// the HIL and the controller ticked in lock-step in this process at real time (the operator runs
// on a wall clock). First an operator on Fast DDS with the project's names; then an operator
// written against Cyclone DDS with ROS 2's names (tests/interop/cyclone_operator.c, a child
// process): it commands a walk, reads the controller's status back, then falls silent, and the
// controller must stop the robot. Last, ROS 2's cmd_vel: a Twist on rt/cmd_vel from a node written
// against Cyclone DDS (tests/interop/cyclone_cmd_vel.c), whose silence stops the command.
#include <doctest/doctest.h>

#include <sys/wait.h>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "runtime/loop/runner.hpp"
#include "runtime/loop/schedule.hpp"
#include "runtime/transport/dds/dds_transport.hpp"
#include "sim_hil/quadruped_rig.hpp"
#include "sim_hil/quadruped_scenario.hpp"
#include "tests/support/dds_domain.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/test_paths.hpp"
#include "tests/support/text_edit.hpp"

using namespace pbppo;

namespace {

constexpr std::int64_t kSecond = 1'000'000'000;

dds::DdsLinkOptions Options(dds::DdsNaming naming, int domain) {
  dds::DdsLinkOptions o;
  o.domain_id = domain;
  o.naming = naming;
  return o;
}

// The controller's operator transport, as pbppo-controller opens it from the robot file.
std::unique_ptr<dds::DdsTransport> MakeController(dds::DdsNaming naming, int domain) {
  auto t = dds::DdsTransport::Open(test::QuadrupedRobot(), "operator", Options(naming, domain));
  REQUIRE_MESSAGE(t.ok(), t.error().message);
  return std::move(*t);
}

// Cyclone DDS in a child process on the loopback interface, discovery by unicast to 127.0.0.1 like
// the Fast DDS profile.
void UseCycloneLoopback() {
  setenv("CYCLONEDDS_URI",
         "<CycloneDDS><Domain id=\"any\"><General><Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
         "<AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex>"
         "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>",
         1);
}

// Reads a child's output to its end into *out; its exit status.
int Finish(FILE* child, std::string* out) {
  char line[512];
  while (std::fgets(line, sizeof line, child) != nullptr) *out += line;
  const int status = pclose(child);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Velocity command samples the controller took.
std::uint64_t Commands(dds::DdsTransport& t) {
  return t.link().reader(0)->counters().received;
}

std::unique_ptr<sim::QuadrupedRig> MakeRig(const std::string& schedule_yaml, robot::Transport* op,
                                           const robot::RobotModel& m = test::QuadrupedRobot()) {
  auto s = loop::ParseSchedule(schedule_yaml, "test schedule", m);
  REQUIRE_MESSAGE(s.ok(), s.error().message);
  auto sc = sim::LoadQuadrupedScenario(test::SourcePath("models/quadruped/scenarios/flat.yaml"), m, m.tick_period_s);
  REQUIRE_MESSAGE(sc.ok(), sc.error().message);
  sim::RigOptions o;
  o.policy = test::SourcePath("policies/frozen/quadruped_walk/flat.blob");
  o.operator_transport = op;
  o.realtime = true;              // the operator's clock is the wall clock
  o.supervise_deadlines = false;  // late ticks here are the simulator's (sanitizer builds, a loaded machine)
  auto r = sim::QuadrupedRig::Make(m, sc->hil, std::move(*s), o);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  return std::move(*r);
}

// Mean |vx - command| over the walking (nominal) ticks where `command` was in force, from `settle_s` after
// the first of them.
double TrackingError(const std::vector<sim::RigSample>& trace, float command, double settle_s, std::uint64_t* n) {
  double first = -1, sum = 0;
  *n = 0;
  for (const sim::RigSample& s : trace) {
    if (s.cmd_vx != command || s.loop_phase != static_cast<std::uint8_t>(loop::Phase::kRun) || s.mode != 0) continue;
    if (first < 0) first = s.t_s;
    if (s.t_s < first + settle_s) continue;
    sum += std::fabs(static_cast<double>(s.vx_mps - command));
    ++*n;
  }
  return *n > 0 ? sum / static_cast<double>(*n) : 1e9;
}

}  // namespace

TEST_CASE("velocity commands over Fast DDS drive the walk, and the status comes back") {
  const int domain = test::TestDomain(41);
  const robot::RobotModel& m = test::QuadrupedRobot();
  auto ctl = MakeController(dds::DdsNaming::kNative, domain);
  auto opl = dds::DdsLink::Open(m, "operator", dds::DdsSide::kPeer, Options(dds::DdsNaming::kNative, domain));
  REQUIRE_MESSAGE(opl.ok(), opl.error().message);
  dds::DdsLink& oper = **opl;
  REQUIRE(ctl->link().WaitForPeer(20 * kSecond));
  REQUIRE(oper.WaitForPeer(20 * kSecond));

  auto rig = MakeRig(
      "stream: velocity_command\n"
      "phases:\n"
      "  - {name: stand, duration_s: 2.0}\n"
      "  - {name: forward, duration_s: 3.5, command_vx: 0.5}\n",
      ctl.get());
  std::atomic<bool> done{false};
  bool ran = false;
  robot::Transport* published[] = {ctl.get()};
  {
    loop::StatusPublisher status(published, rig->loop(), 50'000'000);
    // The operator: stand for 2 s of its clock, then 0.5 m/s forward, at 20 Hz until the rig is done.
    std::thread oper_thread([&] {
      const auto t0 = std::chrono::steady_clock::now();
      auto next = t0;
      dds::DdsSample c(oper.message(0).type);
      std::vector<double> fields(m.fields.size(), 0.0);
      const auto vx = static_cast<std::size_t>(m.FieldIndex("command_vx"));
      while (!done.load()) {
        fields[vx] = std::chrono::steady_clock::now() - t0 < std::chrono::seconds(2) ? 0.0 : 0.5;
        oper.FillFromFields(0, fields, &c);
        (void)oper.writer(0)->Write(c.bytes());
        next += std::chrono::milliseconds(50);
        std::this_thread::sleep_until(next);
      }
    });
    ran = rig->RunSchedule();
    done.store(true);
    oper_thread.join();
    std::this_thread::sleep_for(std::chrono::milliseconds(200));  // a status after the last tick
  }
  REQUIRE(ran);
  const sim::RigReport rep = rig->Report(1.0);
  CAPTURE(rep.phases[1].mean_abs_error[0]);
  CAPTURE(rep.phases[1].mean_measured[0]);
  CHECK_FALSE(rep.fell);
  CHECK(rep.phases[1].mean_abs_error[0] <= 0.2);
  CHECK(Commands(*ctl) >= 50);  // 20 Hz for 5.5 s, less discovery
  CHECK(ctl->link().counters().malformed == 0);
  // The status the operator reads back.
  dds::DdsSample st(oper.message(1).type);
  REQUIRE(oper.reader(1)->Read(st.bytes(), nullptr) != 0);
  CHECK(st.Get("phase").value() == static_cast<double>(loop::Phase::kRun));
  CHECK(st.Get("mode").value() == static_cast<double>(safety::Mode::kNominal));
  // The samples the loop took; the reader may have received one or two more after the last tick.
  const std::uint64_t taken = rig->data().samples[static_cast<std::size_t>(m.StreamIndex("velocity_command"))];
  CHECK(st.Get("commands_received").value() == static_cast<double>(taken));
  CHECK(taken <= Commands(*ctl));
  CHECK(taken + 2 >= Commands(*ctl));
  CHECK(st.Get("command_vx_mps").value() == doctest::Approx(0.5));
  CHECK(st.Get("tick").value() >= 5000);
}

TEST_CASE(
    "a Cyclone DDS operator with ROS 2 names drives the walk, reads the status, and its silence stops the robot") {
  const int domain = test::TestDomain(42);
  auto ctl = MakeController(dds::DdsNaming::kRos2, domain);
  UseCycloneLoopback();
  const std::string cmd = std::string(PBPPO_CYCLONE_OPERATOR) + " " + std::to_string(domain) + " 0.5 5.0 3.0 2>&1";
  FILE* child = popen(cmd.c_str(), "r");
  REQUIRE(child != nullptr);
  const bool matched = ctl->link().WaitForPeer(30 * kSecond);  // its writer discovered
  std::string out;
  if (matched) {
    auto rig = MakeRig(
        "stream: velocity_command\n"
        "phases:\n"
        "  - {name: operator, duration_s: 7.0}\n",
        ctl.get());
    bool ran = false;
    robot::Transport* published[] = {ctl.get()};
    {
      loop::StatusPublisher status(published, rig->loop(), 50'000'000);
      ran = rig->RunSchedule();
    }
    CHECK(ran);
    // While commanded: the robot walks at the command, no fall.
    std::uint64_t n = 0;
    const double err = TrackingError(rig->trace(), 0.5f, 1.0, &n);
    CAPTURE(n);
    CHECK(n >= 1500);  // >= 1.5 s of settled walking
    CHECK(n <= 4500);  // ... and not after the commands stopped
    CHECK(err <= 0.2);
    bool contact_while_commanded = false;
    for (const sim::RigSample& s : rig->trace())
      if (s.cmd_vx == 0.5f && s.mode == 0 && s.body_contact) contact_while_commanded = true;
    CHECK_FALSE(contact_while_commanded);
    // Silent: the stale velocity command stream takes the controller to safe-stop.
    bool safe_stop = false;
    for (const loop::ModeChange& c : rig->loop().mode_changes())
      if (c.mode >= safety::Mode::kSafeStop) {
        CAPTURE(c.reason);
        safe_stop = true;
        CHECK(std::string(c.reason).find("velocity_command") != std::string::npos);
        break;
      }
    CHECK(safe_stop);
    CHECK(Commands(*ctl) >= 40);
  }
  const int rc = Finish(child, &out);
  CAPTURE(out);
  REQUIRE(matched);
  CHECK(rc == 0);
  // What the Cyclone operator read back: walking, nominal, its own command while it commanded; the
  // controller in safe-stop or beyond after it fell silent.
  unsigned long long tick = 0, commands = 0;
  unsigned phase = 0, mode = 9, cause = 0;
  double vx = 0;
  const auto at = out.find("commanding ");
  REQUIRE(at != std::string::npos);
  REQUIRE(std::sscanf(out.c_str() + at, "commanding tick=%llu phase=%u mode=%u cause=%u commands=%llu vx=%lf", &tick,
                      &phase, &mode, &cause, &commands, &vx) == 6);
  CHECK(phase == static_cast<unsigned>(loop::Phase::kRun));
  CHECK(mode == 0);
  CHECK(commands > 0);
  CHECK(vx == doctest::Approx(0.5));
  const auto after = out.find("after ");
  REQUIRE(after != std::string::npos);
  REQUIRE(std::sscanf(out.c_str() + after, "after tick=%llu phase=%u mode=%u", &tick, &phase, &mode) == 3);
  CHECK(mode >= static_cast<unsigned>(safety::Mode::kSafeStop));
}

namespace {

// The quadruped with docs/cmd_vel.md's edit: its velocity command from ROS 2's cmd_vel
// (geometry_msgs/msg/Twist on rt/cmd_vel, models/ros2/idl) on a transport of its own, a command
// source whose silence stops the command (zero_after) instead of a fault; the status stays on the
// operator transport.
const robot::RobotModel& CmdVelQuadruped() {
  static const robot::RobotModel* model = [] {
    const std::string dir = test::CopyRobotFolder("quadruped", "quadruped_cmd_vel");
    std::string text = test::ReadText(dir + "/robot.yaml");
    text = test::ReplaceOnce(text, R"(  - name: operator
    kind: dds
    when: policy
    messages:
      - topic: velocity_command
        idl: idl/VelocityCommand.idl
        direction: in
        stream: velocity_command
        fields: {command_vx: vx_mps, command_vy: vy_mps, command_yaw_rate: yaw_rate_radps}
        peer: {seq: sequence, stamp_ns: clock_ns}  # what an operator writes besides the command
        durability: volatile           # any operator, ROS 2's publishers included
)",
                             R"(  - name: nav
    kind: dds
    when: policy
    topic_prefix: rt/
    messages:
      - topic: cmd_vel
        idl: ../ros2/idl/Twist_.idl
        direction: in
        stream: velocity_command
        fields: {command_vx: linear.x, command_vy: linear.y, command_yaw_rate: angular.z}
        durability: volatile
  - name: operator
    kind: dds
    when: policy
    messages:
)");
    text = test::ReplaceOnce(text, R"(    transport: operator
    period_s: 0.1
    required: false
    stale_after: {degraded: 3, safe_stop: 5, lost: 20}
)",
                             R"(    transport: nav
    period_s: 0.1
    zero_after: 5
)");
    std::ofstream(dir + "/robot.yaml") << text;
    auto m = robot::LoadRobotModel(dir + "/robot.yaml");
    if (!m) {
      std::fprintf(stderr, "%s\n", m.error().message.c_str());
      std::abort();
    }
    return new robot::RobotModel(std::move(*m));
  }();
  return *model;
}

}  // namespace

TEST_CASE(
    "ROS 2's cmd_vel (a Twist on rt/cmd_vel) drives the walk, its silence stops the command, a NaN stops the "
    "robot") {
  const int domain = test::TestDomain(43);
  const robot::RobotModel& m = CmdVelQuadruped();
  const int stream = m.StreamIndex("velocity_command");
  REQUIRE(stream >= 0);
  CHECK(m.streams[static_cast<std::size_t>(stream)].zero_after_ticks == 550);  // older than 5.5 periods
  auto t = dds::DdsTransport::Open(m, "nav", Options(dds::DdsNaming::kNative, domain));
  REQUIRE_MESSAGE(t.ok(), t.error().message);
  auto ctl = std::move(*t);
  CHECK(ctl->link().message(0).type.type_name == "geometry_msgs::msg::dds_::Twist_");
  // A ROS 2 node's side in Cyclone DDS (tests/interop/cyclone_cmd_vel.c), on its own clock from
  // when it sees our reader: 0 until 2.5 s, then 0.5 m/s forward at 20 Hz until 5.9 s, one last
  // Twist of 0.45 m/s (it marks the last sample in the trace: how long it stays in force is the
  // silence before the command stops, on the rig's own clock), silence, one Twist with a NaN at
  // 8.5 s.
  UseCycloneLoopback();
  const std::string cmd = std::string(PBPPO_CYCLONE_CMD_VEL) + " " + std::to_string(domain) + " 2>&1";
  FILE* child = popen(cmd.c_str(), "r");
  REQUIRE(child != nullptr);
  const bool matched = ctl->link().WaitForPeer(30 * kSecond);
  bool ran = false;
  std::unique_ptr<sim::QuadrupedRig> rig;
  if (matched) {
    // 12 s: the node's NaN (8.5 s on its clock, which starts when it sees our reader, up to about
    // a second after we see its writer) arrives inside the run.
    rig = MakeRig("stream: velocity_command\nphases:\n  - {name: nav, duration_s: 12.0}\n", ctl.get(), m);
    ran = rig->RunSchedule();
  }
  std::string out;
  const int rc = Finish(child, &out);
  CAPTURE(out);
  REQUIRE(matched);
  CHECK(rc == 0);
  CHECK(ran);
  const std::vector<sim::RigSample>& trace = rig->trace();
  // While commanded: the robot walks at the command.
  std::uint64_t n = 0;
  const double err = TrackingError(trace, 0.5f, 1.0, &n);
  CAPTURE(n);
  CHECK(n >= 1500);
  CHECK(err <= 0.2);
  // Silent: the last Twist stays in force for 5 periods and a half (0.55 s), then the command in
  // force goes straight to 0; the mode stays nominal, the robot stops and stays up.
  double last_from = -1, last_to = -1, zeroed = -1, first_fault = 1e9;
  for (const loop::ModeChange& c : rig->loop().mode_changes())
    first_fault = std::min(first_fault, static_cast<double>(c.tick) * m.tick_period_s);
  double sum = 0;
  std::uint64_t still = 0;
  bool contact = false;
  for (const sim::RigSample& s : trace) {
    if (s.cmd_vx == 0.45f) {
      if (last_from < 0) last_from = s.t_s;
      last_to = s.t_s;
    }
    if (last_from >= 0 && zeroed < 0 && s.cmd_vx == 0.0f) zeroed = s.t_s;
    if (zeroed >= 0 && s.mode == 0) {
      contact = contact || s.body_contact;
      if (s.t_s > zeroed + 1.0) {
        sum += std::fabs(s.vx_mps);
        ++still;
      }
    }
  }
  CAPTURE(last_from);
  CAPTURE(last_to);
  CAPTURE(zeroed);
  CAPTURE(first_fault);
  REQUIRE(last_from > 0);
  REQUIRE(zeroed > 0);
  CHECK(zeroed - last_to < 0.002);  // straight from the last command to 0, nothing between
  CHECK(zeroed - last_from == doctest::Approx(0.551).epsilon(0.01));
  CHECK(first_fault > zeroed + 1.5);  // no fault for the silence
  CHECK_FALSE(contact);
  REQUIRE(still >= 500);
  CHECK(sum / static_cast<double>(still) <= 0.15);
  // The NaN: an invalid sample, safe-stop naming the field.
  bool safe_stop = false;
  for (const loop::ModeChange& c : rig->loop().mode_changes())
    if (c.mode >= safety::Mode::kSafeStop) {
      CAPTURE(c.reason);
      safe_stop = true;
      CHECK(std::string(c.reason).find("invalid sample") != std::string::npos);
      CHECK(std::string(c.reason).find("command_vx") != std::string::npos);
      break;
    }
  CHECK(safe_stop);
  CHECK(ctl->link().counters().malformed == 0);
}
