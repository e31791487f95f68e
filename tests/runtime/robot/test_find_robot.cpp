// Robots by name (runtime/robot/find_robot.hpp): paths pass through, a folder means its robot.yaml,
// names are looked up in $PBPPO_ROBOT_PATH first, then beside the program, then ./models; unknown
// and malformed names are refused naming where they were looked for and what is there.
#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "runtime/robot/find_robot.hpp"
#include "runtime/robot/robot_model.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;
using namespace pbppo::robot;
namespace fs = std::filesystem;

namespace {

// Sets an environment variable for one scope.
struct ScopedEnv {
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old, had_ = true;
    setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (had_)
      setenv(name_, old_.c_str(), 1);
    else
      unsetenv(name_);
  }
  const char* name_;
  std::string old_;
  bool had_ = false;
};

void Touch(const fs::path& p) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << "robot: x\n";
}

}  // namespace

TEST_CASE("find robot: paths are paths, a folder means its robot.yaml") {
  CHECK(*FindRobot("models/auv/robot.yaml") == "models/auv/robot.yaml");
  CHECK(*FindRobot("robot.yaml") == "robot.yaml");
  CHECK(*FindRobot("/nowhere/x.yaml") == "/nowhere/x.yaml");  // the reader names a missing file
  const std::string dir = test::ScratchDir("find_robot_dir");
  auto none = FindRobot(dir);
  REQUIRE_FALSE(none.ok());
  CHECK(none.error().message.find("a folder without a robot.yaml") != std::string::npos);
  Touch(fs::path(dir) / "robot.yaml");
  CHECK(*FindRobot(dir) == dir + "/robot.yaml");
}

TEST_CASE("find robot: names from PBPPO_ROBOT_PATH in order, then the source tree's models") {
  const std::string a = test::ScratchDir("find_robot_a"), b = test::ScratchDir("find_robot_b");
  Touch(fs::path(b) / "mine" / "robot.yaml");
  Touch(fs::path(a) / "both" / "robot.yaml");
  Touch(fs::path(b) / "both" / "robot.yaml");
  const ScopedEnv env("PBPPO_ROBOT_PATH", a + "::" + b);  // an empty entry is skipped
  CHECK(*FindRobot("mine") == b + "/mine/robot.yaml");
  CHECK(*FindRobot("both") == a + "/both/robot.yaml");  // the first folder wins
  const auto path = RobotSearchPath();
  REQUIRE(path.size() == 4);
  CHECK(path[0] == a);
  CHECK(path[1] == b);
  CHECK(path[2].ends_with("share/pbppo-rt/robots"));
  CHECK(path[3] == "models");
  // From the source tree, the shipped robots by name, loaded as by path.
  const fs::path cwd = fs::current_path();
  fs::current_path(PBPPO_SOURCE_DIR);
  auto auv = LoadRobotModel("auv");
  fs::current_path(cwd);
  REQUIRE_MESSAGE(auv.ok(), auv.error().message);
  CHECK(auv->name == "auv");
  CHECK(auv->path == "models/auv/robot.yaml");
}

TEST_CASE("find robot: unknown and malformed names are refused, naming the folders and the robots there") {
  const std::string a = test::ScratchDir("find_robot_unknown");
  Touch(fs::path(a) / "zeta" / "robot.yaml");
  Touch(fs::path(a) / "alpha" / "robot.yaml");
  fs::create_directories(fs::path(a) / "not_a_robot");
  const ScopedEnv env("PBPPO_ROBOT_PATH", a);
  auto r = FindRobot("go3");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().code == ErrorCode::kIo);
  CHECK(r.error().message.find("robot 'go3': no robot of that name in " + a) == 0);
  // Sorted, from every folder searched (./models may add the shipped robots between them).
  CHECK(r.error().message.find("(robots there: alpha, ") != std::string::npos);
  CHECK(r.error().message.ends_with(", zeta)"));
  CHECK(r.error().message.find("not_a_robot") == std::string::npos);
  auto m = LoadRobotModel("go3");
  REQUIRE_FALSE(m.ok());
  CHECK(m.error().message.find("go3") != std::string::npos);
  for (const char* bad : {"", "-x", "a b", "a;rm", "..", "\xc3\xa9"}) {
    auto b = FindRobot(bad);
    REQUIRE_FALSE(b.ok());
    CHECK(b.error().code == ErrorCode::kInvalidValue);
    CHECK(b.error().message.find("neither a robot file, a folder, nor a robot's name") != std::string::npos);
  }
}
