// pbppo-controller: the controller program of every robot, over runtime/loop.
//
//   pbppo-controller --robot NAME|ROBOT.yaml [--policy BLOB [--commands SCHEDULE] | --trajectory FILE | --safe-stop]
//       [--lockstep [--lockstep-timeout-ms MS] [--lockstep-through-ends]] [--lockstep-wait-ms MS] [--period-ms MS]
//       DDS:  [--domain D] [--dds-profile FILE] [--dds-naming native|ros2] [--dds-security DIR [--dds-identity NAME]]
//             [--peer-timeout-s S] [--lost-after-s S] [--writer-poll-us N] [--status-every-s S]
//       CAN:  [--can IF0,IF1] [--candump FILE] [--receive-all]
//       [--ticks N] [--duration S] [--record LOG [--record-max-mb MB [--record-rotate N]]]
//       [--profile out.json] [--profile-plot out.png]
//       [--rt-priority P] [--cpu C] [--no-mlock] [--skip-self-test] [--kernel K] [--quiet] [--inject-stall-at-tick N]
//       [--failure-record FILE]
//
// Start-up loads the robot once (every file robot.yaml names), the policy blob (refused when it
// was trained for another layout, naming the first difference) and runs the blob's golden vectors
// through the engine (the self-test; a mismatch refuses to arm, naming the row); opens the
// robot's transports through the transport table (runtime/transport/bindings.hpp: every
// transport robot.yaml declares; a schedule file given with --commands stands in for the transport
// of its stream) and waits for the peers the robot file says must be there; applies the real-time
// set-up where permitted; arms and ticks read -> check -> observe -> infer -> supervise -> write
// with no allocation. Ticks come from absolute deadlines at the robot's tick period, or in
// lock-step with a simulator: one tick per sample of the robot's timing.lockstep stream
// (--lockstep; the stream's end field ends the run), or each tick waiting for what the CAN
// transport is owed (--lockstep-wait-ms). A status thread publishes the robot's status messages.
// SIGINT/SIGTERM, --ticks or --duration (seconds of ticks: in lock-step, simulated time) stop:
// motors are damped and switched off; a robot without motors sends its stop command. --safe-stop
// does only that (what a service runs after the controller ended, docs/service.md). Under a
// service manager ($NOTIFY_SOCKET) it reports ready once the robot runs and feeds the watchdog only
// while the loop's tick count advances (runtime/rt/service_notify.hpp). With --failure-record the
// service's stop (--safe-stop) records a run that ended in failure, and the next start refuses to
// arm (exit status 3) unless the robot file allows it (service.rearm_after_failure). Within a run,
// a robot the supervisor stopped runs again by the robot file's supervisor.recovery rule: on a
// person's request (SIGUSR1) or by itself, once healthy (runtime/loop/loop.hpp).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "report/plots.hpp"
#include "runtime/core/alloc_probe.hpp"
#include "runtime/core/cli_checks.hpp"
#include "runtime/loop/log.hpp"
#include "runtime/loop/record_cli.hpp"
#include "runtime/loop/runner.hpp"
#include "runtime/loop/schedule.hpp"
#include "runtime/loop/source_files.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/kernel_option.hpp"
#include "runtime/rt/rt_setup.hpp"
#include "runtime/rt/service_notify.hpp"
#include "runtime/rt/tick_profiler.hpp"
#include "runtime/transport/bindings.hpp"

