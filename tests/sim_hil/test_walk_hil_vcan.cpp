// The quadruped walking over SocketCAN (label vcan: inside tests/vm/vcan-vm, or on a host with
// vcan0/vcan1): the same controller and HIL as the native walking tests (test_quadruped_walk_hil),
// ticked in lock-step in one thread, but every frame crosses the kernel's CAN sockets. The VM's
// emulated CPU is about 90 times slower than the host, so the schedule is short: stand, then
// 0.5 m/s forward (docs/quadruped_hil.md).
#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "runtime/loop/schedule.hpp"
#include "sim_hil/quadruped_rig.hpp"
#include "sim_hil/quadruped_scenario.hpp"
#include "tests/support/command_limits.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;

namespace {

std::string Vcan(int i) {
  const char* env = std::getenv(i == 0 ? "PBPPO_VCAN0" : "PBPPO_VCAN1");
  return env != nullptr ? env : (i == 0 ? "vcan0" : "vcan1");
}

}  // namespace

TEST_CASE("walk HIL over vcan: stand, then 0.5 m/s forward tracked within 0.2 m/s, no fall, commands in limits") {
  const robot::RobotModel& m = test::QuadrupedRobot();
  auto s = loop::ParseSchedule(
      "stream: velocity_command\n"
      "phases:\n"
      "  - {name: stand, duration_s: 1.5}\n"
      "  - {name: forward, duration_s: 2.5, command_vx: 0.5}\n",
      "vcan walk", m);
  REQUIRE_MESSAGE(s.ok(), s.error().message);
  auto sc = sim::LoadQuadrupedScenario(test::SourcePath("models/quadruped/scenarios/flat.yaml"), m, m.tick_period_s);
  REQUIRE_MESSAGE(sc.ok(), sc.error().message);
  sim::RigOptions o;
  o.policy = test::SourcePath("policies/frozen/quadruped_walk/flat.blob");
  o.interfaces = {Vcan(0), Vcan(1)};
  o.wait_ns = 500'000'000;  // the VM is slow
  o.command_record_capacity = 60000;
  auto r = sim::QuadrupedRig::Make(m, sc->hil, std::move(*s), o);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  sim::QuadrupedRig& rig = **r;
  REQUIRE(rig.RunSchedule());
  CHECK(rig.status() == loop::TickStatus::kRunning);
  CHECK(rig.loop().supervisor().mode == safety::Mode::kNominal);
  const sim::RigReport rep = rig.Report(1.0);
  CAPTURE(rep.phases[1].mean_abs_error[0]);
  CAPTURE(rep.phases[1].mean_measured[0]);
  CHECK_FALSE(rep.fell);
  CHECK(rep.phases[1].mean_abs_error[0] <= 0.2);
  CHECK(rep.phases[1].mean_abs_error[1] <= 0.2);
  // Every command the controller put on the bus: finite, inside the model's limits.
  CHECK(rig.can().RecordedCommands().size() >= 12 * 3000);
  CHECK(test::CommandsOutsideLimits(m, rig.can().RecordedCommands()) == 0);
}
