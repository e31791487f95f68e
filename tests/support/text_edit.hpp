// Editing text files in tests: read one, replace a piece of it, and the shipped robot files edited
// in a scratch copy and loaded again (what error the change gives).
#pragma once

#include <doctest/doctest.h>

#include <fstream>
#include <iterator>
#include <string>

#include "runtime/robot/robot_model.hpp"
#include "tests/support/robot_models.hpp"

namespace pbppo::test {

inline std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  REQUIRE_MESSAGE(in.good(), path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// `s` with its first `from` replaced by `to` (which must be there).
inline std::string ReplaceOnce(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  REQUIRE_MESSAGE(at != std::string::npos, from);
  return s.replace(at, from.size(), to);
}

// A scratch copy of a shipped robot's folder (or of `folder`, relative to the source tree) whose
// files are edited one change at a time.
class RobotFileEdits {
 public:
  RobotFileEdits(const std::string& robot, const std::string& scratch, const std::string& folder = "")
      : source_(folder.empty() ? "models/" + robot : folder),
        dir_(CopyRobotFolder(robot, scratch, source_)),
        path_(dir_ + "/robot.yaml") {}
  const std::string& dir() const { return dir_; }
  const std::string& path() const { return path_; }
  // The shipped robot.yaml with `from` replaced by `to`, written and loaded: the error it is
  // refused with (it must be refused).
  std::string Error(const std::string& from, const std::string& to) const { return ErrorIn("robot.yaml", from, to); }
  // The same for another file of the folder (can_map.yaml, ...), put back afterwards.
  std::string ErrorIn(const std::string& file, const std::string& from, const std::string& to) const {
    const std::string original = ReadText(SourcePath(source_ + "/" + file)), path = dir_ + "/" + file;
    std::ofstream(path) << ReplaceOnce(original, from, to);
    auto m = robot::LoadRobotModel(path_);
    std::ofstream(path) << original;
    REQUIRE_FALSE(m.ok());
    return m.error().message;
  }

 private:
  std::string source_, dir_, path_;
};

}  // namespace pbppo::test
