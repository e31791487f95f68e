#include "runtime/robot/find_robot.hpp"

#include <cstdlib>
#include <filesystem>
#include <set>
#include <system_error>

namespace pbppo::robot {
namespace fs = std::filesystem;

namespace {

bool IsName(const std::string& s) {
  if (s.empty() || s.size() > 64) return false;
  for (const char c : s)
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-'))
      return false;
  return s[0] != '-';
}

bool IsFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

}  // namespace

std::vector<std::string> RobotSearchPath() {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("PBPPO_ROBOT_PATH"); env != nullptr) {
    const std::string s(env);
    std::size_t start = 0;
    while (start <= s.size()) {
      const std::size_t end = std::min(s.find(':', start), s.size());
      if (end > start) dirs.push_back(s.substr(start, end - start));
      start = end + 1;
    }
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec)
    dirs.push_back((exe.parent_path().parent_path() / "share" / "pbppo-rt" / "robots").lexically_normal().string());
  dirs.push_back("models");
  return dirs;
}

Result<std::string> FindRobot(const std::string& arg) {
  const bool path = arg.find('/') != std::string::npos || (arg.size() > 5 && arg.ends_with(".yaml"));
  if (path) {
    std::error_code ec;
    if (fs::is_directory(arg, ec)) {
      const fs::path p = fs::path(arg) / "robot.yaml";
      if (!IsFile(p)) return MakeError(ErrorCode::kIo, "robot '" + arg + "': a folder without a robot.yaml");
      return p.string();
    }
    return arg;  // the robot file's reader names a missing file
  }
  if (!IsName(arg))
    return MakeError(
        ErrorCode::kInvalidValue,
        "robot '" + arg + "': neither a robot file, a folder, nor a robot's name (letters, digits, '_', '-')");
  const std::vector<std::string> dirs = RobotSearchPath();
  for (const std::string& d : dirs)
    if (const fs::path p = fs::path(d) / arg / "robot.yaml"; IsFile(p)) return p.string();
  std::string where, known;
  std::set<std::string> names;
  for (const std::string& d : dirs) {
    where += (where.empty() ? "" : ", ") + d;
    std::error_code ec;
    for (fs::directory_iterator it(d, ec), end; !ec && it != end; it.increment(ec))
      if (IsFile(it->path() / "robot.yaml")) names.insert(it->path().filename().string());
  }
  for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
  return MakeError(ErrorCode::kIo, "robot '" + arg + "': no robot of that name in " + where +
                                       (known.empty() ? " (none there)" : " (robots there: " + known + ")"));
}

}  // namespace pbppo::robot