namespace {

using namespace pbppo;

struct Options {
  std::string robot, policy, trajectory, profile_json, profile_png, dds_profile, can, candump, commands;
  std::string gamepad;                       // the device of the robot's gamepad (a transport of kind evdev)
  std::vector<std::string> switch_policies;  // --switch-policy: more policies the operator switches to
  std::string kernel = "auto";
  std::string dds_naming = "native";
  std::string dds_security, dds_identity = "controller";
  std::string failure_record;  // the service's record of a run that ended in failure
  loop::RecordCli record;      // --record, --record-max-mb, --record-rotate
  bool lockstep = false, no_mlock = false, quiet = false, receive_all = false, skip_self_test = false;
  bool lockstep_through_ends = false;
  bool safe_stop = false;
  double period_ms = 0, duration_s = 0, peer_timeout_s = 30, status_every_s = 1.0, lost_after_s = 0;
  int domain = 0, rt_priority = 80, cpu = -1, lockstep_timeout_ms = 500, lockstep_wait_ms = 0;
  std::int64_t writer_poll_us = -1;
  std::uint64_t max_ticks = 0, stall_at_tick = 0;
};

int Fail(const std::string& msg, int rc = 2) {
  std::fprintf(stderr, "pbppo-controller: %s\n", msg.c_str());
  return rc;
}

// The exit status of a controller that will not arm after a failure (the unit does not restart it).
constexpr int kExitNotRearmed = 3;

// --safe-stop under a service manager, after a run that did not end in success ($SERVICE_RESULT,
// $EXIT_CODE, $EXIT_STATUS: what systemd gives the commands that run after the service's main
// process): one line in `path`, unless a record is there already (the first failure's cause stays).
Status RecordFailure(const std::string& path) {
  const char* result = std::getenv("SERVICE_RESULT");
  if (result == nullptr || *result == '\0' || std::string(result) == "success") return {};
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) return {};
  const char* code = std::getenv("EXIT_CODE");
  const char* status = std::getenv("EXIT_STATUS");
  char when[32] = "";
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  if (gmtime_r(&now, &utc) != nullptr) std::strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%SZ", &utc);
  const std::string line = std::string("result ") + result + ", exit " + (code != nullptr ? code : "?") + " " +
                           (status != nullptr ? status : "?") + ", at " + when + "\n";
  if (auto st = policy::WriteFileAtomic(path, {reinterpret_cast<const std::uint8_t*>(line.data()), line.size()}); !st)
    return st;
  std::printf("pbppo-controller: the run ended in failure (%s): recorded in %s\n",
              line.substr(0, line.size() - 1).c_str(), path.c_str());
  return {};
}

// A run's start with a failure record there: arms only if the robot file allows it (the record is
// then removed, so that the next failure is recorded anew). Returns the exit status to end with, or
// -1 to go on.
int CheckFailureRecord(const robot::RobotModel& robot, const std::string& path) {
  std::error_code ec;
  const bool there = std::filesystem::exists(path, ec);
  if (ec)  // fails closed: a record that cannot be looked for may be there
    return Fail("not arming: cannot tell whether the failure record '" + path + "' is there: " + ec.message(),
                kExitNotRearmed);
  if (!there) return -1;
  std::ifstream in(path);
  std::string what;
  if (!std::getline(in, what) || what.empty()) what = "the record names no cause";
  if (!robot.service.rearm_after_failure)
    return Fail("not arming: the last run ended in failure (" + what + "; " + path + ") and " + robot.path +
                    " does not let a controller started again after a failure arm the robot "
                    "(service.rearm_after_failure); once the cause is known, a person starts it",
                kExitNotRearmed);
  std::printf("pbppo-controller: arming again after a failure (%s): %s allows it (service.rearm_after_failure)\n",
              what.c_str(), robot.path.c_str());
  if (!std::filesystem::remove(path, ec) || ec)
    return Fail("--failure-record: cannot remove '" + path + "': " + (ec ? ec.message() : "not removed"), 1);
  return -1;
}

