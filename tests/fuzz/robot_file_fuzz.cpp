// libFuzzer target: any text as a robot file (runtime/robot/robot_model.hpp), read from a copy of
// the shipped quadruped's folder (its CAN map, URDF, layout, DDS messages beside it, and the Go2's
// folder beside that) so that the reader gets past the file's own fields into the pieces it
// names. The file is refused with a message naming it, or loaded into a model whose supervisor
// limits are valid; never a crash or an exception.
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "runtime/robot/robot_model.hpp"

namespace {

namespace fs = std::filesystem;

fs::path Root() {
  return fs::temp_directory_path() / ("pbppo_robot_file_fuzz_" + std::to_string(::getpid()));
}

// The copy's robot.yaml, made once per process and removed at its exit.
const std::string& RobotFile() {
  static const std::string* path = [] {
    const fs::path root = Root();
    fs::remove_all(root);
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(Root(), ec);
    });
    fs::create_directories(root);
    fs::copy(fs::path(PBPPO_SOURCE_DIR) / "models/quadruped", root / "quadruped", fs::copy_options::recursive);
    // A robot file may name the Go2's and the AUV's files beside it (the seeds go2_remote.yaml:
    // ../go2/..., auv_joy.yaml: ../auv/...).
    fs::copy(fs::path(PBPPO_SOURCE_DIR) / "models/go2", root / "go2", fs::copy_options::recursive);
    fs::copy(fs::path(PBPPO_SOURCE_DIR) / "models/auv", root / "auv", fs::copy_options::recursive);
    fs::copy_file(fs::path(PBPPO_SOURCE_DIR) / "models/dds_profile.xml", root / "dds_profile.xml");
    fs::copy(fs::path(PBPPO_SOURCE_DIR) / "models/ros2", root / "ros2", fs::copy_options::recursive);
    return new std::string((root / "quadruped/robot.yaml").string());
  }();
  return *path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pbppo;
  const std::string& path = RobotFile();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  auto m = robot::LoadRobotModel(path);
  if (!m) {
    if (m.error().message.empty()) std::abort();
    return 0;
  }
  if (!safety::ValidateSupervisorModel(m->supervisor_model)) std::abort();
  return 0;
}
