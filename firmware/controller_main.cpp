// pbppo-controller: the controller program of every robot, over runtime/loop.
//
//   pbppo-controller --robot models/auv/robot.yaml --policy policies/frozen/auv_nav/auv_nav.blob
//       [--lockstep] [--period-ms MS] [--domain D] [--dds-profile FILE] [--lost-after-s S]
//       [--peer-timeout-s S] [--writer-poll-us N] [--status-every-s S]
//   pbppo-controller --robot models/quadruped/robot.yaml [--policy BLOB [--commands SCHEDULE] |
//       --trajectory FILE] [--can IF0,IF1]
//       [--lockstep-wait-ms N] [--candump FILE] [--receive-all]
//       (with a policy and no --commands: velocity commands over DDS on --domain, status published)
//   both: [--dds-naming native|ros2] [--dds-security DIR [--dds-identity NAME]] [--ticks N] [--duration S] [--record
//   LOG] [--profile out.json]
//       [--profile-plot out.png] [--rt-priority P] [--cpu C] [--no-mlock] [--skip-self-test] [--quiet]
//
// Start-up loads the robot once (every file robot.yaml names), the policy blob (refused when it
// was trained for another layout, naming the first difference) and runs the blob's golden vectors
// through the engine (the self-test; a mismatch refuses to arm, naming the row); opens the
// robot's transports; applies the real-time set-up where permitted; arms and ticks read -> check
// -> observe -> infer -> supervise -> write with no allocation. The command source is the policy,
// or a joint trajectory (--trajectory, the robot's stand_trajectory.yaml or another), or none
// (hold the default pose). Ticks come from absolute deadlines at the robot's tick period, or in
// lock-step with a simulator: over DDS one tick per sample (--lockstep), over CAN each tick waits
// for the replies it is owed (--lockstep-wait-ms). SIGINT/SIGTERM, --ticks or --duration (seconds
// of ticks: in lock-step, simulated time) stop: motors are damped and switched off; a robot without
// motors sends its stop command.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "firmware/auv/auv_transport.hpp"
#include "firmware/quadruped/operator_transport.hpp"
#include "report/plots.hpp"
#include "runtime/core/alloc_probe.hpp"
#include "runtime/core/cli_checks.hpp"
#include "runtime/loop/log.hpp"
#include "runtime/loop/runner.hpp"
#include "runtime/loop/schedule.hpp"
#include "runtime/loop/source_files.hpp"
#include "runtime/rt/rt_setup.hpp"
#include "runtime/rt/tick_profiler.hpp"
#include "runtime/transport/can/can_transport.hpp"