void AddOptions(CLI::App& app, Options& o) {
  app.add_option("--robot", o.robot, "The robot: an installed robot's name (auv) or its robot.yaml")->required();
  app.add_option("--policy", o.policy, "Frozen policy blob (its golden vectors beside it)");
  app.add_option("--trajectory", o.trajectory, "Joint trajectory (a stand_trajectory.yaml) instead of a policy");
  app.add_option("--commands", o.commands,
                 "A schedule file in place of the transport of its stream (an operator's commands, played)");
  // (Each occurrence appended as it is parsed: a std::vector option makes GCC 12 report a null
  // dereference inside CLI11's string split in the ThreadSanitizer build.)
  app.add_option_function<std::string>(
         "--switch-policy", [&o](const std::string& blob) { o.switch_policies.push_back(blob); },
         "Another policy blob the operator's switch request (robot.yaml operator.switch_policy) moves to, "
         "in the order given, then back to --policy; each loaded and self-tested at start")
      ->trigger_on_parse();
  app.add_option("--gamepad", o.gamepad,
                 "The robot's gamepad (its transport of kind evdev) from this device (/dev/input/eventN, "
                 "/dev/input/by-id/...) or recorded event file, in place of the robot file's");
  app.add_flag("--lockstep", o.lockstep,
               "One tick per sample of the robot's timing.lockstep stream (a simulator in lock-step)");
  app.add_option("--lockstep-timeout-ms", o.lockstep_timeout_ms, "--lockstep: tick anyway after this long")
      ->check(CLI::Range(1, 600000));
  app.add_flag("--lockstep-through-ends", o.lockstep_through_ends,
               "--lockstep: the simulator's episode end does not end the run (simulators that come and go)");
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
  app.add_option("--peer-timeout-s", o.peer_timeout_s,
                 "DDS: how long to wait at start-up for the peers of transports that wait for theirs")
      ->check(CLI::Range(0.1, 3600.0));
  app.add_option("--lost-after-s", o.lost_after_s,
                 "DDS: a peer is lost after this long without a sample (default: the robot file's lost_after_s)")
      ->check(CLI::Range(0.001, 3600.0));
  loop::AddRecordOptions(app, o.record);
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
  policy::AddKernelOption(app, o.kernel);
  app.add_flag("--safe-stop", o.safe_stop,
               "Only stop the robot: damp its motors, then switch them off (a robot without motors: send its "
               "stop command), then exit. What the service runs after the controller ended, however it ended");
  app.add_option("--failure-record", o.failure_record,
                 "The service's record of a run that ended in failure: --safe-stop writes it when $SERVICE_RESULT "
                 "is not success; a run that finds it does not arm (exit status 3) unless the robot file says "
                 "service.rearm_after_failure: true");
  app.add_option("--inject-stall-at-tick", o.stall_at_tick,
                 "Fault injection (the watchdog's test): the control loop stops ticking at this tick while the rest "
                 "of the process goes on (0: never)")
      ->check(pbppo::cli_checks::NonNegativeInteger());
  app.add_option("--writer-poll-us", o.writer_poll_us,
                 "DDS writer threads poll for samples every N us, so the tick makes no system call (0: the "
                 "tick wakes them; default: 200 free-running, 0 in lock-step)")
      ->check(CLI::Range(-1, 1000000));
}

// The robot's transports, opened through the transport table; a schedule file stands in for the
// transport of its stream.
struct Transports {
  std::vector<std::unique_ptr<robot::Transport>> owned;
  std::unique_ptr<loop::ScheduleTransport> schedule;
  std::vector<robot::Transport*> all;  // in robot.yaml's order
  std::vector<const robot::TransportSpec*> specs;
};

Result<Transports> OpenTransports(const robot::RobotModel& robot, const Options& o, const loop::LoadedSource& source) {
  Transports ts;
  std::string schedule_transport;
  if (!o.commands.empty()) {
    auto s = loop::LoadSchedule(o.commands, robot);
    if (!s) return std::move(s).error();
    schedule_transport = robot.streams[s->stream_index].transport;
    auto st = loop::ScheduleTransport::Create(robot, std::move(*s));
    if (!st) return std::move(st).error();
    ts.schedule = std::move(*st);
  }
  transport::Settings settings;
  auto interfaces = can::ParseInterfaceList(o.can);
  if (!interfaces) return MakeError(interfaces.error().code, "--can: " + interfaces.error().message);
  settings.can.interfaces = std::move(*interfaces);
  settings.can.receive_all = o.receive_all;
  settings.can.candump_path = o.candump;
  settings.can_lockstep_wait_ns = static_cast<std::int64_t>(o.lockstep_wait_ms) * 1'000'000;
  if (!o.gamepad.empty()) {
    if (std::none_of(robot.transports.begin(), robot.transports.end(),
                     [](const robot::TransportSpec& t) { return t.kind == "evdev"; }))
      return MakeError(ErrorCode::kInvalidValue,
                       "--gamepad: " + robot.path + " has no gamepad (a transport of kind evdev) to read " + o.gamepad);
    settings.evdev.device = o.gamepad;
  }
  auto naming = dds::ParseDdsNaming(o.dds_naming);
  if (!naming) return MakeError(naming.error().code, "--dds-naming: " + naming.error().message);
  dds::DdsLinkOptions& d = settings.dds;
  d.naming = *naming;
  d.domain_id = o.domain;
  d.profile_file = o.dds_profile;
  d.security = {o.dds_security, o.dds_identity};
  d.writer_poll_us = o.writer_poll_us >= 0 ? o.writer_poll_us : (o.lockstep ? 0 : 200);
  d.lost_after_s = o.lost_after_s;
  for (const robot::TransportSpec& t : robot.transports) {
    if (t.name == schedule_transport) {
      ts.all.push_back(ts.schedule.get());
      ts.specs.push_back(&t);
      continue;
    }
    // A transport only a policy reads (an operator's velocity commands) waits for no one otherwise.
    if (t.policy_only && source.kind != loop::SourceKind::kPolicy) {
      if (!o.quiet) std::fprintf(stderr, "pbppo-controller: transport '%s' unbound (no policy)\n", t.name.c_str());
      continue;
    }
    auto opened = transport::Open(robot, t, settings);
    if (!opened) return std::move(opened).error();
    if (!o.quiet && !t.dds.messages.empty())
      std::fprintf(stderr, "pbppo-controller: transport '%s' on DDS domain %d (%s naming)%s\n", t.name.c_str(),
                   o.domain, dds::ToString(*naming), t.dds.wait_for_peer ? ", waiting for its peer" : "");
    // --safe-stop sends its stop whether or not the peer is there (it may be what stopped).
    const double wait_s = o.safe_stop ? std::min(o.peer_timeout_s, 2.0) : o.peer_timeout_s;
    if (auto st = (*opened)->Connect(static_cast<std::int64_t>(wait_s * 1e9)); !st) {
      if (!o.safe_stop) return MakeError(st.error().code, st.error().message + " (--peer-timeout-s)");
      std::fprintf(stderr, "pbppo-controller: --safe-stop: %s; sending the stop anyway\n", st.error().message.c_str());
    }
    ts.all.push_back(opened->get());
    ts.specs.push_back(&t);
    ts.owned.push_back(std::move(*opened));
  }
  return ts;
}

