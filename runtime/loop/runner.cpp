#include "runtime/loop/runner.hpp"

#include <signal.h>

#include <atomic>

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
  while (r.status == TickStatus::kRunning) {
    if (!phases && StopRequested()) break;
    if (!clock.Wait(t)) break;
    if (!phases && StopRequested()) break;
    r.status = Tick(m, d, l, transports, t);
    ++r.ticks;
    if (o.max_ticks != 0 && r.ticks >= o.max_ticks) {
      if (!phases) break;
      l.RequestStop();
    }
  }
  r.stopped = StopRequested();
  if (r.status == TickStatus::kRunning) Shutdown(m, d, l, transports, r.ticks);
  g_clock.store(nullptr, std::memory_order_relaxed);
  g_loop.store(nullptr, std::memory_order_relaxed);
  return r;
}

}  // namespace pbppo::loop