namespace {

using namespace pbppo;

struct Options {
  std::string robot, policy, trajectory, record, profile_json, profile_png, dds_profile, can, candump, commands;
  std::string dds_naming = "native";
  std::string dds_security, dds_identity = "controller";
  bool lockstep = false, no_mlock = false, quiet = false, receive_all = false, skip_self_test = false;
  double period_ms = 0, duration_s = 0, peer_timeout_s = 30, status_every_s = 1.0, lost_after_s = 2.0;
  int domain = 0, rt_priority = 80, cpu = -1, lockstep_timeout_ms = 500, lockstep_wait_ms = 0;
  std::int64_t writer_poll_us = -1;
  std::uint64_t max_ticks = 0;
};

int Fail(const std::string& msg, int rc = 2) {
  std::fprintf(stderr, "pbppo-controller: %s\n", msg.c_str());
  return rc;
}

void AddOptions(CLI::App& app, Options& o) {
  app.add_option("--robot", o.robot, "The robot (models/<robot>/robot.yaml)")->required();
  app.add_option("--policy", o.policy, "Frozen policy blob (its golden vectors beside it)");
  app.add_option("--trajectory", o.trajectory, "Joint trajectory (a stand_trajectory.yaml) instead of a policy");
  app.add_option("--commands", o.commands,
                 "A schedule file as the operator (its stream's transport), e.g. the quadruped's velocity commands");
  app.add_flag("--lockstep", o.lockstep, "DDS: one tick per sensor sample (a simulator in lock-step)");
  app.add_option("--lockstep-timeout-ms", o.lockstep_timeout_ms, "DDS lock-step: tick anyway after this long")
      ->check(CLI::Range(1, 600000));
  app.add_option("--lockstep-wait-ms", o.lockstep_wait_ms, "CAN lock-step: each tick waits this long for replies")
      ->check(CLI::Range(0, 600000));
  app.add_option("--period-ms", o.period_ms, "Free-running tick period (default: the robot's)")
      ->check(CLI::Range(0.01, 10000.0));
  app.add_option("--domain", o.domain, "DDS domain id")->check(CLI::Range(0, 232));
  app.add_option("--dds-profile", o.dds_profile, "Fast DDS XML profile file (default: the robot's)");
  app.add_option("--dds-naming", o.dds_naming,
                 "DDS topic and type names: native (pbppo/<robot>/...) or ros2 (rt/pbppo/<robot>/..., "
                 "pbppo_msgs::msg::dds_::<Type>_)");
  app.add_option("--dds-security", o.dds_security,
                 "DDS Security folder (tools/security/make_dds_security.sh): authenticated, encrypted DDS");
  app.add_option("--dds-identity", o.dds_identity, "--dds-security: this participant's certificate name")
      ->default_str("controller");
  app.add_option("--can", o.can, "CAN interfaces, one per bus of the CAN map (IF0,IF1)");
  app.add_option("--candump", o.candump, "Log every CAN frame (candump -L)");
  app.add_flag("--receive-all", o.receive_all, "CAN: no kernel filter (count strays)");
  app.add_option("--ticks", o.max_ticks, "Stop after this many ticks (0: no limit)")
      ->check(pbppo::cli_checks::NonNegativeInteger());
  app.add_option("--duration", o.duration_s,
                 "Stop after this many seconds of ticks (duration / tick period ticks; lock-step: simulated time)")
      ->check(CLI::Range(0.0, 1e7));
  app.add_option("--peer-timeout-s", o.peer_timeout_s, "DDS: how long to wait for the vehicle at start-up")
      ->check(CLI::Range(0.1, 3600.0));
  app.add_option("--lost-after-s", o.lost_after_s, "DDS: the vehicle is lost after this long without a sample")
      ->check(CLI::Range(0.001, 3600.0));
  app.add_option("--record", o.record, "Record every input and command to a log (pbppo replay)");
  app.add_option("--profile", o.profile_json, "Write the latency profile as JSON");
  app.add_option("--profile-plot", o.profile_png, "Write the latency histograms as PNG");
  app.add_option("--rt-priority", o.rt_priority, "SCHED_FIFO priority (0: keep the scheduler)")
      ->check(CLI::Range(0, 99));
  app.add_option("--cpu", o.cpu, "Pin the control thread to this CPU (-1: no pinning)");
  app.add_flag("--no-mlock", o.no_mlock, "Do not lock memory");
  app.add_option("--status-every-s", o.status_every_s, "Status publication and progress line period")
      ->check(CLI::Range(0.05, 3600.0));
  app.add_flag("--quiet", o.quiet, "No progress line");
  app.add_flag("--skip-self-test", o.skip_self_test, "Arm without running the blob's golden vectors");
  app.add_option("--writer-poll-us", o.writer_poll_us,
                 "DDS writer thread polls for commands every N us, so the tick makes no system call (0: the "
                 "tick wakes it; default: 200 free-running, 0 in lock-step)")
      ->check(CLI::Range(-1, 1000000));
}

void PrintSummary(const robot::RobotModel& robot, const loop::LoopData& l, const loop::RunResult& r,
                  const char* clock) {
  const safety::SupervisorState& sup = l.supervisor();
  std::printf("controller: %llu ticks (%s), final mode %s%s%s, phase %s\n", static_cast<unsigned long long>(r.ticks),
              clock, safety::ToString(sup.mode), sup.mode != safety::Mode::kNominal ? " - " : "",
              sup.mode != safety::Mode::kNominal
                  ? safety::Describe(robot.supervisor_model, sup.entered[static_cast<std::size_t>(sup.mode)]).c_str()
                  : "",
              loop::ToString(l.phase()));
  std::printf("supervisor: ");
  for (std::size_t i = 0; i < safety::kCauseCount; ++i)
    std::printf("%s%s %llu", i ? ", " : "", safety::ToString(static_cast<safety::Cause>(i)),
                static_cast<unsigned long long>(sup.counts.n[i]));
  std::printf("\n");
  if (robot.phases.enable_motors)
    for (const auto& p : l.phase_changes())
      std::printf("phase: tick %llu: %s -> %s\n", static_cast<unsigned long long>(p.tick), loop::ToString(p.from),
                  loop::ToString(p.to));
  for (const auto& m : l.mode_changes())
    std::printf("mode change: tick %llu: %s\n", static_cast<unsigned long long>(m.tick), m.reason);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbppo-controller: runs a robot's controller (runtime/loop) over its transports"};
  Options o;
  AddOptions(app, o);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // usage errors exit 2, after CLI11 printed the reason
  }
  // Everything is loaded and checked before anything moves: the robot once, then the source.
  auto loaded = robot::LoadRobotModel(o.robot);
  if (!loaded) return Fail(loaded.error().message);
  // Per-tick limits follow the tick period (a faster free-running tick than the robot's).
  auto ticking =
      robot::WithTickPeriod(*loaded, o.period_ms > 0 && !o.lockstep ? o.period_ms * 1e-3 : loaded->tick_period_s);
  if (!ticking) return Fail(ticking.error().message);
  const robot::RobotModel& robot = *ticking;
  auto source = loop::LoadSource(robot, {o.policy, o.trajectory, !o.skip_self_test});
  if (!source) return Fail(source.error().message);