// --inject-stall-at-tick: the inner clock's ticks until that tick, then none until Stop().
class StallingClock final : public rt::TickClock {
 public:
  StallingClock(std::unique_ptr<rt::TickClock> inner, std::uint64_t stall_at) noexcept
      : inner_(std::move(inner)), stall_at_(stall_at) {}
  bool Wait(rt::TickTiming& t) noexcept override {
    if (!inner_->Wait(t)) return false;
    if (t.tick < stall_at_) return true;
    while (!stop_.load(std::memory_order_relaxed)) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    return false;
  }
  void Stop() noexcept override {
    stop_.store(true, std::memory_order_relaxed);
    inner_->Stop();
  }
  std::uint64_t deadline_misses() const noexcept override { return inner_->deadline_misses(); }

 private:
  std::unique_ptr<rt::TickClock> inner_;
  std::uint64_t stall_at_;
  std::atomic<bool> stop_{false};
};

// The tick clock: one tick per sample of the robot's lock-step stream (a pacing thread), each
// tick paced by a transport that waits (CAN lock-step), or absolute deadlines.
struct Clock {
  std::unique_ptr<rt::TickClock> clock;
  std::thread pacer;
  const char* name = "free-running";
};

Result<Clock> MakeClock(const robot::RobotModel& robot, const Options& o, const Transports& ts,
                        const std::atomic<bool>& done) {
  Clock c;
  if (o.lockstep) {
    if (robot.lockstep_stream < 0)
      return MakeError(ErrorCode::kInvalidValue, "--lockstep: " + robot.path + " declares no timing.lockstep stream");
    const auto stream = static_cast<std::uint32_t>(robot.lockstep_stream);
    const auto pacer =
        std::find_if(ts.all.begin(), ts.all.end(), [&](robot::Transport* t) { return t->Paces(stream); });
    if (pacer == ts.all.end())
      return MakeError(ErrorCode::kInvalidValue, "--lockstep: no open transport waits for samples of stream '" +
                                                     robot.streams[stream].name + "'");
    auto ls = std::make_unique<rt::LockStepClock>();
    c.pacer =
        loop::PaceBySamples(**pacer, stream, *ls, done, static_cast<std::int64_t>(o.lockstep_timeout_ms) * 1'000'000);
    c.clock = std::move(ls);
    c.name = "lock-step";
  } else if (o.lockstep_wait_ms > 0) {
    c.clock = std::make_unique<rt::PacedClock>();  // the CAN transport waits for each tick's replies
    c.name = "lock-step";
  } else {
    auto fr =
        std::make_unique<rt::FreeRunningClock>(static_cast<std::int64_t>(std::llround(robot.tick_period_s * 1e9)));
    fr->Start();
    c.clock = std::move(fr);
  }
  if (o.stall_at_tick > 0) c.clock = std::make_unique<StallingClock>(std::move(c.clock), o.stall_at_tick);
  return c;
}

