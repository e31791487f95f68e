#include "sim_hil/quadruped_main.hpp"

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "report/plots.hpp"
#include "runtime/core/cli_checks.hpp"
#include "runtime/loop/record_cli.hpp"
#include "runtime/loop/runner.hpp"
#include "runtime/loop/schedule.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/kernel_option.hpp"
#include "runtime/rt/rt_setup.hpp"
#include "runtime/transport/bindings.hpp"
#include "runtime/transport/can/can_transport.hpp"
#include "sim_hil/quadruped_rig.hpp"
#include "sim_hil/quadruped_scenario.hpp"

namespace pbppo::sim {
namespace {

struct Options {
  std::string robot = "quadruped", scenario, policy, commands, trace, report, plot;
  std::string can;      // IF0[,IF1]
  std::string profile;  // --in-process: the controller's tick profile (JSON)
  std::string operator_kind = "schedule", dds_naming = "native";
  std::string kernel = "auto";  // --in-process: the policy's forward kernel
  std::string dds_security, dds_identity = "controller";
  std::string gamepad;  // --operator robot: the gamepad's device in place of the robot file's
  std::vector<std::string> switch_policies;
  int domain = 0;
  bool stand = false, lockstep = false, in_process = false, skip_self_test = false, realtime = false;
  double duration_s = 0, settle_s = 1.0;
  std::uint64_t seed = 1;
  loop::RecordCli record;  // --in-process: the controller's log (pbppo replay)
};

int Fail(const std::string& msg, int rc) {
  std::fprintf(stderr, "pbppo-hil quadruped: %s\n", msg.c_str());
  return rc;
}

Status WriteReportJson(const RigReport& r, double rtf, const std::string& path) {
  nlohmann::json j = {{"fell", r.fell},
                      {"fell_at_s", r.fell_at_s},
                      {"distance_m", r.distance_m},
                      {"real_time_factor", rtf},
                      {"phases", nlohmann::json::array()}};
  for (const PhaseTracking& p : r.phases) {
    auto three = [](const double* v) { return nlohmann::json::array({v[0], v[1], v[2]}); };
    j["phases"].push_back({{"name", p.name},
                           {"start_s", p.start_s},
                           {"end_s", p.end_s},
                           {"command", three(p.command)},
                           {"mean_abs_error", three(p.mean_abs_error)},
                           {"mean_measured", three(p.mean_measured)}});
  }
  const std::string text = j.dump(2) + "\n";
  return policy::WriteFileAtomic(path, {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()});
}

int InProcess(const Options& o, const robot::RobotModel& model, QuadrupedHilOptions hil) {
  // --operator dds (the older name) and robot: the robot file's own transport of the velocity
  // command, whatever its kind (DDS, a gamepad).
  const bool dds_operator = o.operator_kind != "schedule";
  if (!dds_operator && o.commands.empty())
    return Fail("--in-process needs --commands SCHEDULE (or --operator robot)", 2);
  if (dds_operator && o.commands.empty() && o.duration_s <= 0)
    return Fail(
        "--operator " + o.operator_kind + " needs --duration S or --commands SCHEDULE (the phases of the report)", 2);
  // The schedule plays the operator, or (--operator dds) only names the report's phases.
  auto schedule = !o.commands.empty()
                      ? loop::LoadSchedule(o.commands, model)
                      : loop::ParseSchedule("stream: velocity_command\nphases: [{name: operator, duration_s: " +
                                                std::to_string(o.duration_s) + "}]\n",
                                            "--duration", model);
  if (!schedule) return Fail(schedule.error().message, 2);
  // The robot's own transport of the schedule's stream, opened as pbppo-controller does.
  std::unique_ptr<robot::Transport> op;
  std::string op_what;
  bool wall_clock = false;  // the operator is on a wall clock: a DDS peer, a gamepad (not a recorded file)
  if (dds_operator) {
    transport::Settings s;
    auto naming = dds::ParseDdsNaming(o.dds_naming);
    if (!naming) return Fail("--dds-naming: " + naming.error().message, 2);
    s.dds.domain_id = o.domain;
    s.dds.naming = *naming;
    s.dds.security = {o.dds_security, o.dds_identity};
    s.evdev.device = o.gamepad;
    const int t = model.TransportIndex(model.streams[schedule->stream_index].transport);
    const robot::TransportSpec& spec = model.transports[static_cast<std::size_t>(t)];
    if (!o.gamepad.empty() && spec.kind != "evdev")
      return Fail(
          "--gamepad: the velocity command comes from transport '" + spec.name + "' (" + spec.kind + "), not a gamepad",
          2);
    auto opened = transport::Open(model, spec, s);
    if (!opened) return Fail(opened.error().message, 2);
    op = std::move(*opened);
    if (spec.kind == "evdev") {
      std::error_code ec;
      const std::string& device = o.gamepad.empty() ? spec.evdev.device : o.gamepad;
      wall_clock = !std::filesystem::is_regular_file(device, ec);
      op_what = std::string(wall_clock ? "a gamepad, " : "a recorded gamepad session, ") + device;
    } else {
      wall_clock = true;
      op_what = "velocity commands over DDS, domain " + std::to_string(o.domain) + ", " + o.dds_naming + " names";
    }
  }
  RigOptions ro;
  ro.policy = o.policy;
  ro.switch_policies = o.switch_policies;
  ro.self_test = !o.skip_self_test;
  ro.kernel = policy::KernelOption(o.kernel);
  ro.realtime = o.realtime || wall_clock;
  // An operator who arms the robot (robot.yaml operator.arm) does; else the run arms at once.
  ro.arm = !(dds_operator && model.op.arm >= 0);
  ro.operator_transport = op.get();
  // With a DDS operator the run only needs the wall clock: late ticks (the plant shares the
  // thread) are counted in the profile, not acted on. --realtime alone measures the controller.
  ro.supervise_deadlines = !wall_clock;
  auto rig = QuadrupedRig::Make(model, std::move(hil), std::move(*schedule), ro);
  if (!rig) return Fail(rig.error().message, 2);
  std::printf("pbppo-hil quadruped: controller and HIL in one process, %s, %s, %s, %s (%.1f s)\n",
              ro.realtime ? "free-running at the tick period" : "lock-step",
              o.scenario.empty() ? "flat ground" : o.scenario.c_str(),
              o.policy.empty() ? "no policy" : o.policy.c_str(),
              dds_operator ? op_what.c_str() : ("schedule " + o.commands).c_str(),
              (*rig)->operator_source().schedule().duration_s());
  if (const policy::PolicyModel* p = (*rig)->policy())
    std::printf("controller: policy %s\n", policy::KernelNote(*p, o.skip_self_test).c_str());
  if (ro.realtime) {
    // As pbppo-controller does: locked memory, SCHED_FIFO where permitted (warnings otherwise).
    const rt::RtSetupResult rs = rt::SetUpRealTime(rt::RtOptions{});
    for (const auto& w : rs.warnings) std::fprintf(stderr, "pbppo-hil quadruped: warning: %s\n", w.c_str());
    std::printf("%s\n", rs.Summary().c_str());
  }
  std::unique_ptr<loop::Recorder> recorder;
  if (!o.record.path.empty()) {  // as pbppo-controller records: every input and command of the loop
    auto rec = loop::Recorder::Open(o.record.path, model,
                                    loop::MakeLogHeader(model, (*rig)->source().kind, (*rig)->source().hash),
                                    o.record.options());
    if (!rec) return Fail(rec.error().message, 2);
    recorder = std::move(*rec);
    if (auto st = loop::AttachRecorder(model, (*rig)->data(), (*rig)->loop(), recorder.get()); !st) {
      (void)recorder->Stop();
      return Fail("--record-max-mb: " + st.error().message, 2);
    }
  }
  robot::Transport* published[] = {op.get()};
  std::optional<loop::StatusPublisher> status;
  if (op) status.emplace(published, (*rig)->loop(), 200'000'000);
  std::fflush(stdout);
  const auto t0 = std::chrono::steady_clock::now();
  const bool ok = (*rig)->RunSchedule();
  status.reset();
  if (recorder) {
    (void)loop::AttachRecorder(model, (*rig)->data(), (*rig)->loop(), nullptr);
    if (auto st = recorder->Stop(); !st) return Fail("--record: " + st.error().message, 1);
    std::printf("recorded %llu records in %s (%llu dropped)\n", static_cast<unsigned long long>(recorder->records()),
                o.record.path.c_str(), static_cast<unsigned long long>(recorder->dropped()));
  }
  if (op) op->Finish(loop::StatusOf((*rig)->loop()));  // the final status out, delivered
  if (op && !op->Summary().empty()) std::printf("operator: %s\n", op->Summary().c_str());
  if (const std::string op_line = loop::Describe((*rig)->loop().operator_status()); !op_line.empty())
    std::printf("operator: %s\n", op_line.c_str());
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double sim_s = static_cast<double>((*rig)->ticks()) * model.tick_period_s;
  const RigReport rep = (*rig)->Report(o.settle_s, dds_operator);
  PrintRigReport(rep);
  const safety::SupervisorState& sup = (*rig)->loop().supervisor();
  std::printf("controller: phase %s, mode %s; %llu IMU samples, %llu commands per motor\n",
              loop::ToString((*rig)->loop().phase()), safety::ToString(sup.mode),
              static_cast<unsigned long long>((*rig)->hil().imu_samples()),
              static_cast<unsigned long long>((*rig)->can().commands_sent(0)));
  for (const std::string& line : loop::DescribeChanges((*rig)->loop(), true)) std::printf("%s\n", line.c_str());
  std::printf("%.2f s simulated in %.2f s wall: real-time factor %.2f (%s, Simbody RK2 4 x 0.25 ms per tick)\n", sim_s,
              wall, sim_s / wall, ro.realtime ? "free-running" : "lock-step");
  // The controller's own tick, stage by stage (the HIL's step is outside it); free-running, also
  // the wake-up jitter and the ticks that started late (controller and HIL together overran).
  const rt::ProfileReport profile = rt::TakeReport((*rig)->loop().profiler());
  std::printf("controller tick profile:\n%s", rt::FormatText(profile).c_str());
  if (!o.profile.empty()) {
    const std::string json = rt::FormatJson(profile);
    if (auto st = policy::WriteFileAtomic(o.profile, {reinterpret_cast<const std::uint8_t*>(json.data()), json.size()});
        !st)
      return Fail(st.error().message, 1);
  }
  if (!o.trace.empty())
    if (auto st = WriteRigTrace((*rig)->trace(), o.trace); !st) return Fail(st.error().message, 1);
  if (!o.report.empty())
    if (auto st = WriteReportJson(rep, sim_s / wall, o.report); !st) return Fail(st.error().message, 1);
  if (!o.plot.empty()) {
    if (auto st = PlotRigTrace((*rig)->trace(), "quadruped HIL", (*rig)->model().op.any(), o.plot); !st)
      std::fprintf(stderr, "pbppo-hil quadruped: --plot: %s\n", st.error().message.c_str());
    if (auto st = report::PlotLatency(
            profile, PngStem(o.plot) + "_latency.png",
            std::string("quadruped controller tick (") + (ro.realtime ? "free-running 1 kHz" : "lock-step") + ")");
        !st)
      std::fprintf(stderr, "pbppo-hil quadruped: --plot: %s\n", st.error().message.c_str());
  }
  return ok && !rep.fell ? 0 : 1;
}

}  // namespace

int RunQuadrupedHil(int argc, char** argv, const std::atomic<bool>& stop) {
  CLI::App app{"pbppo-hil quadruped: the quadruped's Simbody plant behind its emulated CAN devices"};
  Options o;
  app.add_option("--robot", o.robot, "The robot: a name or its robot.yaml (default quadruped)");
  app.add_option("--scenario", o.scenario, "Scenario file (terrain, start, pushes, faults); default: flat ground");
  app.add_flag("--stand", o.stand, "The base welded to a stand (no contact)");
  app.add_option("--can", o.can, "CAN interfaces, one per bus of the CAN map (IF0,IF1)");
  app.add_flag("--lockstep", o.lockstep, "Each tick waits for the controller's frames");
  app.add_option("--duration", o.duration_s, "Stop after this much simulated time (s)")->check(CLI::Range(0.0, 1e7));
  app.add_option("--seed", o.seed, "Seed of the emulated drivers' frame drops")
      ->check(cli_checks::NonNegativeInteger());
  app.add_flag("--in-process", o.in_process, "Run the controller in this process too (lock-step, no SocketCAN)");
  app.add_option("--policy", o.policy, "--in-process: the policy blob");
  app.add_option("--commands", o.commands, "--in-process: the velocity command schedule");
  app.add_option_function<std::string>(
         "--switch-policy", [&o](const std::string& blob) { o.switch_policies.push_back(blob); },
         "--in-process: another policy blob the operator's switch request moves to (in order, then back)")
      ->trigger_on_parse();
  app.add_flag("--skip-self-test", o.skip_self_test, "--in-process: arm without the blob's golden vectors");
  policy::AddKernelOption(app, o.kernel);
  app.add_option("--trace", o.trace, "--in-process: write the trace (CSV, every 10 ms)");
  app.add_option("--report", o.report, "--in-process: write per-phase tracking (JSON)");
  app.add_option("--plot", o.plot,
                 "--in-process: velocities PNG (and <name>_path.png, the base path; <name>_latency.png, the tick)");
  app.add_option("--profile", o.profile, "--in-process: write the controller's tick profile (JSON)");
  loop::AddRecordOptions(app, o.record);
  app.add_option("--operator", o.operator_kind,
                 "--in-process: the operator: schedule (--commands), or robot: the robot file's own transport of the "
                 "velocity command (DDS, e.g. from pbppo-operator, or a gamepad; real time unless a recorded gamepad "
                 "file); dds: the same")
      ->check(CLI::IsMember({"schedule", "dds", "robot"}));
  app.add_option("--gamepad", o.gamepad,
                 "--operator robot: the gamepad's device (/dev/input/eventN) or a recorded event file, in place of "
                 "the robot file's");
  app.add_option("--domain", o.domain, "--operator dds: DDS domain id")->check(CLI::Range(0, 232));
  app.add_option("--dds-naming", o.dds_naming, "--operator dds: native or ros2 names");
  app.add_option("--dds-security", o.dds_security, "--operator dds: DDS Security folder (make_dds_security.sh)");
  app.add_option("--dds-identity", o.dds_identity, "--dds-security: this participant's certificate name")
      ->default_str("controller");
  app.add_flag("--realtime", o.realtime,
               "--in-process: tick at the robot's period on the controller's clock (jitter, deadline misses)");
  app.add_option("--settle-s", o.settle_s, "--in-process: tracking is measured this long after each phase starts")
      ->check(CLI::Range(0.0, 100.0));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (o.stand && !o.scenario.empty()) return Fail("--stand and --scenario exclude each other", 2);
  auto model = robot::LoadRobotModel(o.robot);
  if (!model) return Fail(model.error().message, 2);
  QuadrupedHilOptions hil;
  if (!o.scenario.empty()) {
    auto sc = LoadQuadrupedScenario(o.scenario, *model, model->tick_period_s);
    if (!sc) return Fail(sc.error().message, 2);
    hil = sc->hil;
  } else if (!o.stand) {
    hil.plant.mount = Mount::kGround;
  }
  hil.seed = o.seed;
  if (o.in_process) return InProcess(o, *model, std::move(hil));
  auto interfaces = can::ParseInterfaceList(o.can);
  if (!interfaces) return Fail("--can: " + interfaces.error().message, 2);
  hil.interfaces = std::move(*interfaces);
  auto h = QuadrupedHil::Make(*model, hil);
  if (!h) return Fail(h.error().message, 2);
  QuadrupedHil& sim = **h;
  std::printf("pbppo-hil: quadruped %s, %zu joints, %s on %s, %s\n",
              hil.plant.mount == Mount::kStand ? "on a stand" : "on the ground", sim.motor_count(), o.robot.c_str(),
              sim.interface(0).c_str(), o.lockstep ? "lock-step" : "free-running at 1 kHz");
  std::fflush(stdout);
  const auto limit = o.duration_s > 0 ? static_cast<std::uint64_t>(o.duration_s / model->tick_period_s) : 0;
  const HilLoopResult r = RunHilLoop(
      [&] { return o.lockstep ? sim.Tick(sim.frames_per_tick().data(), 100'000'000) : sim.Tick(nullptr, 0); },
      o.lockstep, static_cast<std::int64_t>(model->tick_period_s * 1e9), limit, stop);
  const double sim_s = static_cast<double>(sim.tick()) * model->tick_period_s;
  std::printf("pbppo-hil: %.3f s simulated in %.3f s wall (%.3f simulated s per wall s), %llu overruns%s\n", sim_s,
              r.wall_s, sim_s / r.wall_s, static_cast<unsigned long long>(r.overruns), r.ok ? "" : ", PLANT FAILED");
  std::vector<double> q(sim.plant().joint_count());
  for (std::size_t j = 0; j < q.size(); ++j) q[j] = sim.plant().q_rad(j);
  PrintDeviceSummary(sim.devices(), *model->can, q.data());
  if (hil.plant.mount == Mount::kGround) {
    const BaseState& b = sim.plant().base();
    std::printf("  base at (%.3f, %.3f, %.3f) m\n", b.position_m[0], b.position_m[1], b.position_m[2]);
  }
  return r.ok ? 0 : 1;
}

}  // namespace pbppo::sim
