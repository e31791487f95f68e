#include "runtime/loop/runner.hpp"

#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>

namespace pbppo::loop {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<LoopData*> g_loop{nullptr};
std::atomic<rt::TickClock*> g_clock{nullptr};  // stopped by a stop request (robots without shutdown phases)
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<LoopData*>::is_always_lock_free &&
              std::atomic<rt::TickClock*>::is_always_lock_free);

extern "C" void OnStopSignal(int) {
  RequestStop();
}

extern "C" void OnRearmSignal(int) {
  if (LoopData* l = g_loop.load(std::memory_order_relaxed)) l->RequestRearm();
}

}  // namespace

void RequestStop() noexcept {
  g_stop.store(true, std::memory_order_relaxed);
  if (LoopData* l = g_loop.load(std::memory_order_relaxed)) l->RequestStop();
  if (rt::TickClock* c = g_clock.load(std::memory_order_relaxed)) c->Stop();
}

bool StopRequested() noexcept {
  return g_stop.load(std::memory_order_relaxed);
}

void ClearStop() noexcept {
  g_stop.store(false, std::memory_order_relaxed);
}

void InstallStopSignals() {
  struct sigaction sa{};
  sa.sa_handler = OnStopSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

void InstallRearmSignal() {
  struct sigaction sa{};
  sa.sa_handler = OnRearmSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGUSR1, &sa, nullptr);
}

RunResult Run(const robot::RobotModel& m, robot::RobotData& d, LoopData& l,
              std::span<robot::Transport* const> transports, rt::TickClock& clock, const RunOptions& o) noexcept {
  RunResult r;
  // A robot with motors shuts down on its own ticks; one without stops its clock.
  const bool phases = m.phases.enable_motors;
  g_loop.store(&l, std::memory_order_relaxed);
  g_clock.store(phases ? nullptr : &clock, std::memory_order_relaxed);
  if (StopRequested()) l.RequestStop();
  if (o.arm) l.Arm();
  rt::TickTiming t;
  // A robot without phases stops at a signal or at its end field.
  auto stop = [&] { return !phases && (StopRequested() || l.ended()); };
  while (r.status == TickStatus::kRunning) {
    if (stop()) break;
    if (!clock.Wait(t)) break;
    if (stop()) break;
    r.status = Tick(m, d, l, transports, t);
    ++r.ticks;
    if (o.max_ticks != 0 && r.ticks >= o.max_ticks) {
      if (!phases) break;
      l.RequestStop();
    }
  }
  r.stopped = StopRequested();
  r.ended = l.ended();
  if (r.status == TickStatus::kRunning) Shutdown(m, d, l, transports, r.ticks);
  g_clock.store(nullptr, std::memory_order_relaxed);
  g_loop.store(nullptr, std::memory_order_relaxed);
  return r;
}

robot::ControllerStatus StatusOf(const LoopData& l) noexcept {
  const LoopStatus st = l.Status();
  robot::ControllerStatus s;
  s.tick = st.tick;
  s.phase = static_cast<std::uint8_t>(st.phase);
  s.mode = st.mode;
  s.cause = st.any_latched ? 1u << static_cast<unsigned>(st.latched) : 0u;
  s.counts = st.counts;
  s.deadline_misses = l.profiler().deadline_misses();
  const rt::LatencyStats t = l.profiler().histogram(rt::Stage::kTick).Snapshot().Stats();
  s.tick_median_us = static_cast<double>(t.p50_ns) / 1000.0;
  s.tick_max_us = static_cast<double>(t.max_ns) / 1000.0;
  return s;
}

StatusPublisher::StatusPublisher(std::span<robot::Transport* const> transports, const LoopData& loop,
                                 std::int64_t period_ns, Poll poll)
    : thread_([this, transports, &loop, period_ns, poll = std::move(poll)] {
        auto next = std::chrono::steady_clock::now();
        while (!stop_.load()) {
          std::this_thread::sleep_for(std::chrono::milliseconds(10));
          const bool due = std::chrono::steady_clock::now() >= next;
          if (due) {
            next += std::chrono::nanoseconds(period_ns);
            const robot::ControllerStatus status = StatusOf(loop);
            for (robot::Transport* t : transports) t->PublishStatus(status);
          }
          if (poll) poll(loop.Status(), due);
        }
      }) {}

StatusPublisher::~StatusPublisher() {
  stop_.store(true);
  thread_.join();
}

std::thread PaceBySamples(robot::Transport& transport, std::uint32_t stream, rt::LockStepClock& clock,
                          const std::atomic<bool>& done, std::int64_t timeout_ns) {
  return std::thread([&transport, stream, &clock, &done, timeout_ns] {
    std::uint64_t version = 0;
    constexpr std::int64_t kSlice = 50'000'000;  // `done` is seen within 50 ms
    while (!done.load()) {
      const std::uint64_t started = clock.started();
      bool fresh = false;
      for (std::int64_t waited = 0; !fresh && waited < timeout_ns && !done.load(); waited += kSlice)
        fresh = transport.WaitForSample(stream, &version, std::min(kSlice, timeout_ns - waited));
      if (done.load()) break;
      clock.Advance();
      // Wait for the loop to take this tick before allowing the next one.
      while (clock.started() == started && !done.load()) std::this_thread::yield();
    }
  });
}

}  // namespace pbppo::loop