  // The transports.
  auto naming = dds::ParseDdsNaming(o.dds_naming);
  if (!naming) return Fail("--dds-naming: " + naming.error().message);
  // A DDS transport's participant: the robot's profiles (or --dds-profile's file), the
  // transport's participant_profile, --domain.
  auto participant_options = [&](const robot::TransportSpec& t) -> Result<dds::DdsOptions> {
    dds::DdsOptions d;
    d.domain_id = o.domain;
    if (t.options.count("participant_profile") != 0) d.participant_profile = t.options.at("participant_profile");
    d.profile_file = o.dds_profile;
    d.security = {o.dds_security, o.dds_identity};
    if (o.dds_profile.empty()) {
      auto doc = robot.Document("dds_profile");  // read with the robot
      if (!doc) return std::move(doc).error();
      d.profile_xml = (*doc)->text;
    }
    return d;
  };
  std::unique_ptr<dds::AuvDdsLink> link;
  std::unique_ptr<auv::AuvTransport> auv;
  std::unique_ptr<dds::OperatorDdsLink> operator_link;
  std::unique_ptr<quadruped::OperatorTransport> op;
  std::unique_ptr<can::CanTransport> can;
  std::unique_ptr<loop::ScheduleTransport> schedule;
  std::vector<robot::Transport*> transports;
  std::string schedule_transport;
  if (!o.commands.empty()) {
    auto s = loop::LoadSchedule(o.commands, robot);
    if (!s) return Fail(s.error().message);
    schedule_transport = robot.streams[s->stream_index].transport;
    auto st = loop::ScheduleTransport::Create(robot, std::move(*s));
    if (!st) return Fail(st.error().message);
    schedule = std::move(*st);
  }
  for (const robot::TransportSpec& t : robot.transports) {
    if (t.name == schedule_transport) {
      transports.push_back(schedule.get());
      continue;
    }
    const std::string messages = t.options.count("messages") != 0 ? t.options.at("messages") : "";
    if (t.kind == "can") {
      can::CanTransportOptions co;
      auto interfaces = can::ParseInterfaceList(o.can);
      if (!interfaces) return Fail("--can: " + interfaces.error().message, 2);
      co.interfaces = std::move(*interfaces);
      co.receive_all = o.receive_all;
      co.candump_path = o.candump;
      auto c = can::CanTransport::Open(robot, t.name, co);
      if (!c) return Fail(c.error().message, 1);
      can = std::move(*c);
      can->SetLockStep(static_cast<std::int64_t>(o.lockstep_wait_ms) * 1'000'000);
      transports.push_back(can.get());
    } else if (t.kind == "dds" && messages == "auv") {
      auto participant = participant_options(t);
      if (!participant) return Fail(participant.error().message);
      dds::AuvDdsOptions d;
      static_cast<dds::DdsOptions&>(d) = *participant;
      d.naming = *naming;
      d.writer_poll_us = o.writer_poll_us >= 0 ? o.writer_poll_us : (o.lockstep ? 0 : 200);
      auto l = dds::AuvDdsLink::Create(dds::AuvDdsRole::kController, d);
      if (!l) return Fail(l.error().message);
      link = std::move(*l);
      if (!o.quiet) std::fprintf(stderr, "pbppo-controller: waiting for the vehicle on DDS domain %d\n", o.domain);
      if (!link->WaitForPeer(static_cast<std::int64_t>(o.peer_timeout_s * 1e9)))
        return Fail("no vehicle on DDS domain " + std::to_string(o.domain) + " within " +
                        std::to_string(o.peer_timeout_s) + " s (--peer-timeout-s)",
                    1);
      auto a = auv::AuvTransport::Create(robot, t.name, *link, static_cast<std::int64_t>(o.lost_after_s * 1e9));
      if (!a) return Fail(a.error().message);
      auv = std::move(*a);
      transports.push_back(auv.get());
    } else if (t.kind == "dds" && messages == "velocity_command") {
      // Velocity commands feed the walking policy: with a trajectory (or no source) nobody listens.
      if (source->kind != loop::SourceKind::kPolicy) {
        if (!o.quiet)
          std::fprintf(stderr, "pbppo-controller: transport '%s' unbound (no policy to command)\n", t.name.c_str());
        continue;
      }
      auto participant = participant_options(t);
      if (!participant) return Fail(participant.error().message);
      dds::OperatorDdsOptions d;
      static_cast<dds::DdsOptions&>(d) = *participant;
      d.naming = *naming;
      auto l = dds::OperatorDdsLink::Create(dds::OperatorDdsRole::kController, d);
      if (!l) return Fail(l.error().message);
      operator_link = std::move(*l);
      auto ot = quadruped::OperatorTransport::Create(robot, *operator_link);
      if (!ot) return Fail(ot.error().message);
      op = std::move(*ot);
      transports.push_back(op.get());
      if (!o.quiet)
        std::fprintf(stderr, "pbppo-controller: velocity commands on DDS domain %d (%s naming)\n", o.domain,
                     dds::ToString(*naming));
    } else {
      return Fail(robot.path + ": transport '" + t.name + "' (" + t.kind + (messages.empty() ? "" : ", " + messages) +
                  "): no binding in this program");
    }
  }

