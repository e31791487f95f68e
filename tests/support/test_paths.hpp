// Paths the tests use: the source tree (shipped data) and a scratch folder in the build tree.
#pragma once

#include <filesystem>
#include <string>

namespace pbppo::test {

inline std::string SourcePath(const std::string& rel) {
  return std::string(PBPPO_SOURCE_DIR) + "/" + rel;
}

// A fresh, empty folder for one test case.
inline std::string ScratchDir(const std::string& name) {
  const std::filesystem::path p = std::filesystem::path(PBPPO_SCRATCH_DIR) / name;
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p.string();
}

}  // namespace pbppo::test
