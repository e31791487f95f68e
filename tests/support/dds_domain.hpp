// DDS domains for tests: every test process picks its own domain from its process id and a salt,
// so ctest's parallel runs (and several participants of one test) do not hear each other.
#pragma once

#include <unistd.h>

#include <string>

#include "tests/support/test_paths.hpp"

namespace pbppo::test {

// A domain in 10 ... 229 (Fast DDS maps domains above 232 to invalid UDP ports).
inline int TestDomain(int salt = 0) {
  return 10 + static_cast<int>((static_cast<unsigned>(getpid()) * 7u + static_cast<unsigned>(salt)) % 220u);
}

inline std::string DdsProfile() {
  return SourcePath("models/dds_profile.xml");
}

}  // namespace pbppo::test
