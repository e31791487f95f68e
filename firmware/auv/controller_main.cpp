// pbppo-controller: the AUV's controller program.
//
//   pbppo-controller --robot models/auv/auv.yaml --policy policies/frozen/auv_nav/auv_nav.blob
//       --transport dds [--io-layout FILE] [--lockstep] [--period-ms MS] [--domain D]
//       [--dds-profile FILE] [--ticks N] [--duration S] [--peer-timeout-s S]
//       [--profile out.json] [--profile-plot out.png] [--rt-priority P] [--cpu C] [--no-mlock]
//       [--status-every-s S] [--quiet]
//
// Start-up loads and validates the robot description, the IO layout and the blob (a blob trained
// for another layout is refused, naming the first difference), opens the DDS link and waits for
// the vehicle, applies the real-time set-up where permitted (warnings otherwise), arms and runs
// receive -> observe -> infer -> supervise -> send every tick, with no allocation in the tick.
// Ticks come from absolute deadlines (free-running; default: the robot's control period) or,
// with --lockstep, from the vehicle: one tick per new sensor sample (a simulator in lock-step);
// if no sample arrives for --lockstep-timeout-ms the tick runs anyway, so a vanished vehicle is
// seen as stale samples. SIGINT/SIGTERM, --ticks, --duration or (lock-step) the vehicle's
// episode end stop the loop; the last command sent is zero speed in e-stop mode.
#include <CLI/CLI.hpp>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>

#include "firmware/auv/auv_controller.hpp"
#include "firmware/auv/controller_loop.hpp"
#include "report/plots.hpp"
#include "runtime/core/alloc_probe.hpp"
#include "runtime/rt/rt_setup.hpp"
#include "runtime/rt/tick_clock.hpp"
#include "runtime/rt/tick_profiler.hpp"
#include "runtime/transport/dds/auv_dds_link.hpp"

namespace {

using namespace pbppo;

// The control loop's view of the DDS link: newest sample from the mailbox, commands into the
// writer's queue, and the peer as the link sees it. No allocation, lock or blocking call.
class DdsAuvLink final : public firmware::AuvLink {
 public:
  DdsAuvLink(dds::AuvDdsLink& link, std::int64_t lost_after_ns) : link_(link), lost_after_ns_(lost_after_ns) {}
  bool Latest(robot::AuvSensorSample& out) noexcept override {
    if (link_.ReadSample(&in_) == 0) return false;
    out = in_.sample;
    last_flags_.store(in_.flags, std::memory_order_relaxed);
    return true;
  }
  bool Send(const robot::AuvCommand& cmd) noexcept override { return link_.PushCommand(cmd); }
  firmware::PeerState Peer() noexcept override {
    const dds::AuvPeerView v = link_.Peer();
    if (v.last_receive_age_ns < 0) return firmware::PeerState::kUnknown;
    if (v.matched_writers == 0 || v.last_receive_age_ns > lost_after_ns_) return firmware::PeerState::kLost;
    return firmware::PeerState::kAlive;
  }

