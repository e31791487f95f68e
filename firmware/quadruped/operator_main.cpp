// pbppo-operator: a scripted operator for the walking quadruped over DDS. Plays a velocity command
// schedule (models/quadruped/schedules/*.yaml) on the operator topic at the stream's period in
// real time, and prints the controller's status as it comes back.
//
//   pbppo-operator --schedule models/quadruped/schedules/demo.yaml [--domain D]
//       [--dds-naming native|ros2] [--dds-profile FILE] [--dds-security DIR [--dds-identity NAME]] [--robot
//       models/quadruped/robot.yaml]
//       [--peer-timeout-s S] [--linger-s S] [--quiet]
//
// Waits for a controller (pbppo-controller, or pbppo-hil quadruped --in-process --operator dds)
// to match, publishes each phase's command (seq, stamp, vx, vy, yaw rate), then falls silent and
// listens --linger-s longer (the controller's reaction to a silent operator). One line per status
// received (at most one a second) and a last one; exit 0 when the schedule was played and a status
// came back, 1 when no controller matched, 2 on bad arguments or files.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "runtime/core/clock.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/loop/schedule.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/safety/supervisor.hpp"
#include "runtime/transport/dds/operator_dds_link.hpp"

using namespace pbppo;

namespace {

int Fail(const std::string& msg, int rc) {
  std::fprintf(stderr, "pbppo-operator: %s\n", msg.c_str());
  return rc;
}

void PrintStatus(const char* when, double t_s, const robot::QuadrupedStatus& s) {
  std::printf("%s t=%.1f s: controller tick %llu, %s, %s, commands %llu, in force (%.2f, %.2f, %.2f)\n", when, t_s,
              static_cast<unsigned long long>(s.tick),
              s.phase < loop::kPhaseCount ? loop::ToString(static_cast<loop::Phase>(s.phase)) : "?",
              s.mode < safety::kModeCount ? safety::ToString(static_cast<safety::Mode>(s.mode)) : "?",
              static_cast<unsigned long long>(s.commands_received), s.command_vx_mps, s.command_vy_mps,
              s.command_yaw_rate_radps);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbppo-operator: plays a velocity command schedule to a walking quadruped over DDS"};
  std::string robot_path = "models/quadruped/robot.yaml", schedule_path, profile, naming_text = "native";
  int domain = 0;
  double peer_timeout_s = 30, linger_s = 1.0;
  bool quiet = false;
  app.add_option("--schedule", schedule_path, "Velocity command schedule (models/quadruped/schedules/*.yaml)")
      ->required();
  app.add_option("--robot", robot_path, "The robot (its velocity_command stream, its DDS profile)");
  app.add_option("--domain", domain, "DDS domain id")->check(CLI::Range(0, 232));
  app.add_option("--dds-naming", naming_text, "native or ros2 (rt/ topics, pbppo_msgs::msg::dds_ types)");
  app.add_option("--dds-profile", profile, "Fast DDS XML profile file (default: the robot's)");
  std::string security_dir, identity = "operator";
  app.add_option("--dds-security", security_dir,
                 "DDS Security folder (tools/security/make_dds_security.sh): authenticated, encrypted DDS");
  app.add_option("--dds-identity", identity, "--dds-security: this participant's certificate name")
      ->default_str("operator");
  app.add_option("--peer-timeout-s", peer_timeout_s, "How long to wait for a controller")
      ->check(CLI::Range(0.1, 3600.0));
  app.add_option("--linger-s", linger_s, "After the schedule: listen this long, silent")
      ->check(CLI::Range(0.0, 3600.0));
  app.add_flag("--quiet", quiet, "Only the last status line");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  auto naming = dds::ParseDdsNaming(naming_text);
  if (!naming) return Fail("--dds-naming: " + naming.error().message, 2);
  auto robot = robot::LoadRobotModel(robot_path);
  if (!robot) return Fail(robot.error().message, 2);
  auto schedule = loop::LoadSchedule(schedule_path, *robot);
  if (!schedule) return Fail(schedule.error().message, 2);
  const robot::StreamSpec& stream = robot->streams[schedule->stream_index];
  auto columns = schedule->Columns(*robot, {"command_vx", "command_vy", "command_yaw_rate"});
  if (!columns) return Fail(columns.error().message, 2);
  const std::vector<std::size_t>& field = *columns;

  dds::OperatorDdsOptions o;
  o.domain_id = domain;
  o.naming = *naming;
  o.profile_file = profile;
  o.security = {security_dir, identity};
  if (profile.empty()) {
    auto doc = robot->Document("dds_profile");
    if (!doc) return Fail(doc.error().message, 2);
    o.profile_xml = (*doc)->text;
  }
  auto link = dds::OperatorDdsLink::Create(dds::OperatorDdsRole::kOperator, o);
  if (!link) return Fail(link.error().message, 2);
  std::printf("pbppo-operator: %s (%.1f s, %zu phases) on DDS domain %d, %s names; waiting for a controller\n",
              schedule_path.c_str(), schedule->duration_s(), schedule->phases.size(), domain, dds::ToString(*naming));
  std::fflush(stdout);
  if (!(*link)->WaitForPeer(static_cast<std::int64_t>(peer_timeout_s * 1e9)))
    return Fail("no controller on DDS domain " + std::to_string(domain) + " within " + std::to_string(peer_timeout_s) +
                    " s (--peer-timeout-s)",
                1);

  const auto period = std::chrono::duration<double>(stream.period_s);
  const auto t0 = std::chrono::steady_clock::now();
  auto next = t0;
  const auto end = t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(schedule->duration_s()));
  const auto silent_end =
      end + std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(linger_s));
  std::uint64_t seq = 0, status_version = 0;
  robot::QuadrupedStatus status;
  double last_print = -1;
  int last_phase = -2;
  for (;;) {
    const auto now = std::chrono::steady_clock::now();
    if (now >= silent_end) break;
    const double t = std::chrono::duration<double>(now - t0).count();
    if (now < end && now >= next) {
      const int phase = schedule->PhaseAt(t);
      if (phase >= 0) {
        const loop::SchedulePhase& p = schedule->phases[static_cast<std::size_t>(phase)];
        robot::VelocityCommand c;
        c.seq = ++seq;
        c.stamp_ns = MonotonicNs();
        c.vx_mps = p.values[field[0]];
        c.vy_mps = p.values[field[1]];
        c.yaw_rate_radps = p.values[field[2]];
        if (auto st = (*link)->PublishCommand(c); !st) return Fail(st.error().message, 1);
        if (phase != last_phase && !quiet) {
          std::printf("t=%.1f s: phase '%s': (%.2f, %.2f, %.2f)\n", t, p.name.c_str(), c.vx_mps, c.vy_mps,
                      c.yaw_rate_radps);
          std::fflush(stdout);
        }
        last_phase = phase;
      }
      next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    }
    if (const std::uint64_t v = (*link)->ReadStatus(&status); v != status_version) {
      status_version = v;
      if (!quiet && t - last_print >= 1.0) {
        PrintStatus("status", t, status);
        last_print = t;
      }
    }
    if (now >= end && last_phase != -1) {
      last_phase = -1;
      if (!quiet)
        std::printf("t=%.1f s: schedule done, %llu commands sent; silent\n", t, static_cast<unsigned long long>(seq));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  if (status_version == 0) return Fail("no status came back from the controller", 1);
  PrintStatus("last status", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), status);
  return 0;
}
