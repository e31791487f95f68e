#include "runtime/rt/service_notify.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace pbppo::rt {

static_assert(sizeof(sockaddr_un) <= 112);

Result<ServiceNotifier> ServiceNotifier::FromEnvironment() {
  ServiceNotifier n;
  const char* path = std::getenv("NOTIFY_SOCKET");
  if (path == nullptr || path[0] == '\0') return n;
  const std::size_t len = std::strlen(path);
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  if ((path[0] != '/' && path[0] != '@') || len >= sizeof a.sun_path)
    return MakeError(ErrorCode::kInvalidValue, std::string("NOTIFY_SOCKET '") + path +
                                                   "': not a socket path (absolute, or '@' for an abstract one)");
  std::memcpy(a.sun_path, path, len);
  if (path[0] == '@') a.sun_path[0] = '\0';  // the abstract namespace
  n.address_size_ = static_cast<unsigned>(offsetof(sockaddr_un, sun_path) + len);
  std::memcpy(n.address_, &a, sizeof a);
  if (const char* w = std::getenv("WATCHDOG_USEC"); w != nullptr && w[0] != '\0') {
    char* end = nullptr;
    errno = 0;
    const unsigned long long us = std::strtoull(w, &end, 10);
    if (errno != 0 || end == w || *end != '\0' || us == 0 || us > 86400ULL * 1000000ULL)
      return MakeError(ErrorCode::kInvalidValue,
                       std::string("WATCHDOG_USEC '") + w + "': not a period in microseconds (1 to 86400e6)");
    const char* pid = std::getenv("WATCHDOG_PID");
    // The watchdog is this process's only where WATCHDOG_PID names it (or is absent).
    if (pid == nullptr || std::strtoll(pid, nullptr, 10) == static_cast<long long>(getpid()))
      n.watchdog_ns_ = static_cast<std::int64_t>(us) * 1000;
  }
  n.fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (n.fd_ < 0)
    return MakeError(ErrorCode::kIo, std::string("NOTIFY_SOCKET '") + path + "': socket: " + std::strerror(errno));
  return n;
}

ServiceNotifier::ServiceNotifier(ServiceNotifier&& o) noexcept {
  *this = std::move(o);
}

ServiceNotifier& ServiceNotifier::operator=(ServiceNotifier&& o) noexcept {
  if (this == &o) return *this;
  if (fd_ >= 0) ::close(fd_);
  fd_ = o.fd_;
  o.fd_ = -1;
  std::memcpy(address_, o.address_, sizeof address_);
  address_size_ = o.address_size_;
  watchdog_ns_ = o.watchdog_ns_;
  sent_ = o.sent_;
  failures_ = o.failures_;
  return *this;
}

ServiceNotifier::~ServiceNotifier() {
  if (fd_ >= 0) ::close(fd_);
}

bool ServiceNotifier::Send(const char* message) noexcept {
  if (fd_ < 0) return true;
  const ssize_t n = ::sendto(fd_, message, std::strlen(message), MSG_NOSIGNAL,
                             reinterpret_cast<const sockaddr*>(address_), static_cast<socklen_t>(address_size_));
  if (n < 0) {
    ++failures_;
    return false;
  }
  ++sent_;
  return true;
}

bool ServiceNotifier::Status(const char* text) noexcept {
  char buf[208];
  std::snprintf(buf, sizeof buf, "STATUS=%.200s", text);
  return Send(buf);
}

}  // namespace pbppo::rt
