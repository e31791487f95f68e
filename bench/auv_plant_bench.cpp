// Throughput of the AUV plant and navigation task: physics steps/s, control steps/s of the bare
// plant, and task steps/s (Step with random actions, resets included) per layout and integrator.
// Per-thread CPU time, so other load on the machine does not count.
//
//   auv_plant_bench [control_steps]   (default 20000)
#include <time.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "runtime/core/random.hpp"
#include "sim_hil/scenarios/auv_nav_task.hpp"

namespace {

double CpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

const char* Name(pbppo::sim::AuvIntegrator i) {
  return i == pbppo::sim::AuvIntegrator::kRk2 ? "rk2" : "semi_explicit_euler";
}

}  // namespace

int main(int argc, char** argv) {
  const long steps = argc > 1 ? std::atol(argv[1]) : 20000;
  const std::string model = std::string(PBPPO_SOURCE_DIR) + "/models/auv/";
  std::printf("AUV plant/task throughput, %ld control steps per row, per-thread CPU time\n", steps);
  for (auto integ : {pbppo::sim::AuvIntegrator::kRk2, pbppo::sim::AuvIntegrator::kSemiExplicitEuler}) {
    // Bare plant: a varying command, no sonar, no reward.
    auto params = pbppo::sim::LoadAuvParams(model + "auv.yaml");
    if (!params) {
      std::fprintf(stderr, "%s\n", params.error().message.c_str());
      return 1;
    }
    params->integrator = integ;
    auto plant = pbppo::sim::AuvPlant::Create(*params);
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
                params->physics_step_s, params->substeps(), physics / dt, static_cast<double>(steps) / dt);

    for (const char* layout : {"easy", "medium", "hard"}) {
      auto config = pbppo::sim::LoadAuvTaskConfig(model + "auv.yaml", model + "layouts/" + layout + ".yaml",
                                                  model + "io_layout.yaml");
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
      float action[2];
      long episodes = 0;
      std::uint64_t seed = 0;
      task->Reset(seed++, obs.data());
      t0 = CpuSeconds();
      for (long k = 0; k < steps; ++k) {
        action[0] = static_cast<float>(rng.Uniform(-1.0, 1.0));
        action[1] = static_cast<float>(rng.Uniform(-1.0, 1.0));
        const auto r = task->Step(action, obs.data());
        if (r.terminated || r.truncated) {
          task->Reset(seed++, obs.data());
          ++episodes;
        }
      }
      dt = CpuSeconds() - t0;
      std::printf("task  %-20s %-6s: %8.0f control steps/s (%ld episodes ended), %.1f us/step\n", Name(integ), layout,
                  static_cast<double>(steps) / dt, episodes, 1e6 * dt / static_cast<double>(steps));
    }
  }
  return 0;
}
