#include "runtime/rt/rt_setup.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace pbppo::rt {
namespace {

std::string Why(int err) {
  std::string s = std::strerror(err);
  if (err == EPERM || err == ENOMEM)
    s += " (needs root, CAP_SYS_NICE/CAP_IPC_LOCK, or rtprio/memlock limits in /etc/security/limits.conf)";
  return s;
}

// Touches the stack the tick will use so that its pages are resident (and locked).
[[gnu::noinline]] unsigned PrefaultStack(std::size_t bytes) {
  constexpr std::size_t kChunk = 4096;
  volatile unsigned char buf[kChunk];
  for (std::size_t i = 0; i < kChunk; i += 64) buf[i] = 0;
  const unsigned here = buf[0];
  return bytes > kChunk ? PrefaultStack(bytes - kChunk) + here : here;  // not a tail call: frames stay
}

}  // namespace

RtSetupResult SetUpRealTime(const RtOptions& o) {
  RtSetupResult r;
  if (o.lock_memory) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      r.memory_locked = true;
    } else {
      r.warnings.push_back("mlockall(MCL_CURRENT | MCL_FUTURE): " + Why(errno) + "; pages may fault in the tick");
    }
  }
  if (o.prefault_stack_bytes > 0) {
    (void)PrefaultStack(o.prefault_stack_bytes);
    r.stack_prefaulted = true;
  }
  if (o.fifo_priority > 0) {
    const int lo = sched_get_priority_min(SCHED_FIFO), hi = sched_get_priority_max(SCHED_FIFO);
    if (o.fifo_priority < lo || o.fifo_priority > hi) {
      r.warnings.push_back("SCHED_FIFO " + std::to_string(o.fifo_priority) + ": priority outside [" +
                           std::to_string(lo) + ", " + std::to_string(hi) + "]; left at SCHED_OTHER");
    } else {
      sched_param p{};
      p.sched_priority = o.fifo_priority;
      const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
      if (err == 0) {
        r.fifo = true;
        r.priority = o.fifo_priority;
      } else {
        r.warnings.push_back("SCHED_FIFO " + std::to_string(o.fifo_priority) + ": " + Why(err) +
                             "; left at SCHED_OTHER");
      }
    }
  }
  if (o.cpu >= 0) {
    const long cpus = sysconf(_SC_NPROCESSORS_CONF);
    if (o.cpu >= cpus || o.cpu >= CPU_SETSIZE) {
      r.warnings.push_back("CPU affinity " + std::to_string(o.cpu) + ": this machine has " + std::to_string(cpus) +
                           " CPUs; not pinned");
    } else {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(static_cast<std::size_t>(o.cpu), &set);
      const int err = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
      if (err == 0) {
        r.pinned = true;
        r.cpu = o.cpu;
      } else {
        r.warnings.push_back("CPU affinity " + std::to_string(o.cpu) + ": " + std::strerror(err) + "; not pinned");
      }
    }
  }
  return r;
}

std::string RtSetupResult::Summary() const {
  std::string s = "real-time set-up: memory ";
  s += memory_locked ? "locked" : "not locked";
  s += fifo ? ", SCHED_FIFO " + std::to_string(priority) : ", SCHED_OTHER";
  s += pinned ? ", pinned to CPU " + std::to_string(cpu) : ", not pinned";
  for (const auto& w : warnings) s += "\n  warning: " + w;
  return s;
}

}  // namespace pbppo::rt
