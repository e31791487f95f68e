// pbppo-operator: a scripted operator of any robot over DDS. Plays a schedule file (one declared
// stream's fields over time, e.g. models/quadruped/schedules/*.yaml) as the peer of the robot's
// DDS transport that carries that stream, at the stream's period in real time, and prints the
// controller's status messages as they come back.
//
//   pbppo-operator --robot models/<robot>/robot.yaml --schedule SCHEDULE [--domain D]
//       [--dds-naming native|ros2] [--dds-profile FILE] [--dds-security DIR [--dds-identity NAME]]
//       [--peer-timeout-s S] [--linger-s S] [--quiet]
//
// Waits for a controller (pbppo-controller, or a HIL's in-process controller) to match, publishes
// each phase's values (the message's other leaves: the sequence number and clock the robot file
// names under peer), then falls silent and listens --linger-s longer (the controller's reaction to
// a silent operator). One line per status received (at most one a second): the controller's
// tick, phase, mode, samples taken and the stream's fields in force, as far as the status message
// carries them; and a last one. Exit 0 when the schedule was played and a status came back, 1
// when no controller matched, 2 on bad arguments or files.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "runtime/loop/loop.hpp"
#include "runtime/loop/schedule.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/safety/supervisor.hpp"
#include "runtime/transport/dds/dds_link.hpp"

using namespace pbppo;

namespace {

int Fail(const std::string& msg, int rc) {
  std::fprintf(stderr, "pbppo-operator: %s\n", msg.c_str());
  return rc;
}

// The status message's view of the controller: each part printed where a leaf carries it.
class StatusPrinter {
 public:
  StatusPrinter(const robot::RobotModel& robot, dds::DdsLink& link, std::size_t message, std::uint32_t stream)
      : robot_(robot), link_(link), message_(message), stream_(stream) {
    using K = robot::ValueTerm::Kind;
    tick_ = link.LeafOf(message, K::kTick);
    phase_ = link.LeafOf(message, K::kPhase);
    mode_ = link.LeafOf(message, K::kMode);
    samples_ = link.LeafOf(message, K::kSamples, stream);
    const robot::StreamSpec& s = robot.streams[stream];
    for (std::uint32_t f = s.first_field; f < s.first_field + s.field_count; ++f)
      fields_.push_back(link.LeafOf(message, K::kField, f));
  }
  void Print(const char* when, double t_s, const dds::DdsSample& s) const {
    std::string line;
    char buf[96];
    if (tick_ >= 0) line += ", controller tick " + Whole(s.Get(static_cast<std::uint32_t>(tick_)));
    if (phase_ >= 0) {
      const auto p = static_cast<std::size_t>(s.Get(static_cast<std::uint32_t>(phase_)));
      line += std::string(", ") + (p < loop::kPhaseCount ? loop::ToString(static_cast<loop::Phase>(p)) : "?");
    }
    if (mode_ >= 0) {
      const auto m = static_cast<std::size_t>(s.Get(static_cast<std::uint32_t>(mode_)));
      line += std::string(", ") + (m < safety::kModeCount ? safety::ToString(static_cast<safety::Mode>(m)) : "?");
    }
    if (samples_ >= 0)
      line += ", " + robot_.streams[stream_].name + " " + Whole(s.Get(static_cast<std::uint32_t>(samples_)));
    std::string in_force;
    for (const int leaf : fields_) {
      std::snprintf(buf, sizeof buf, "%s%.2f", in_force.empty() ? "" : ", ",
                    leaf >= 0 ? s.Get(static_cast<std::uint32_t>(leaf)) : 0.0);
      in_force += buf;
    }
    std::printf("%s t=%.1f s%s, in force (%s)\n", when, t_s, line.c_str(), in_force.c_str());
    std::fflush(stdout);
  }

