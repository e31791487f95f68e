// Throughput of the AUV plant and navigation task: physics steps/s, control steps/s of the bare
// plant, and task steps/s (Step with random actions, resets included) per layout and integrator.
// Per-thread CPU time, so other load on the machine does not count. Last, the route planner's
// pieces (chart clearances, adding a sonar return to the map, a replan) on the hard layout.
//
//   auv_plant_bench [control_steps]   (default 20000)
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/cpu_time.hpp"
#include "runtime/core/random.hpp"
#include "sim_hil/scenarios/auv_nav_task.hpp"

namespace {

using pbppo::bench::CpuSeconds;
using pbppo::bench::Median;

const char* Name(pbppo::sim::AuvIntegrator i) {
  return i == pbppo::sim::AuvIntegrator::kRk2 ? "rk2" : "semi_explicit_euler";
}

// The route planner's pieces on the hard layout (0.25 m grid): the chart's clearances (once per
// task), one sonar return added to the map, and one replan (Solve), each the median of 31 runs.
int RouteBench(const pbppo::robot::RobotModel& robot) {
  auto hard = pbppo::sim::MakeAuvTaskConfig(robot, "hard");
  if (!hard) {
    std::fprintf(stderr, "%s\n", hard.error().message.c_str());
    return 1;
  }
  const auto* layout = &hard->layout;
  const auto& w = layout->world;
  const auto& goal = layout->targets.back();
  pbppo::sim::GeodesicField chart(w.arena, 0.25), route(w.arena, 0.25);
  std::vector<double> set, add, solve;
  pbppo::Rng rng(3);
  for (int k = 0; k < 31; ++k) {
    double t0 = CpuSeconds();
    chart.SetObstacles(w);
    set.push_back(CpuSeconds() - t0);
    route.CopyObstacles(chart);
    t0 = CpuSeconds();
    for (int p = 0; p < 100; ++p) route.AddPoint(rng.Uniform(5.0, 35.0), rng.Uniform(5.0, 35.0), 1.2 + 2.0 + 0.25);
    add.push_back((CpuSeconds() - t0) / 100);
    t0 = CpuSeconds();
    route.Solve(1.2, goal[0], goal[1], 2.0, 4.0);
    solve.push_back(CpuSeconds() - t0);
  }
  std::printf("route hard (%dx%d nodes): chart clearances %.2f ms, add a return %.1f us, replan %.2f ms (medians)\n",
              chart.nx(), chart.ny(), 1e3 * Median(set), 1e6 * Median(add), 1e3 * Median(solve));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const long steps = argc > 1 ? std::atol(argv[1]) : 20000;
  auto robot = pbppo::robot::LoadRobotModel(std::string(PBPPO_SOURCE_DIR) + "/models/auv/robot.yaml");
  if (!robot) {
    std::fprintf(stderr, "%s\n", robot.error().message.c_str());
    return 1;
  }
  std::printf("AUV plant/task throughput, %ld control steps per row, per-thread CPU time\n", steps);
  for (auto integ : {pbppo::sim::AuvIntegrator::kRk2, pbppo::sim::AuvIntegrator::kSemiExplicitEuler}) {
    // Bare plant: a varying command, no sonar, no reward.
    auto hard = pbppo::sim::MakeAuvTaskConfig(*robot, "hard");
    if (!hard) {
      std::fprintf(stderr, "%s\n", hard.error().message.c_str());
      return 1;
    }
    pbppo::sim::AuvParams params = hard->plant;
    params.integrator = integ;
    auto plant = pbppo::sim::AuvPlant::Create(params);
    if (!plant) {
      std::fprintf(stderr, "%s\n", plant.error().message.c_str());
      return 1;
    }
    plant->Reset(pbppo::sim::AuvPose{20, 20, -5, 0});
    pbppo::Rng rng(1);
    double t0 = CpuSeconds();
    for (long k = 0; k < steps; ++k) {
      plant->SetCommand(rng.Uniform(0.0, 1.5), rng.Uniform(-0.5, 0.5));
      plant->AdvanceControlPeriod();
    }
    double dt = CpuSeconds() - t0;
    const double physics = static_cast<double>(plant->physics_steps());
    std::printf("plant %-20s physics step %.3f s x %d: %9.0f physics steps/s, %8.0f control steps/s\n", Name(integ),
                params.physics_step_s, params.substeps(), physics / dt, static_cast<double>(steps) / dt);

    for (const char* layout : {"easy", "medium", "hard"}) {
      auto config = pbppo::sim::MakeAuvTaskConfig(*robot, layout);
      if (!config) {
        std::fprintf(stderr, "%s\n", config.error().message.c_str());
        return 1;
      }
      config->plant.integrator = integ;
      auto task = pbppo::sim::AuvNavTask::Create(*config);
      if (!task) {
        std::fprintf(stderr, "%s\n", task.error().message.c_str());
        return 1;
      }
      std::vector<float> obs(static_cast<std::size_t>(task->observation_size()));
      std::uint64_t seed = 0;
      task->Reset(seed++, obs.data());
      t0 = CpuSeconds();
      const long episodes = pbppo::sim::StepRandomly(*task, rng, steps, obs.data(), &seed);
      dt = CpuSeconds() - t0;
      std::printf("task  %-20s %-6s: %8.0f control steps/s (%ld episodes ended), %.1f us/step\n", Name(integ), layout,
                  static_cast<double>(steps) / dt, episodes, 1e6 * dt / static_cast<double>(steps));
    }
  }
  return RouteBench(*robot);
}
