// The soak, shortened for the test command (label soak): the walking quadruped in one process for
// 150,000 lock-step ticks (150 s of walking, ~13 faults of a seeded schedule, each ended; the robot
// file's recovery rule automatic). bench/soak.sh runs it for 10^6 ticks and more, with plots.
// Every promise of sim_hil/quadruped_soak.hpp holds: no allocation in the controller's ticks, every
// command inside its limits, every stopping fault at the safe state within 3 ticks of being
// detectable, the others not stopping the robot, every stop recovered only by the rule; resident
// memory flat (in the default build; under AddressSanitizer, the same run without memory errors).
#include <doctest/doctest.h>

#include <cstdio>
#include <set>

#include "sim_hil/quadruped_soak.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;

TEST_CASE("soak: the walking quadruped, 150,000 ticks under seeded faults - every promise kept, memory flat") {
  sim::SoakOptions o;
  o.ticks = 150'000;
  o.seed = 3;
  o.policy = test::SourcePath("policies/frozen/quadruped_walk/flat.blob");
  auto r = sim::RunQuadrupedSoak(test::QuadrupedRobot(), o);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  std::set<sim::SoakFaultKind> kinds;
  std::size_t walking = 0, stopped = 0;
  for (const sim::SoakFault& f : r->faults) {
    std::printf("soak fault: %-20s ticks %7llu-%-7llu %s safe %lld re-armed %lld\n", sim::ToString(f.kind),
                static_cast<unsigned long long>(f.start), static_cast<unsigned long long>(f.end),
                f.while_walking ? "walking" : "stopped", static_cast<long long>(f.safe_tick),
                static_cast<long long>(f.rearm_tick));
    kinds.insert(f.kind);
    if (f.while_walking) ++walking;
    if (f.safe_tick >= 0) ++stopped;
  }
  for (const std::string& v : r->violations) std::printf("soak violation: %s\n", v.c_str());
  std::printf(
      "soak: %llu ticks in %.1f s, %zu faults (%zu while walking), %llu stops, %llu re-arms, %llu falls, "
      "%llu command phases, resident %llu -> %llu KiB\n",
      static_cast<unsigned long long>(r->ticks), r->wall_s, r->faults.size(), walking,
      static_cast<unsigned long long>(r->stops), static_cast<unsigned long long>(r->rearms),
      static_cast<unsigned long long>(r->falls), static_cast<unsigned long long>(r->command_phases),
      static_cast<unsigned long long>(r->rss_kib[1].second), static_cast<unsigned long long>(r->rss_kib.back().second));
  CHECK(r->ticks == o.ticks);
  CHECK(r->violation_count == 0);
  CHECK(r->allocations == 0);
  CHECK(r->commands_outside_limits == 0);
  CHECK(r->falls == 0);
  // The schedule is what it claims: faults of most kinds, most of them while walking, stops recovered.
  CHECK(r->faults.size() >= 10);
  CHECK(kinds.size() == sim::kSoakFaultKinds);
  CHECK(walking == r->faults.size());
  CHECK(stopped >= 8);
  CHECK(r->rearms == r->stops);
  CHECK(r->command_phases > 20);
  // Resident memory flat: after the first tenth, it grows by less than 1 MiB. Not under
  // AddressSanitizer, whose quarantine keeps freed memory resident by design (hundreds of MiB):
  // there the run checks memory errors instead; the default build checks the growth.
  REQUIRE(r->rss_kib.size() > 10);
#if !defined(__SANITIZE_ADDRESS__)
  CHECK(r->rss_kib.back().second <= r->rss_kib[r->rss_kib.size() / 10].second + 1024);
#endif
}
