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
//
//   pbppo-hil go2 [--robot models/go2/robot.yaml] [--commands SCHEDULE] [--remote SCHEDULE] [--realtime] [--domain D]
//             [--duration S] [--fault KIND@S[+D][:MOTOR]]... [--report out.json] [--trace out.csv]
//
// A legged robot whose motors speak DDS (the Go2's rt/lowstate and rt/lowcmd) on flat ground,
// behind an emulation of its low-level interface (sim_hil/legged_dds_hil.hpp), for a
// pbppo-controller --lockstep in another process.
//
//   pbppo-hil rotors --robot ROBOT.yaml [--can IF0[,IF1...]] [--lockstep] [--duration S]
//
// Any robot of a CAN map on a stand (sim_hil/rotor_hil.hpp): every actuated joint a free rotor
// behind its emulated driver, the IMU level and still; for a pbppo-controller in another process,
// free-running or in lock-step as above.
#include <signal.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "runtime/core/cli_checks.hpp"
#include "runtime/transport/dds/dds_endpoint.hpp"
#include "sim_hil/auv_hil.hpp"
#include "sim_hil/legged_dds_hil.hpp"
#include "sim_hil/quadruped_main.hpp"
#include "sim_hil/rotor_hil.hpp"

namespace {

std::atomic<bool> g_stop{false};
void OnSignal(int) {
  g_stop.store(true);
}

// pbppo-hil auv's flags into `o` (errors name the flag and the value).
void AddAuvOptions(CLI::App& app, pbppo::sim::AuvHilOptions& o) {
  app.add_option("--layout", o.layout, "Obstacle layout")->check(CLI::IsMember({"easy", "medium", "hard"}));
  app.add_option("--seed", o.seed, "Seed of the episode's start and obstacles")
      ->check(pbppo::cli_checks::NonNegativeInteger())
      ->required();
  app.add_flag("--lockstep", o.lockstep, "Advance one control period per command (the default)");
  app.add_flag_callback("--realtime", [&o] { o.lockstep = false; }, "One control period per period of wall time");
  app.add_option("--domain", o.domain_id, "DDS domain id")->check(CLI::Range(0, 232));
  app.add_option("--dds-naming", o.dds_naming, "DDS topic and type names: native or ros2")
      ->check(CLI::Validator(
          [](const std::string& v) {
            return pbppo::dds::ParseDdsNaming(v) ? std::string() : "'" + v + "' is not native or ros2";
          },
          "native|ros2"));
  app.add_option("--dds-security", o.dds_security, "DDS Security folder (tools/security/make_dds_security.sh)");
  app.add_option("--dds-identity", o.dds_identity, "--dds-security: this participant's certificate name")
      ->default_str("hil");
  const auto positive = pbppo::cli_checks::PositiveSeconds();
  app.add_option("--max-time", o.max_time_s, "Stop after this much simulated time (s)")->check(positive);
  app.add_option("--peer-timeout", o.peer_timeout_s, "Longest wait for the controller to appear (s)")->check(positive);
  app.add_option("--command-timeout", o.command_timeout_s, "Lock-step: longest wait for the next command (s)")
      ->check(positive);
  app.add_option("--trajectory", o.trajectory_csv, "Write the trajectory (CSV)");
  app.add_option("--plot", o.plot_png, "Plot the trajectory over the map (PNG)");
  app.add_option("--events", o.events_json, "Write the episode's events (JSON)");
  app.add_option("--robot", o.robot, "The robot: a name or its robot.yaml (default auv)");
  app.add_option_function<std::string>(
      "--fault",
      [&o](const std::string& v) {
        const auto at = v.find('@');
        const std::string kind = v.substr(0, at);
        char* end = nullptr;
        const double t = at == std::string::npos ? -1 : std::strtod(v.c_str() + at + 1, &end);
        double d = HUGE_VAL;
        bool ok = at != std::string::npos && (kind == "nan" || kind == "range") && end != v.c_str() + at + 1 && t >= 0;
        if (ok && *end == '+') {
          const char* from = end + 1;
          d = std::strtod(from, &end);
          ok = end != from && d > 0 && std::isfinite(d);
        }
        if (!ok || *end != '\0')
          throw CLI::ValidationError("--fault", "'" + v + "' is not KIND@SECONDS[+DURATION] with KIND nan or range");
        o.fault = kind;
        o.fault_time_s = t;
        o.fault_duration_s = d;
      },
      "From this simulated time on (for DURATION s, or to the end), every sample carries the fault: nan@S[+D] or "
      "range@S[+D]");
}

// pbppo-hil go2's flags into `o`.
void AddLeggedDdsOptions(CLI::App& app, pbppo::sim::LeggedDdsHilOptions& o) {
  app.add_option("--robot", o.robot, "The robot: a name or its robot.yaml (default go2)");
  app.add_option("--commands", o.commands, "The controller's velocity schedule: per-phase tracking in the report");
  app.add_flag_callback("--realtime", [&o] { o.lockstep = false; }, "One robot period per period of wall time");
  app.add_option("--domain", o.domain_id, "DDS domain id")->check(CLI::Range(0, 232));
  const auto positive = pbppo::cli_checks::PositiveSeconds();
  app.add_option("--duration", o.duration_s,
                 "Simulated seconds (default: the schedule's end + 3 s, else until the "
                 "controller leaves)")
      ->check(positive);
  app.add_option("--settle-s", o.settle_s, "Tracking is judged this long after each phase starts")
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--peer-timeout", o.peer_timeout_s, "Longest wait for the controller to appear (s)")->check(positive);
  app.add_option("--command-timeout", o.command_timeout_s, "Lock-step: longest wait for the next command (s)")
      ->check(positive);
  app.add_option("--report", o.report, "Write the run's report (JSON)");
  app.add_option("--trace", o.trace, "Write the base's trace, every 10 periods (CSV)");
  app.add_option("--plot", o.plot,
                 "Plot the commanded and measured velocity (PNG; and <name>_path.png, the base's path from above)");
  app.add_option("--remote", o.remote,
                 "A schedule of a stream the state message carries (the robot's remote: its keys and sticks), "
                 "played on the robot's clock");
  app.add_option_function<std::string>(
         "--fault",
         [&o](const std::string& v) {
           pbppo::sim::LeggedDdsFault f;
           std::string why;
           if (!pbppo::sim::ParseLeggedDdsFault(v, &f, &why)) throw CLI::ValidationError("--fault", why);
           o.faults.push_back(f);
         },
         "A fault from SECONDS on (for DURATION s): stop (no state), crc (bad checksums), nan or range (MOTOR's "
         "position), lost (MOTOR's lost-frame counter grows by one per state), silent (MOTOR stops "
         "answering: no torque, its state held, its lost counter growing); repeatable")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
}

// Parses a subcommand's flags (after its name; 2 on a bad one), then runs it with SIGINT and
// SIGTERM asking it to stop.
template <typename Run>
int ParseAndRun(CLI::App& app, int argc, char** argv, Run run) {
  try {
    app.parse(argc - 1, argv + 1);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  signal(SIGINT, OnSignal);
  signal(SIGTERM, OnSignal);
  return run();
}

int Usage(const char* why) {
  std::fprintf(stderr,
               "pbppo-hil: %s\nusage: pbppo-hil auv ... (pbppo-hil auv --help)\n"
               "       pbppo-hil quadruped ... (pbppo-hil quadruped --help)\n"
               "       pbppo-hil go2 ... (pbppo-hil go2 --help)\n"
               "       pbppo-hil rotors ... (pbppo-hil rotors --help)\n",
               why);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pbppo;
  if (argc >= 2 && std::strcmp(argv[1], "auv") == 0) {
    CLI::App app{"pbppo-hil auv: the AUV navigation task over DDS, the vehicle side of the controller's link"};
    sim::AuvHilOptions o;
    AddAuvOptions(app, o);
    return ParseAndRun(app, argc, argv, [&o] { return sim::RunAuvHil(o, g_stop); });
  }
  if (argc >= 2 && std::strcmp(argv[1], "go2") == 0) {
    CLI::App app{
        "pbppo-hil go2: a legged robot whose motors speak DDS (the Go2), the robot's side of its low-level link"};
    sim::LeggedDdsHilOptions o;
    AddLeggedDdsOptions(app, o);
    return ParseAndRun(app, argc, argv, [&o] { return sim::RunLeggedDdsHil(o, g_stop); });
  }
  const bool rotors = argc >= 2 && std::strcmp(argv[1], "rotors") == 0;
  if (argc < 2 || (!rotors && std::strcmp(argv[1], "quadruped") != 0))
    return Usage("the first argument must be 'auv', 'quadruped', 'go2' or 'rotors'");
  signal(SIGINT, OnSignal);
  signal(SIGTERM, OnSignal);
  return rotors ? sim::RunRotorHil(argc - 1, argv + 1, g_stop) : sim::RunQuadrupedHil(argc - 1, argv + 1, g_stop);
}