  loop::LoopOptions lopt;
  lopt.shutdown_after_source = false;
  robot::RobotData data = robot::MakeRobotData(robot);
  auto loop = loop::MakeLoopData(robot, source->source.get(), lopt);
  std::unique_ptr<loop::Recorder> recorder;
  if (!o.record.empty()) {
    const loop::LogHeader h = loop::MakeLogHeader(robot, source->kind, source->hash, lopt);
    auto r = loop::Recorder::Open(o.record, robot, h);
    if (!r) return Fail(r.error().message, 1);
    recorder = std::move(*r);
    loop->recorder = recorder.get();
  }

  rt::RtOptions ro;
  ro.lock_memory = !o.no_mlock;
  ro.fifo_priority = o.rt_priority;
  ro.cpu = o.cpu;
  const rt::RtSetupResult rs = rt::SetUpRealTime(ro);
  for (const auto& w : rs.warnings) std::fprintf(stderr, "pbppo-controller: warning: %s\n", w.c_str());

  loop::InstallStopSignals();
  std::atomic<bool> done{false}, episode_end{false};
  std::unique_ptr<rt::TickClock> clock;
  std::thread pacer;
  const char* clock_name = "free-running";
  if (o.lockstep && link) {
    auto ls = std::make_unique<rt::LockStepClock>();
    pacer =
        auv::PaceLockStep(*link, *ls, done, static_cast<std::int64_t>(o.lockstep_timeout_ms) * 1'000'000, &episode_end);
    clock = std::move(ls);
    clock_name = "lock-step";
  } else if (o.lockstep_wait_ms > 0) {
    clock = std::make_unique<rt::PacedClock>();  // the CAN transport waits for each tick's replies
    clock_name = "lock-step";
  } else {
    auto fr =
        std::make_unique<rt::FreeRunningClock>(static_cast<std::int64_t>(std::llround(robot.tick_period_s * 1e9)));
    fr->Start();
    clock = std::move(fr);
  }
  if (!o.quiet && can)
    std::printf("pbppo-controller: %s on %s, %s\n", robot.name.c_str(),
                o.can.empty() ? "its CAN map's buses" : o.can.c_str(),
                source->kind == loop::SourceKind::kTrajectory ? "with a trajectory"
                : source->kind == loop::SourceKind::kPolicy   ? "with a policy"
                                                              : "holding the default pose");
  std::fflush(stdout);

