#include "firmware/auv/controller_loop.hpp"

#include <signal.h>

#include <atomic>

namespace pbppo::firmware {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<rt::TickClock*> g_clock{nullptr};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<rt::TickClock*>::is_always_lock_free);

extern "C" void OnStopSignal(int) {
  RequestLoopStop();
}

}  // namespace

void RequestLoopStop() noexcept {
  g_stop.store(true, std::memory_order_relaxed);
  if (rt::TickClock* c = g_clock.load(std::memory_order_relaxed)) c->Stop();
}
bool LoopStopRequested() noexcept {
  return g_stop.load(std::memory_order_relaxed);
}
void ClearLoopStop() noexcept {
  g_stop.store(false, std::memory_order_relaxed);
}

void InstallLoopSignalHandlers() {
  struct sigaction sa{};
  sa.sa_handler = OnStopSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

LoopResult RunAuvControlLoop(AuvController& controller, AuvLink& link, rt::TickClock& clock,
                             const LoopOptions& options) noexcept {
  LoopResult r;
  rt::TickProfiler& prof = controller.profiler();
  g_clock.store(&clock, std::memory_order_relaxed);
  if (options.arm_at_start) controller.Arm();
  robot::AuvSensorSample sample;
  robot::AuvCommand cmd;
  rt::TickTiming t;
  std::uint64_t tick = 0;
  while (options.max_ticks == 0 || tick < options.max_ticks) {
    if (LoopStopRequested()) break;
    if (!clock.Wait(t)) break;
    if (LoopStopRequested()) break;
    if (t.missed) prof.CountDeadlineMiss();
    prof.Record(rt::Stage::kJitter, t.jitter_ns);
    const std::int64_t t0 = MonotonicNs();
    const bool have = link.Latest(sample);
    const PeerState peer = link.Peer();
    const std::int64_t t1 = MonotonicNs();
    prof.Record(rt::Stage::kReceive, t1 - t0);
    controller.SetLinkState(peer == PeerState::kLost, t.consecutive_misses);
    controller.Tick(have ? &sample : nullptr, t.tick, cmd);
    const std::int64_t t2 = MonotonicNs();
    if (!link.Send(cmd)) ++r.send_failures;
    const std::int64_t t3 = MonotonicNs();
    prof.Record(rt::Stage::kSend, t3 - t2);
    prof.Record(rt::Stage::kTick, t3 - t.wake_ns);
    ++tick;
  }
  r.stopped = LoopStopRequested();
  // Leave the vehicle stopped.
  controller.Disarm();
  controller.ShutdownCommand(tick, cmd);
  if (!link.Send(cmd)) ++r.send_failures;
  g_clock.store(nullptr, std::memory_order_relaxed);
  r.ticks = tick;
  r.final_mode = controller.supervisor().mode;
  return r;
}

}  // namespace pbppo::firmware