// The service manager (rt/service_notify.hpp), from the status thread: ready once the robot runs
// (robots with motors: stood up, in hold or run), the watchdog only while the tick count advances,
// stopping once the stop began, a status line with each publication.
struct ServiceState {
  rt::ServiceNotifier& notify;
  bool ready = false, stopping = false;
  const char* note = "";  // appended to the status line
  std::uint64_t last_tick = 0;
  std::chrono::steady_clock::time_point last_ping{};

  void Poll(const robot::RobotModel& robot, const loop::LoopStatus& st, bool published) {
    if (!notify.active()) return;
    const bool running =
        st.phase == loop::Phase::kRun || (robot.phases.enable_motors && st.phase == loop::Phase::kHold);
    if (!ready && running) {
      ready = true;
      notify.Ready();
    }
    const bool ending = st.phase == loop::Phase::kDamping || st.phase == loop::Phase::kMotorOff ||
                        st.phase == loop::Phase::kDone || st.phase == loop::Phase::kFailed || loop::StopRequested();
    if (!stopping && ending) {
      stopping = true;
      notify.Stopping();
    }
    const auto now = std::chrono::steady_clock::now();
    if (notify.watchdog_ns() > 0 && st.tick != last_tick &&
        now - last_ping >= std::chrono::nanoseconds(notify.watchdog_ns() / 4)) {
      notify.Watchdog();
      last_tick = st.tick;
      last_ping = now;
    }
    if (published) {
      char line[200];
      std::snprintf(line, sizeof line, "tick %llu, phase %s, mode %s%s", static_cast<unsigned long long>(st.tick),
                    loop::ToString(st.phase), safety::ToString(st.mode), note);
      notify.Status(line);
    }
  }
};