  // Status publication, the phase as it changes, progress line: another thread.
  std::thread status([&] {
    const auto t0 = std::chrono::steady_clock::now();
    auto next = t0;
    loop::Phase phase = loop::Phase::kDisarmed;
    while (!done.load()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      const loop::LoopStatus st = loop->Status();
      if (st.phase != phase && robot.phases.enable_motors) {
        std::printf("pbppo-controller: tick %llu: now %s\n", static_cast<unsigned long long>(st.tick),
                    loop::ToString(st.phase));
        std::fflush(stdout);
        phase = st.phase;
      }
      if (std::chrono::steady_clock::now() < next) continue;
      next += std::chrono::milliseconds(static_cast<long>(o.status_every_s * 1000));
      if (link) (void)link->PublishStatus(auv::StatusOf(*loop));
      if (operator_link) (void)operator_link->PublishStatus(quadruped::StatusOf(*loop, op.get()));
      if (!o.quiet && !can) {
        std::fprintf(stderr, "\rtick %llu  mode %s  stale %llu  invalid %llu   ",
                     static_cast<unsigned long long>(st.tick), safety::ToString(st.mode),
                     static_cast<unsigned long long>(st.counts[safety::Cause::kStaleSample]),
                     static_cast<unsigned long long>(st.counts[safety::Cause::kInvalidSample]));
        std::fflush(stderr);
      }
    }
  });

  // --ticks and --duration: whichever comes first (control time: in lock-step the simulator's).
  std::uint64_t max_ticks = o.max_ticks;
  double duration_s = o.duration_s;
  if (duration_s <= 0 && schedule) duration_s = schedule->schedule().duration_s();  // the schedule's end stops
  if (duration_s > 0) {
    const auto d = static_cast<std::uint64_t>(std::max(1.0, std::round(duration_s / robot.tick_period_s)));
    max_ticks = max_ticks == 0 ? d : std::min(max_ticks, d);
  }
  // Every heap allocation of this (the control) thread while the loop runs is counted.
  std::uint64_t allocations = 0;
  loop::RunResult r;
  {
    AllocationScope scope;
    r = loop::Run(robot, data, *loop, transports, *clock, {max_ticks, true});
    allocations = scope.count();
  }
  done.store(true);
  clock->Stop();
  if (pacer.joinable()) pacer.join();
  status.join();
  if (link) (void)link->Flush(1000000000);
  if (operator_link) {
    (void)operator_link->PublishStatus(quadruped::StatusOf(*loop, op.get()));  // the final state
    (void)operator_link->Flush(1000000000);
  }
  if (can) can->Stop();
  if (recorder)
    if (auto st = recorder->Stop(); !st) return Fail(st.error().message, 1);
  if (!o.quiet && !can) std::fprintf(stderr, "\n");

  const rt::ProfileReport report = rt::TakeReport(loop->profiler());
  PrintSummary(robot, *loop, r, clock_name);
  std::printf("control thread heap allocations during the loop: %llu\n", static_cast<unsigned long long>(allocations));
  if (auv)
    std::printf("link: send failures %llu, stopped by %s\n", static_cast<unsigned long long>(auv->send_failures()),
                episode_end.load() ? "the vehicle's episode end" : (r.stopped ? "a signal" : "--ticks or --duration"));
  if (source->trajectory != nullptr && source->trajectory->ticks() > 0)
    std::printf("trajectory tracking RMS %.4f rad, %.4f rad/s (velocity-commanded joints) over %llu ticks\n",
                source->trajectory->rms_tracking_error_rad(), source->trajectory->rms_speed_error_rad_s(),
                static_cast<unsigned long long>(source->trajectory->ticks()));
  if (recorder)
    std::printf("log: %s, %llu records, %llu dropped\n", o.record.c_str(),
                static_cast<unsigned long long>(recorder->records()),
                static_cast<unsigned long long>(recorder->dropped()));
  std::printf("%s\n", rs.Summary().c_str());
  std::printf("%s", rt::FormatText(report).c_str());
  if (!o.profile_json.empty()) {
    std::ofstream f(o.profile_json);
    f << rt::FormatJson(report);
    if (!f) return Fail("--profile: cannot write '" + o.profile_json + "'", 1);
  }
  if (!o.profile_png.empty()) {
    if (auto s = pbppo::report::PlotLatency(report, o.profile_png, "pbppo-controller tick latency"); !s)
      std::fprintf(stderr, "pbppo-controller: --profile-plot: %s\n", s.error().message.c_str());
  }
  return r.status == loop::TickStatus::kFailed ? 1 : 0;
}
