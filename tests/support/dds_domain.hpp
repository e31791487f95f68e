// DDS domains for tests: every test takes a domain no other test on this machine holds, so
// ctest's parallel runs (and several participants of one test) do not hear each other. A domain is
// held by an exclusive lock on /tmp/pbppo-dds-domain-N.lock until the process ends; the test
// scripts take theirs the same way (dds_domain in tests/support/checks.sh). Choosing by process id
// alone let two tests that ran together land on one domain now and then, and a test that must not
// hear a peer heard the other's.
#pragma once

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <map>
#include <mutex>
#include <string>

#include "tests/support/test_paths.hpp"

namespace pbppo::test {

// A domain in 10 ... 229 (Fast DDS maps domains above 232 to invalid UDP ports), the same one for
// the same salt within a process, another for another salt; tried from one picked by the process id
// and the salt.
inline int TestDomain(int salt = 0) {
  static std::mutex mu;
  static std::map<int, int> held;  // salt -> domain
  const std::lock_guard<std::mutex> lock(mu);
  if (const auto it = held.find(salt); it != held.end()) return it->second;
  const unsigned start = (static_cast<unsigned>(getpid()) * 7u + static_cast<unsigned>(salt)) % 220u;
  for (unsigned k = 0; k < 220u; ++k) {
    const int domain = 10 + static_cast<int>((start + k) % 220u);
    const std::string path = "/tmp/pbppo-dds-domain-" + std::to_string(domain) + ".lock";
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) continue;
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) {  // the descriptor stays open: held until exit
      held[salt] = domain;
      return domain;
    }
    ::close(fd);
  }
  return 10 + static_cast<int>(start);  // all 220 held: the process id's choice
}

inline std::string DdsProfile() {
  return SourcePath("models/dds_profile.xml");
}

}  // namespace pbppo::test
