// The service manager's notification protocol (systemd's sd_notify, spoken directly): datagrams
// such as "READY=1" to the unix socket named by $NOTIFY_SOCKET, and the watchdog that
// $WATCHDOG_USEC (and $WATCHDOG_PID) ask for. Outside a service (no $NOTIFY_SOCKET) every call is
// a no-op. The socket is opened once at set-up; each message is one sendto from a fixed buffer: no
// allocation, safe from a thread beside the control loop (one sending thread at a time).
//
// Meaning in the controller (docs/service.md): READY=1 once the robot is armed and in its run (or
// hold) phase, so `systemctl start` returns only then; WATCHDOG=1 only while the control loop's
// tick count advances, so a stalled loop is noticed however alive the rest of the process is;
// STOPPING=1 when the stop begins; STATUS= one line of tick, phase and mode.
#pragma once

#include <cstdint>

#include "runtime/core/result.hpp"

namespace pbppo::rt {

class ServiceNotifier {
 public:
  // From the environment. No $NOTIFY_SOCKET: an inactive notifier. A socket that cannot be
  // opened, or a malformed $WATCHDOG_USEC, is an error naming the variable and its value.
  static Result<ServiceNotifier> FromEnvironment();
  ServiceNotifier() = default;
  ServiceNotifier(ServiceNotifier&& o) noexcept;
  ServiceNotifier& operator=(ServiceNotifier&& o) noexcept;
  ServiceNotifier(const ServiceNotifier&) = delete;
  ServiceNotifier& operator=(const ServiceNotifier&) = delete;
  ~ServiceNotifier();

  bool active() const noexcept { return fd_ >= 0; }
  // The watchdog period the manager asked for (0: none).
  std::int64_t watchdog_ns() const noexcept { return watchdog_ns_; }
  // One message; false when it could not be sent (counted in failures()).
  bool Send(const char* message) noexcept;
  bool Ready() noexcept { return Send("READY=1"); }
  bool Stopping() noexcept { return Send("STOPPING=1"); }
  bool Watchdog() noexcept { return Send("WATCHDOG=1"); }
  // "STATUS=" + text (cut at 200 bytes).
  bool Status(const char* text) noexcept;
  std::uint64_t sent() const noexcept { return sent_; }
  std::uint64_t failures() const noexcept { return failures_; }

 private:
  int fd_ = -1;
  // sockaddr_un, kept as bytes to keep <sys/un.h> out of the header.
  alignas(8) unsigned char address_[112] = {};
  unsigned address_size_ = 0;
  std::int64_t watchdog_ns_ = 0;
  std::uint64_t sent_ = 0, failures_ = 0;
};

}  // namespace pbppo::rt
