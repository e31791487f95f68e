// Training and deployment build the AUV observation by one code path: an AuvSensorSample filled
// from the task's state (what the HIL publishes), mapped onto the robot's fields as the
// controller's transport does (firmware/auv) and run through the robot's signals, gives the task's
// own observation.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "firmware/auv/auv_transport.hpp"
#include "runtime/robot/observation_builder.hpp"
#include "runtime/robot/signals.hpp"
#include "sim_hil/scenarios/auv_nav_task.hpp"
#include "tests/support/robot_models.hpp"

using namespace pbppo;

namespace {

robot::AuvSensorSample SampleOf(const sim::AuvNavTask& t, bool episode_end) {
  const sim::AuvState& s = t.vehicle();
  robot::AuvSensorSample a;
  a.x_m = s.x_m;
  a.y_m = s.y_m;
  a.depth_m = -s.z_m;
  a.yaw_rad = robot::WrapAngleRad(s.yaw_rad);
  a.surge_mps = s.u_mps;
  a.sway_mps = s.v_mps;
  a.yaw_rate_radps = s.r_radps;
  a.sonar_beams = static_cast<std::uint32_t>(t.sonar_ranges().size());
  for (std::size_t i = 0; i < t.sonar_ranges().size(); ++i) a.sonar_m[i] = static_cast<float>(t.sonar_ranges()[i]);
  a.target_index = t.target_index();
  a.episode_end = episode_end;
  return a;
}

std::uint32_t UlpDistance(float a, float b) {
  std::int32_t ia, ib;
  std::memcpy(&ia, &a, 4);
  std::memcpy(&ib, &b, 4);
  return static_cast<std::uint32_t>(std::abs(ia - ib));
}
}  // namespace

TEST_CASE("auv observation: a sensor sample of the task's state gives the task's observation") {
  auto c = sim::MakeAuvTaskConfig(test::AuvRobot(), "medium");
  REQUIRE_MESSAGE(c.ok(), c.error().message);
  // Every signal of the table, some with history, on top of the shipped layout.
  for (const char* sig : {"yaw", "cos_yaw", "sin_yaw", "x", "y", "depth_error", "clearance", "target_index",
                          "sway_speed", "cos_target_bearing", "sin_target_bearing", "nearest_echo", "target_x",
                          "target_y", "route_bearing", "cos_route_bearing", "sin_route_bearing"}) {
    robot::ObservationElement e;
    e.name = sig;
    e.signal = sig;
    e.scale = 0.3;
    e.offset = 0.1;
    e.clip = 5;
    e.history = 2;
    c->io.observations.push_back(e);
  }
  auto task = sim::AuvNavTask::Create(*c);
  REQUIRE_MESSAGE(task.ok(), task.error().message);
  const auto n = static_cast<std::size_t>(task->observation_size());
  const robot::RobotModel& m = test::AuvRobot();
  auto program = robot::SignalProgram::ForLayout(m, c->io);
  REQUIRE_MESSAGE(program.ok(), program.error().message);
  auto builder = robot::ObservationBuilder::Create(c->io, program->names());
  REQUIRE_MESSAGE(builder.ok(), builder.error().message);
  auto sample_fields = auv::SampleFields::Create(m);
  REQUIRE_MESSAGE(sample_fields.ok(), sample_fields.error().message);
  REQUIRE(builder->observation_size() == n);
  std::vector<std::string> signal_of;  // the signal behind each input
  for (const auto& e : c->io.observations)
    for (std::uint32_t h = 0; h < e.history; ++h) signal_of.push_back(e.signal);
  REQUIRE(signal_of.size() == n);

  std::vector<float> task_obs(n), ctrl_obs(n);
  std::vector<double> fields(m.fields.size(), 0.0), g(program->size());
  task->Reset(5, task_obs.data());
  std::size_t compared = 0, sonar_ulp = 0;
  for (int k = 0; k < 300; ++k) {
    robot::AuvSensorSample s = SampleOf(*task, false);
    const auto& t = c->layout.targets[static_cast<std::size_t>(task->target_index())];
    s.target_x_m = t[0];
    s.target_y_m = t[1];
    s.target_distance_m = std::hypot(t[0] - s.x_m, t[1] - s.y_m);
    s.target_bearing_rad = robot::WrapAngleRad(std::atan2(t[1] - s.y_m, t[0] - s.x_m) - task->vehicle().yaw_rad);
    s.clearance_m = sim::Clearance(task->world(), s.x_m, s.y_m);
    robot::AuvSensorSample planned;  // the route comes from the mission computer (here: the task)
    task->FillSensorSample(planned);
    s.route_bearing_rad = planned.route_bearing_rad;
    sample_fields->Write(s, fields);
    program->Compute(fields, {}, g.data());
    builder->Build(g.data(), k == 0, ctrl_obs.data());
    for (std::size_t i = 0; i < n; ++i) {
      CAPTURE(signal_of[i]);
      if (signal_of[i].rfind("sonar_", 0) == 0) {
        // The sample carries sonar ranges as float (as on the wire): at most one float step apart.
        CHECK(UlpDistance(ctrl_obs[i], task_obs[i]) <= 1);
        sonar_ulp += ctrl_obs[i] != task_obs[i];
      } else if (signal_of[i] == "nearest_echo") {
        // The shortest of those float ranges, scaled.
        CHECK(ctrl_obs[i] == doctest::Approx(task_obs[i]).epsilon(1e-6));
      } else if (signal_of[i] == "cos_yaw" || signal_of[i] == "sin_yaw") {
        // cos/sin of the wrapped yaw (the sample's) against the task's unwrapped yaw.
        CHECK(ctrl_obs[i] == doctest::Approx(task_obs[i]).epsilon(1e-6));
      } else {
        CHECK(ctrl_obs[i] == task_obs[i]);
      }
      ++compared;
    }
    const float a[2] = {static_cast<float>(std::sin(0.05 * k)), static_cast<float>(std::cos(0.03 * k))};
    const auto r = task->Step(a, task_obs.data());
    if (r.terminated || r.truncated) break;
  }
  CHECK(compared > 1000);
  MESSAGE("sonar inputs differing by one float step: " << sonar_ulp);
}
