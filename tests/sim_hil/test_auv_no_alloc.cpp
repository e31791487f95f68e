// After set-up, our code in the AUV task (controller, integrator, sonar, reward, observation,
// reset) allocates nothing. Simbody itself (Debian 3.7) allocates two small temporaries in every
// realize(Stage::Acceleration) (measured: none in Position, Velocity or Dynamics; its
// calcAccelerationIgnoringConstraints makes 11), so the count must be exactly two per
// acceleration realisation: RK2 realises twice per physics step, semi-explicit Euler once.
// The simulator thread is not the controller's real-time thread; the controller side is proven
// allocation-free by the runtime's own tests.
#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/core/random.hpp"
#include "sim_hil/scenarios/auv_nav_task.hpp"
#include "tests/support/robot_models.hpp"

TEST_CASE("auv task: Step and Reset allocate nothing beyond Simbody's own two per realisation") {
  REQUIRE(pbppo::AllocationCountingActive());
  auto config = pbppo::sim::MakeAuvTaskConfig(pbppo::test::AuvRobot(), "hard");
  REQUIRE(config.ok());
  REQUIRE(config->plant.integrator == pbppo::sim::AuvIntegrator::kRk2);
  auto task = pbppo::sim::AuvNavTask::Create(*config);
  REQUIRE(task.ok());
  std::vector<float> obs(static_cast<std::size_t>(task->observation_size()));
  pbppo::Rng rng(9);
  float action[2] = {0.0f, 0.0f};
  task->Reset(0, obs.data());
  for (int k = 0; k < 50; ++k) (void)task->Step(action, obs.data());  // warm-up
  std::uint64_t seed = 1;
  const std::uint64_t physics_before = task->physics_steps();
  pbppo::AllocationScope scope;
  const long episodes = pbppo::sim::StepRandomly(*task, rng, 5000, obs.data(), &seed);
  const std::uint64_t count = scope.count();
  const std::uint64_t realizations = 2 * (task->physics_steps() - physics_before);
  CHECK(realizations == static_cast<std::uint64_t>(2 * config->plant.substeps() * 5000));
  CHECK(count == 2 * realizations);
  CHECK(episodes > 0);
}