 private:
  static std::string Whole(double v) { return std::to_string(static_cast<unsigned long long>(v)); }
  const robot::RobotModel& robot_;
  dds::DdsLink& link_;
  std::size_t message_;
  std::uint32_t stream_;
  int tick_ = -1, phase_ = -1, mode_ = -1, samples_ = -1;
  std::vector<int> fields_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbppo-operator: plays a schedule of one stream's fields to a robot's controller over DDS"};
  std::string robot_path, schedule_path, profile, naming_text = "native", security_dir, identity = "operator";
  int domain = 0;
  double peer_timeout_s = 30, linger_s = 1.0;
  bool quiet = false;
  app.add_option("--robot", robot_path, "The robot: an installed robot's name (auv) or its robot.yaml")->required();
  app.add_option("--schedule", schedule_path, "Schedule of one of its streams (e.g. models/quadruped/schedules/*.yaml)")
      ->required();
  app.add_option("--domain", domain, "DDS domain id")->check(CLI::Range(0, 232));
  app.add_option("--dds-naming", naming_text, "native or ros2 (rt/ topics, pbppo_msgs::msg::dds_ types)");
  app.add_option("--dds-profile", profile, "Fast DDS XML profile file (default: the robot's)");
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
  const int t = robot->TransportIndex(stream.transport);
  if (t < 0 || robot->transports[static_cast<std::size_t>(t)].kind != "dds")
    return Fail(schedule_path + ": stream '" + stream.name + "' does not travel over DDS (transport '" +
                    stream.transport + "')",
                2);
  dds::DdsLinkOptions o;
  o.domain_id = domain;
  o.naming = *naming;
  o.profile_file = profile;
  o.security = {security_dir, identity};
  auto link = dds::DdsLink::Open(*robot, stream.transport, dds::DdsSide::kPeer, o);
  if (!link) return Fail(link.error().message, 2);
  dds::DdsLink& l = **link;
  std::size_t in = 0, status = l.message_count();
  for (std::size_t i = 0; i < l.message_count(); ++i) {
    if (l.message(i).direction == robot::MessageDirection::kIn && l.message(i).stream == schedule->stream_index) in = i;
    if (l.message(i).direction == robot::MessageDirection::kStatus && status == l.message_count()) status = i;
  }
  std::printf("pbppo-operator: %s (%.1f s, %zu phases) on DDS domain %d, %s names; waiting for a controller\n",
              schedule_path.c_str(), schedule->duration_s(), schedule->phases.size(), domain, dds::ToString(*naming));
  std::fflush(stdout);
  if (!l.WaitForPeer(static_cast<std::int64_t>(peer_timeout_s * 1e9)))
    return Fail("no controller on DDS domain " + std::to_string(domain) + " within " + std::to_string(peer_timeout_s) +
                    " s (--peer-timeout-s)",
                1);

  using Clock = std::chrono::steady_clock;
  auto seconds = [](double s) { return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s)); };
  const auto t0 = Clock::now();
  const auto end = t0 + seconds(schedule->duration_s()), silent_end = end + seconds(linger_s);
  auto next = t0;
  dds::DdsSample command(l.message(in).type);
  std::vector<double> fields(robot->fields.size(), 0.0);
  std::optional<dds::DdsSample> last_status;
  std::optional<StatusPrinter> printer;
  if (status < l.message_count()) {
    last_status.emplace(l.message(status).type);
    printer.emplace(*robot, l, status, schedule->stream_index);
  }
  std::uint64_t sent = 0, status_version = 0;
  double last_print = -1;
  int last_phase = -2;
  for (auto now = Clock::now(); now < silent_end; now = Clock::now()) {
    const double t_s = std::chrono::duration<double>(now - t0).count();
    if (now < end && now >= next) {
      const int phase = schedule->PhaseAt(t_s);
      if (phase >= 0) {
        const loop::SchedulePhase& p = schedule->phases[static_cast<std::size_t>(phase)];
        for (std::uint32_t k = 0; k < stream.field_count; ++k) fields[stream.first_field + k] = p.values[k];
        l.FillFromFields(in, fields, &command);
        if (auto st = l.writer(in)->Write(command.bytes()); !st) return Fail(st.error().message, 1);
        ++sent;
        if (phase != last_phase && !quiet) std::printf("t=%.1f s: phase '%s'\n", t_s, p.name.c_str());
        last_phase = phase;
      }
      next += seconds(stream.period_s);
    }
    if (printer) {
      const std::uint64_t v = l.reader(status)->Read(last_status->bytes(), nullptr);
      if (v != status_version) {
        status_version = v;
        if (!quiet && t_s - last_print >= 1.0) {
          printer->Print("status", t_s, *last_status);
          last_print = t_s;
        }
      }
    }
    if (now >= end && last_phase != -1) {
      last_phase = -1;
      if (!quiet)
        std::printf("t=%.1f s: schedule done, %llu samples sent; silent\n", t_s, static_cast<unsigned long long>(sent));
    }
    std::fflush(stdout);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  if (!printer) return 0;
  if (status_version == 0) return Fail("no status came back from the controller", 1);
  printer->Print("last status", std::chrono::duration<double>(Clock::now() - t0).count(), *last_status);
  return 0;
}
