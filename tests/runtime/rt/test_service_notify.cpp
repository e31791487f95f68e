// The service manager's notifications (runtime/rt/service_notify.hpp) against a real unix datagram
// socket standing in for systemd's: the messages arrive as sent (a path and an abstract socket),
// the watchdog period is read from WATCHDOG_USEC only for this process, outside a service nothing
// is sent, bad variables are refused naming them, and sending allocates nothing.
#include <doctest/doctest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <string>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/rt/service_notify.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;
using namespace pbppo::rt;

namespace {

struct Env {
  explicit Env(std::initializer_list<std::pair<const char*, const char*>> vars) {
    for (const char* n : {"NOTIFY_SOCKET", "WATCHDOG_USEC", "WATCHDOG_PID"}) unsetenv(n);
    for (const auto& [n, v] : vars) setenv(n, v, 1);
  }
  ~Env() {
    for (const char* n : {"NOTIFY_SOCKET", "WATCHDOG_USEC", "WATCHDOG_PID"}) unsetenv(n);
  }
};

// The manager's end: a bound datagram socket (a path, or "@name": abstract).
struct Manager {
  explicit Manager(const std::string& where) {
    fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::memcpy(a.sun_path, where.data(), where.size());
    if (where[0] == '@')
      a.sun_path[0] = '\0';
    else
      unlink(where.c_str());
    REQUIRE(bind(fd, reinterpret_cast<sockaddr*>(&a),
                 static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + where.size())) == 0);
  }
  ~Manager() { close(fd); }
  std::string Next() {
    char buf[512];
    const ssize_t n = recv(fd, buf, sizeof buf, MSG_DONTWAIT);
    return n < 0 ? std::string("(nothing)") : std::string(buf, static_cast<std::size_t>(n));
  }
  int fd = -1;
};

}  // namespace

TEST_CASE("service notify: messages reach the manager's socket, a path or an abstract one") {
  const std::string path = test::ScratchDir("service_notify") + "/notify";
  const std::string abstract = "@pbppo-test-notify-" + std::to_string(getpid());
  for (const std::string& where : {path, abstract}) {
    Manager m(where);
    const std::string pid = std::to_string(getpid());
    Env env({{"NOTIFY_SOCKET", where.c_str()}, {"WATCHDOG_USEC", "500000"}, {"WATCHDOG_PID", pid.c_str()}});
    auto n = ServiceNotifier::FromEnvironment();
    REQUIRE_MESSAGE(n.ok(), n.error().message);
    CHECK(n->active());
    CHECK(n->watchdog_ns() == 500'000'000);
    std::uint64_t allocations = 0;
    {
      AllocationScope scope;
      CHECK(n->Ready());
      CHECK(n->Watchdog());
      CHECK(n->Status("tick 12, phase run, mode nominal"));
      CHECK(n->Stopping());
      allocations = scope.count();
    }
    CHECK(allocations == 0);
    CHECK(m.Next() == "READY=1");
    CHECK(m.Next() == "WATCHDOG=1");
    CHECK(m.Next() == "STATUS=tick 12, phase run, mode nominal");
    CHECK(m.Next() == "STOPPING=1");
    CHECK(m.Next() == "(nothing)");
    CHECK(n->sent() == 4);
    CHECK(n->failures() == 0);
  }
}

TEST_CASE("service notify: outside a service nothing is sent, and another process's watchdog is not ours") {
  {
    Env env({});
    auto n = ServiceNotifier::FromEnvironment();
    REQUIRE(n.ok());
    CHECK_FALSE(n->active());
    CHECK(n->Ready());
    CHECK(n->sent() == 0);
  }
  const std::string path = test::ScratchDir("service_notify_pid") + "/notify";
  Manager m(path);
  Env env({{"NOTIFY_SOCKET", path.c_str()}, {"WATCHDOG_USEC", "1000000"}, {"WATCHDOG_PID", "1"}});
  auto n = ServiceNotifier::FromEnvironment();
  REQUIRE(n.ok());
  CHECK(n->active());
  CHECK(n->watchdog_ns() == 0);
  // A manager that went away: counted, not fatal.
  unlink(path.c_str());
  CHECK_FALSE(n->Ready());
  CHECK(n->failures() == 1);
}

TEST_CASE("service notify: malformed variables are refused naming them and their value") {
  const std::string path = test::ScratchDir("service_notify_bad") + "/notify";
  Manager m(path);
  for (const char* w : {"abc", "0", "-5", "12x", "99999999999999999999"}) {
    Env env({{"NOTIFY_SOCKET", path.c_str()}, {"WATCHDOG_USEC", w}});
    auto n = ServiceNotifier::FromEnvironment();
    REQUIRE_FALSE(n.ok());
    CHECK(n.error().message == std::string("WATCHDOG_USEC '") + w + "': not a period in microseconds (1 to 86400e6)");
  }
  Env env({{"NOTIFY_SOCKET", "relative/socket"}});
  auto n = ServiceNotifier::FromEnvironment();
  REQUIRE_FALSE(n.ok());
  CHECK(n.error().message.find("NOTIFY_SOCKET 'relative/socket'") == 0);
}