// Start-up (loading, self-test, waiting for peers) keeps the watchdog fed from a thread of its own;
// once the loop ticks, only its progress does (ServiceState).
class StartupWatchdog {
 public:
  explicit StartupWatchdog(rt::ServiceNotifier& n) {
    if (!n.active() || n.watchdog_ns() <= 0) return;
    thread_ = std::thread([this, &n] {
      std::unique_lock lock(m_);
      do n.Watchdog();
      while (!cv_.wait_for(lock, std::chrono::nanoseconds(n.watchdog_ns() / 4), [this] { return done_; }));
    });
  }
  ~StartupWatchdog() { Finish(); }
  void Finish() {
    {
      std::lock_guard lock(m_);
      done_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::mutex m_;
  std::condition_variable cv_;
  bool done_ = false;
  std::thread thread_;
};

// ", in 5 files (run.log to run.4.log; the 3 oldest deleted)" for a rotated log.
std::string Files(const loop::Recorder& r) {
  const std::uint32_t n = r.files(), deleted = r.files_deleted();
  if (n == 1) return "";
  std::string s = ", in " + std::to_string(n) + " files (" + r.path() + " to " + loop::RotatedPath(r.path(), n - 1);
  if (deleted > 0) s += "; the " + std::to_string(deleted) + " oldest deleted";
  return s + ")";
}

// The phase as it changes (robots with phases) or a progress line every status period (others);
// a recording that stopped on a failure, once, as soon as the status thread sees it.
loop::StatusPublisher::Poll Progress(const robot::RobotModel& robot, const Options& o, ServiceState* service,
                                     const loop::Recorder* recorder) {
  return [&robot, &o, service, recorder, phase = loop::Phase::kDisarmed, told = false, recoveries = std::uint64_t{0},
          stopped = false](const loop::LoopStatus& st, bool published) mutable {
    service->Poll(robot, st, published);
    // Stopped by the supervisor: what it takes to run again; then each re-arm or refused request.
    const bool now_stopped = st.mode >= safety::Mode::kSafeStop && st.phase != loop::Phase::kDisarmed &&
                             st.phase != loop::Phase::kDamping && st.phase != loop::Phase::kMotorOff &&
                             st.phase != loop::Phase::kDone;
    if (now_stopped && !stopped) {
      const robot::RecoverySpec& r = robot.supervisor.recovery;
      std::printf("pbppo-controller: tick %llu: %s%s%s; runs again %s once healthy for %g s\n",
                  static_cast<unsigned long long>(st.tick), safety::ToString(st.mode), st.any_latched ? ": " : "",
                  st.any_latched ? safety::ToString(st.latched) : "",
                  r.automatic ? "by itself (supervisor.recovery: automatic, for its causes) or on request (SIGUSR1)"
                              : "on request (SIGUSR1; supervisor.recovery: request)",
                  r.healthy_s);
      std::fflush(stdout);
    }
    stopped = now_stopped;
    if (st.rearms + st.refused != recoveries) {
      recoveries = st.rearms + st.refused;
      std::printf("pbppo-controller: tick %llu: %s\n", static_cast<unsigned long long>(st.tick), st.recovery);
      std::fflush(stdout);
    }
    if (recorder != nullptr && !told && recorder->failed()) {
      told = true;
      std::fprintf(stderr, "\npbppo-controller: tick %llu: log %s: %s; recording stopped, the control loop goes on\n",
                   static_cast<unsigned long long>(st.tick), o.record.path.c_str(), recorder->failure().c_str());
      std::fflush(stderr);
      service->note = ", recording stopped (a failed write)";
    }
    if (st.phase != phase && robot.phases.enable_motors) {
      std::printf("pbppo-controller: tick %llu: now %s\n", static_cast<unsigned long long>(st.tick),
                  loop::ToString(st.phase));
      std::fflush(stdout);
      phase = st.phase;
    }
    if (!published || o.quiet || robot.phases.enable_motors) return;
    std::fprintf(stderr, "\rtick %llu  mode %s  stale %llu  invalid %llu   ", static_cast<unsigned long long>(st.tick),
                 safety::ToString(st.mode), static_cast<unsigned long long>(st.counts[safety::Cause::kStaleSample]),
                 static_cast<unsigned long long>(st.counts[safety::Cause::kInvalidSample]));
    std::fflush(stderr);
  };
}

void PrintSummary(const robot::RobotModel& robot, const loop::LoopData& l, const loop::RunResult& r, const char* clock,
                  bool safe_stop) {
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
  for (const std::string& line : loop::DescribeChanges(l, true)) std::printf("%s\n", line.c_str());
  if (const std::string op_line = loop::Describe(l.operator_status()); !op_line.empty())
    std::printf("operator: %s\n", op_line.c_str());
  if (const loop::RecoveryStatus& rec = l.recovery(); rec.stops + rec.refused > 0)
    std::printf(
        "recovery: stopped %llu times, re-armed %llu (%llu automatically, %llu on request), %llu requests "
        "refused\n",
        static_cast<unsigned long long>(rec.stops), static_cast<unsigned long long>(rec.automatic + rec.requested),
        static_cast<unsigned long long>(rec.automatic), static_cast<unsigned long long>(rec.requested),
        static_cast<unsigned long long>(rec.refused));
  const bool done = r.status == loop::TickStatus::kDone;
  const char* end = r.ended             ? nullptr
                    : r.stopped         ? "a signal"
                    : safe_stop && done ? "--safe-stop, its stop done"
                    : done              ? "its stop done (the operator's stop request or the command source's end)"
                                        : "--ticks or --duration";
  std::printf("stopped by %s%s\n", end != nullptr ? end : "the end field ",
              end != nullptr ? "" : robot.fields[static_cast<std::size_t>(robot.lockstep_end_field)].name.c_str());
}

// --ticks and --duration, whichever comes first (control time: in lock-step the simulator's); a
// schedule's end stops too.
std::uint64_t MaxTicks(const robot::RobotModel& robot, const Options& o, const Transports& ts) {
  std::uint64_t max_ticks = o.max_ticks;
  double duration_s = o.duration_s;
  if (duration_s <= 0 && ts.schedule) duration_s = ts.schedule->schedule().duration_s();
  if (duration_s > 0) {
    const auto d = static_cast<std::uint64_t>(std::max(1.0, std::round(duration_s / robot.tick_period_s)));
    max_ticks = max_ticks == 0 ? d : std::min(max_ticks, d);
  }
  return max_ticks;
}

// Everything is loaded and checked before anything moves: the robot once, its source, its transports.
int Run(const Options& o) {
  auto notifier = rt::ServiceNotifier::FromEnvironment();
  if (!notifier) return Fail(notifier.error().message);
  StartupWatchdog startup(*notifier);
  if (o.safe_stop && (!o.policy.empty() || !o.trajectory.empty() || !o.commands.empty() || o.lockstep))
    return Fail("--safe-stop: takes no --policy, --trajectory, --commands or --lockstep (it only stops the robot)");
  if (o.lockstep_through_ends && !o.lockstep) return Fail("--lockstep-through-ends: only with --lockstep");
  auto loaded = robot::LoadRobotModel(o.robot);
  if (!loaded) return Fail(loaded.error().message);
  if (!o.failure_record.empty()) {
    if (o.safe_stop) {
      if (auto st = RecordFailure(o.failure_record); !st)
        std::fprintf(stderr, "pbppo-controller: --failure-record: %s (stopping anyway)\n", st.error().message.c_str());
    } else if (const int rc = CheckFailureRecord(*loaded, o.failure_record); rc >= 0) {
      return rc;
    }
  }
  // Per-tick limits follow the tick period (a faster free-running tick than the robot's).
  auto ticking =
      robot::WithTickPeriod(*loaded, o.period_ms > 0 && !o.lockstep ? o.period_ms * 1e-3 : loaded->tick_period_s);
  if (!ticking) return Fail(ticking.error().message);
  const robot::RobotModel& robot = *ticking;
  auto source = loop::LoadSource(
      robot, {o.policy, o.trajectory, !o.skip_self_test, policy::KernelOption(o.kernel), o.switch_policies});
  if (!source) return Fail(source.error().message);
  if (source->policy)
    std::printf("pbppo-controller: policy %s %s\n", o.policy.c_str(),
                policy::KernelNote(*source->policy, o.skip_self_test).c_str());
  for (std::size_t k = 0; k < source->more_policies.size(); ++k)
    std::printf("pbppo-controller: policy %s %s (field '%s' switches to it in turn)\n", o.switch_policies[k].c_str(),
                policy::KernelNote(*source->more_policies[k], o.skip_self_test).c_str(),
                robot.fields[static_cast<std::size_t>(robot.op.switch_policy)].name.c_str());
  loop::LoopOptions lopt;
  lopt.shutdown_after_source = false;
  lopt.stop_at_end_field = o.lockstep && robot.lockstep_end_field >= 0 && !o.lockstep_through_ends;
  // The log before the transports: a log that cannot be written is refused at once, not after
  // the wait for a peer; if the transports then fail, the empty log is removed.
  std::unique_ptr<loop::Recorder> recorder;
  if (!o.record.path.empty()) {
    auto r = loop::Recorder::Open(o.record.path, robot, loop::MakeLogHeader(robot, source->kind, source->hash, lopt),
                                  o.record.options());
    if (!r) return Fail(r.error().message, 1);
    recorder = std::move(*r);
  }
  robot::RobotData data = robot::MakeRobotData(robot);
  auto loop = loop::MakeLoopData(robot, source->source.get(), lopt);
  if (auto st = loop::AttachRecorder(robot, data, *loop, recorder.get()); !st) {
    (void)recorder->Stop();
    std::error_code ec;
    std::filesystem::remove(o.record.path, ec);
    return Fail("--record-max-mb: " + st.error().message, 2);
  }
  auto opened = OpenTransports(robot, o, *source);
  if (!opened) {
    if (recorder) {
      (void)recorder->Stop();
      std::error_code ec;
      std::filesystem::remove(o.record.path, ec);
    }
    return Fail(opened.error().message, opened.error().code == ErrorCode::kIo ? 1 : 2);
  }
  Transports& ts = *opened;
  rt::RtOptions ro;
  ro.lock_memory = !o.no_mlock;
  ro.fifo_priority = o.rt_priority;
  ro.cpu = o.cpu;
  const rt::RtSetupResult rs = rt::SetUpRealTime(ro);
  for (const auto& w : rs.warnings) std::fprintf(stderr, "pbppo-controller: warning: %s\n", w.c_str());
  loop::InstallStopSignals();
  loop::InstallRearmSignal();
  std::atomic<bool> done{false};
  auto clock = MakeClock(robot, o, ts, done);
  if (!clock) return Fail(clock.error().message);
  if (o.safe_stop) {
    loop->RequestStop();  // the first tick begins the stop: damping, then motors off
    std::printf("pbppo-controller: %s: safe stop\n", robot.name.c_str());
  }
  // A robot on CAN: where its buses are (--can, else the interfaces its CAN map names).
  const std::string where = robot.can ? " on " + (o.can.empty() ? std::string("its CAN map's buses") : o.can) : "";
  if (!o.quiet && robot.phases.enable_motors)
    std::printf("pbppo-controller: %s%s, %s\n", robot.name.c_str(), where.c_str(),
                source->kind == loop::SourceKind::kTrajectory ? "with a trajectory"
                : source->kind == loop::SourceKind::kPolicy   ? "with a policy"
                                                              : "holding the default pose");
  std::fflush(stdout);
  std::optional<loop::StatusPublisher> status;
  ServiceState service{*notifier};
  startup.Finish();  // the status thread feeds the watchdog from here on (one thread sends at a time)
  status.emplace(ts.all, *loop, static_cast<std::int64_t>(o.status_every_s * 1e9),
                 Progress(robot, o, &service, recorder.get()));

  // Every heap allocation of this (the control) thread while the loop runs is counted.
  // A robot whose operator arms it (robot.yaml operator.arm: a gamepad's button) waits for the
  // request, unless a schedule plays the operator's stream.
  const bool operator_arms = robot.op.arm >= 0 && o.commands.empty() && !o.safe_stop;
  if (operator_arms)
    std::printf("waiting for the operator to arm (field '%s')\n",
                robot.fields[static_cast<std::size_t>(robot.op.arm)].name.c_str());
  std::fflush(stdout);
  std::uint64_t allocations = 0;
  loop::RunResult r;
  {
    AllocationScope scope;
    r = loop::Run(robot, data, *loop, ts.all, *clock->clock, {MaxTicks(robot, o, ts), !o.safe_stop && !operator_arms});
    allocations = scope.count();
  }
  done.store(true);
  clock->clock->Stop();
  if (clock->pacer.joinable()) clock->pacer.join();
  status.reset();
  if (!service.stopping) notifier->Stopping();
  const robot::ControllerStatus final_status = loop::StatusOf(*loop);
  for (robot::Transport* t : ts.all) t->Finish(final_status);
  const Status recorded = recorder ? recorder->Stop() : Status{};
  if (!o.quiet && !robot.phases.enable_motors) std::fprintf(stderr, "\n");

  const rt::ProfileReport report = rt::TakeReport(loop->profiler());
  PrintSummary(robot, *loop, r, clock->name, o.safe_stop);
  std::printf("control thread heap allocations during the loop: %llu\n", static_cast<unsigned long long>(allocations));
  for (const robot::Transport* t : ts.all)
    if (const std::string s = t->Summary(); !s.empty()) std::printf("%s\n", s.c_str());
  if (source->trajectory != nullptr && source->trajectory->ticks() > 0)
    std::printf("trajectory tracking RMS %.4f rad, %.4f rad/s (velocity-commanded joints) over %llu ticks\n",
                source->trajectory->rms_tracking_error_rad(), source->trajectory->rms_speed_error_rad_s(),
                static_cast<unsigned long long>(source->trajectory->ticks()));
  if (recorder)
    std::printf(
        "log: %s, %llu records%s, %llu dropped%s%s%s\n", o.record.path.c_str(),
        static_cast<unsigned long long>(recorder->records()), Files(*recorder).c_str(),
        static_cast<unsigned long long>(recorder->dropped()), recorder->failed() ? ", recording stopped: " : "",
        recorder->failed() ? recorder->failure().c_str() : "",
        recorder->failed() ? (", " + std::to_string(recorder->not_written()) + " records not written").c_str() : "");
  std::printf("%s\n%s", rs.Summary().c_str(), rt::FormatText(report).c_str());
  if (!o.profile_json.empty()) {
    std::ofstream f(o.profile_json);
    f << rt::FormatJson(report);
    if (!f) return Fail("--profile: cannot write '" + o.profile_json + "'", 1);
  }
  if (!o.profile_png.empty())
    if (auto s = pbppo::report::PlotLatency(report, o.profile_png, "pbppo-controller tick latency"); !s)
      std::fprintf(stderr, "pbppo-controller: --profile-plot: %s\n", s.error().message.c_str());
  if (!recorded) return Fail(recorded.error().message, 1);
  return r.status == loop::TickStatus::kFailed ? 1 : 0;
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
  return Run(o);
}
