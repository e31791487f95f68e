// Training and deployment build the AUV observation by one code path: the robot's sensor fields
// filled from the task's state as the HIL publishes them (sonar ranges as the wire's floats) and
// run through the robot's signals give the task's own observation.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "runtime/robot/observation_builder.hpp"
#include "runtime/robot/signals.hpp"
#include "sim_hil/scenarios/auv_nav_task.hpp"
#include "tests/support/robot_models.hpp"

using namespace pbppo;

namespace {

double& Field(std::vector<double>& fields, const std::string& name) {
  const int k = test::AuvRobot().FieldIndex(name);
  REQUIRE_MESSAGE(k >= 0, name);
  return fields[static_cast<std::size_t>(k)];
}

// The sample of the task's vehicle as the robot's fields, with its sonar as the wire's floats.
void SampleOf(const sim::AuvNavTask& t, bool episode_end, std::vector<double>& f) {
  const sim::AuvState& s = t.vehicle();
  std::fill(f.begin(), f.end(), 0.0);
  Field(f, "x_m") = s.x_m;
  Field(f, "y_m") = s.y_m;
  Field(f, "depth_m") = -s.z_m;
  Field(f, "yaw_rad") = robot::WrapAngleRad(s.yaw_rad);
  Field(f, "surge_mps") = s.u_mps;
  Field(f, "sway_mps") = s.v_mps;
  Field(f, "yaw_rate_radps") = s.r_radps;
  Field(f, "sonar_beams") = static_cast<double>(t.sonar_ranges().size());
  for (std::uint32_t i = 0; i < t.sonar_ranges().size(); ++i)
    Field(f, robot::ExpandIndex("sonar_{i}_m", i)) = static_cast<float>(t.sonar_ranges()[i]);
  Field(f, "target_index") = t.target_index();
  Field(f, "episode_end") = episode_end ? 1.0 : 0.0;
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
  REQUIRE(builder->observation_size() == n);
  std::vector<std::string> signal_of;  // the signal behind each input
  for (const auto& e : c->io.observations)
    for (std::uint32_t h = 0; h < e.history; ++h) signal_of.push_back(e.signal);
  REQUIRE(signal_of.size() == n);

  std::vector<float> task_obs(n), ctrl_obs(n);
  std::vector<double> fields(m.fields.size(), 0.0), planned(m.fields.size(), 0.0), g(program->size());
  task->Reset(5, task_obs.data());
  std::size_t compared = 0;
  for (int k = 0; k < 300; ++k) {
    SampleOf(*task, false, fields);
    const auto& t = c->layout.targets[static_cast<std::size_t>(task->target_index())];
    const double x = Field(fields, "x_m"), y = Field(fields, "y_m");
    Field(fields, "target_x_m") = t[0];
    Field(fields, "target_y_m") = t[1];
    Field(fields, "target_distance_m") = std::hypot(t[0] - x, t[1] - y);
    Field(fields, "target_bearing_rad") = robot::WrapAngleRad(std::atan2(t[1] - y, t[0] - x) - task->vehicle().yaw_rad);
    Field(fields, "clearance_m") = sim::Clearance(task->world(), x, y);
    task->FillSensorFields(planned);  // the route comes from the mission computer (here: the task)
    Field(fields, "route_bearing_rad") = Field(planned, "route_bearing_rad");
    program->Compute(fields, {}, g.data());
    builder->Build(g.data(), k == 0, ctrl_obs.data());
    for (std::size_t i = 0; i < n; ++i) {
      CAPTURE(signal_of[i]);
      CHECK(ctrl_obs[i] == task_obs[i]);  // bit for bit: sonar as the sample's floats, the yaw wrapped
      ++compared;
    }
    const float a[2] = {static_cast<float>(std::sin(0.05 * k)), static_cast<float>(std::cos(0.03 * k))};
    const auto r = task->Step(a, task_obs.data());
    if (r.terminated || r.truncated) break;
  }
  CHECK(compared > 1000);
}