 private:
  dds::AuvDdsLink& link_;
  std::int64_t lost_after_ns_;
  dds::AuvSensorInput in_;
  std::atomic<std::uint32_t> last_flags_{0};
};

int Fail(const std::string& msg, int rc = 2) {
  std::fprintf(stderr, "pbppo-controller: %s\n", msg.c_str());
  return rc;
}

std::string DefaultIoLayout(const std::string& robot_yaml) {
  const auto dir = std::filesystem::path(robot_yaml).parent_path();
  return (dir / "io_layout.yaml").string();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pbppo-controller: runs a frozen policy on the AUV over DDS"};
  std::string robot_yaml, io_yaml, blob, transport = "dds", dds_profile, profile_json, profile_png;
  bool lockstep = false, no_mlock = false, quiet = false;
  double period_ms = 0, duration_s = 0, peer_timeout_s = 30, status_every_s = 1.0, lost_after_s = 2.0;
  int domain = 0, rt_priority = 80, cpu = -1, lockstep_timeout_ms = 500;
  std::int64_t writer_poll_us = -1;
  std::uint64_t max_ticks = 0;
  app.add_option("--robot", robot_yaml, "Robot description (models/auv/auv.yaml)")->required();
  app.add_option("--policy", blob, "Frozen policy blob")->required();
  app.add_option("--transport", transport, "Transport: dds");
  app.add_option("--io-layout", io_yaml, "IO layout (default: io_layout.yaml beside --robot)");
  app.add_flag("--lockstep", lockstep, "One tick per sensor sample (a simulator in lock-step)");
  app.add_option("--lockstep-timeout-ms", lockstep_timeout_ms,
                 "Lock-step: tick anyway after this long without a sample")
      ->check(CLI::Range(1, 600000));
  app.add_option("--period-ms", period_ms, "Free-running tick period (default: the robot's control period)")
      ->check(CLI::Range(0.01, 10000.0));
  app.add_option("--domain", domain, "DDS domain id")->check(CLI::Range(0, 232));
  app.add_option("--dds-profile", dds_profile, "Fast DDS XML profile (default: dds_profile.xml beside --robot)");
  app.add_option("--ticks", max_ticks, "Stop after this many ticks (0: no limit)");
  app.add_option("--duration", duration_s, "Stop after this many seconds (0: no limit)")->check(CLI::Range(0.0, 1e7));
  app.add_option("--peer-timeout-s", peer_timeout_s, "How long to wait for the vehicle at start-up")
      ->check(CLI::Range(0.1, 3600.0));
  app.add_option("--lost-after-s", lost_after_s, "The link reports the vehicle lost after this long without a sample")
      ->check(CLI::Range(0.001, 3600.0));
  app.add_option("--profile", profile_json, "Write the latency profile as JSON");
  app.add_option("--profile-plot", profile_png, "Write the latency histograms as PNG");
  app.add_option("--rt-priority", rt_priority, "SCHED_FIFO priority (0: keep the scheduler)")->check(CLI::Range(0, 99));
  app.add_option("--cpu", cpu, "Pin the control thread to this CPU (-1: no pinning)");
  app.add_flag("--no-mlock", no_mlock, "Do not lock memory");
  app.add_option("--status-every-s", status_every_s, "Status publication and progress line period")
      ->check(CLI::Range(0.05, 3600.0));
  app.add_flag("--quiet", quiet, "No progress line");
  app.add_option("--writer-poll-us", writer_poll_us,
                 "DDS writer thread polls for commands every N us, so the tick makes no system call (0: the "
                 "tick wakes it; default: 200 free-running, 0 in lock-step)")
      ->check(CLI::Range(-1, 1000000));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (transport != "dds") return Fail("--transport: '" + transport + "' unknown (dds)");
  if (io_yaml.empty()) io_yaml = DefaultIoLayout(robot_yaml);
  if (dds_profile.empty()) dds_profile = (std::filesystem::path(robot_yaml).parent_path() / "dds_profile.xml").string();

  // Everything is loaded and checked before anything moves.
  // Sample ages and rate limits are per tick: a tick period other than the control period scales them.
  auto controller = firmware::AuvController::Create(robot_yaml, io_yaml, blob, lockstep ? 0.0 : period_ms * 1e-3);
  if (!controller) return Fail(controller.error().message);
  firmware::AuvController& c = **controller;
  const double period_s = period_ms > 0 ? period_ms * 1e-3 : c.config().control_period_s;

  dds::AuvDdsOptions dopt;
  dopt.domain_id = domain;
  dopt.profile_file = dds_profile;
  dopt.writer_poll_us = writer_poll_us >= 0 ? writer_poll_us : (lockstep ? 0 : 200);
  auto link = dds::AuvDdsLink::Create(dds::AuvDdsRole::kController, dopt);
  if (!link) return Fail(link.error().message);
  if (!quiet) std::fprintf(stderr, "pbppo-controller: waiting for the vehicle on DDS domain %d\n", domain);
  if (!(*link)->WaitForPeer(static_cast<std::int64_t>(peer_timeout_s * 1e9))) {
    return Fail("no vehicle on DDS domain " + std::to_string(domain) + " within " + std::to_string(peer_timeout_s) +
                    " s (--peer-timeout-s)",
                1);
  }

  rt::RtOptions ro;
  ro.lock_memory = !no_mlock;
  ro.fifo_priority = rt_priority;
  ro.cpu = cpu;
  const rt::RtSetupResult rs = rt::SetUpRealTime(ro);
  for (const auto& w : rs.warnings) std::fprintf(stderr, "pbppo-controller: warning: %s\n", w.c_str());

  DdsAuvLink view(**link, static_cast<std::int64_t>(lost_after_s * 1e9));
  firmware::InstallLoopSignalHandlers();
  firmware::LoopOptions lo;
  lo.max_ticks = max_ticks;
  lo.arm_at_start = true;

  std::atomic<bool> done{false};
  std::atomic<bool> episode_end{false};
  std::unique_ptr<rt::TickClock> clock;
  std::thread pacer;
  if (lockstep) {
    auto ls = std::make_unique<rt::LockStepClock>();
    rt::LockStepClock* lsp = ls.get();
    clock = std::move(ls);
    // The vehicle drives the ticks: one per new sample, or one per timeout without a sample.
    pacer = std::thread([&, lsp] {
      std::uint64_t version = 0;
      dds::AuvSensorInput in;
      while (!done.load()) {
        const std::uint64_t started = lsp->started();
        const bool fresh = (*link)->WaitForSample(version, static_cast<std::int64_t>(lockstep_timeout_ms) * 1000000);
        if (done.load()) break;
        if (fresh) version = (*link)->ReadSample(&in);
        lsp->Advance();
        // Wait for the loop to take this tick before allowing the next one.
        while (lsp->started() == started && !done.load()) std::this_thread::yield();
        if (fresh && in.sample.episode_end) {
          episode_end.store(true);
          // Let the tick that answers the final sample finish, then stop.
          std::this_thread::sleep_for(std::chrono::milliseconds(20));
          firmware::RequestLoopStop();
          break;
        }
      }
    });
  } else {
    auto fr = std::make_unique<rt::FreeRunningClock>(static_cast<std::int64_t>(std::llround(period_s * 1e9)));
    fr->Start();
    clock = std::move(fr);
  }

  // Status publication, progress line and --duration on a non-real-time thread.
  std::thread status([&] {
    const auto t0 = std::chrono::steady_clock::now();
    auto next = t0;
    while (!done.load()) {
      next += std::chrono::milliseconds(static_cast<long>(status_every_s * 1000));
      while (!done.load() && std::chrono::steady_clock::now() < next)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      if (done.load()) break;
      const robot::AuvControllerStatus st = c.Status();
      (void)(*link)->PublishStatus(st);
      if (!quiet) {
        std::fprintf(stderr, "\rtick %llu  mode %s  tick median %.1f us  max %.1f us  misses %llu  stale %llu   ",
                     static_cast<unsigned long long>(st.tick), safety::ToString(static_cast<safety::AuvMode>(st.mode)),
                     st.tick_median_us, st.tick_max_us, static_cast<unsigned long long>(st.deadline_misses),
                     static_cast<unsigned long long>(st.stale_samples));
        std::fflush(stderr);
      }
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (duration_s > 0 && elapsed >= duration_s) firmware::RequestLoopStop();
    }
  });

  // Every heap allocation of this (the control) thread while the loop runs is counted.
  std::uint64_t loop_allocations = 0;
  firmware::LoopResult r;
  {
    AllocationScope scope;
    r = firmware::RunAuvControlLoop(c, view, *clock, lo);
    loop_allocations = scope.count();
  }
  done.store(true);
  clock->Stop();
  if (pacer.joinable()) pacer.join();
  status.join();
  (void)(*link)->Flush(1000000000);
  if (!quiet) std::fprintf(stderr, "\n");

  const rt::ProfileReport report = rt::TakeReport(c.profiler());
  const robot::AuvControllerStatus st = c.Status();
  char why[256];
  safety::DescribeAuv(c.last_decision(), why, sizeof why);
  const auto& sup = c.supervisor();
  std::printf("controller: %llu ticks (%s), final mode %s%s%s\n", static_cast<unsigned long long>(r.ticks),
              lockstep ? "lock-step" : "free-running", safety::ToString(sup.mode),
              sup.mode != safety::AuvMode::kNominal ? " - " : "", sup.mode != safety::AuvMode::kNominal ? why : "");
  std::printf("supervisor: ");
  for (std::size_t i = 0; i < safety::kAuvCauseCount; ++i)
    std::printf("%s%s %llu", i ? ", " : "", safety::AuvCauseName(1u << i),
                static_cast<unsigned long long>(sup.cause_ticks[i]));
  std::printf("\n");
  for (const auto& m : c.mode_changes())
    std::printf("mode change: tick %llu: %s\n", static_cast<unsigned long long>(m.tick), m.reason);
  std::printf("control thread heap allocations during the loop: %llu\n",
              static_cast<unsigned long long>(loop_allocations));
  std::printf("link: send failures %llu, stopped by %s\n", static_cast<unsigned long long>(r.send_failures),
              episode_end.load() ? "the vehicle's episode end" : (r.stopped ? "a signal or --duration" : "--ticks"));
  std::printf("%s\n", rs.Summary().c_str());
  std::printf("%s", rt::FormatText(report).c_str());
  (void)st;
  if (!profile_json.empty()) {
    std::ofstream f(profile_json);
    f << rt::FormatJson(report);
    if (!f) return Fail("--profile: cannot write '" + profile_json + "'", 1);
  }
  if (!profile_png.empty()) {
    if (auto s = pbppo::report::PlotLatency(report, profile_png, "pbppo-controller tick latency"); !s)
      std::fprintf(stderr, "pbppo-controller: --profile-plot: %s\n", s.error().message.c_str());
  }
  return 0;
}
