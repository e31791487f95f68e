// The soak, shortened for the test command (label soak): the walking quadruped in one process for
// 150,000 lock-step ticks (150 s of walking, ~13 faults of a seeded schedule, each ended; the robot
// file's recovery rule automatic). bench/soak.sh runs it for 10^6 ticks and more, with plots.
// Every promise of sim_hil/quadruped_soak.hpp holds: no allocation in the controller's ticks, every
// command inside its limits, every stopping fault at the safe state within 3 ticks of being
// detectable, the others not stopping the robot, every stop recovered only by the rule; resident
// memory flat (in the default build; under AddressSanitizer, the same run without memory errors).
// The run is recorded with rotation (files of 12 MiB, the newest 4 kept): each kept file replays on
// its own, bit for bit, from the snapshot it begins with, through stops and re-arms.
#include <doctest/doctest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <set>

#include "runtime/loop/replay.hpp"
#include "runtime/loop/source_files.hpp"
#include "sim_hil/quadruped_soak.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;

TEST_CASE("soak: the walking quadruped, 150,000 ticks under seeded faults - every promise kept, memory flat") {
  sim::SoakOptions o;
  o.ticks = 150'000;
  o.seed = 3;
  o.policy = test::SourcePath("policies/frozen/quadruped_walk/flat.blob");
  o.record = test::ScratchDir("soak") + "/soak.log";
  o.record_options.max_file_bytes = 12u << 20;
  o.record_options.keep_files = 4;
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

  // The log: rotated, the newest four files kept, each replaying alone from its snapshot.
  CHECK(r->record_error.empty());
  CHECK(r->records_dropped == 0);
  REQUIRE(r->record_files > 4);
  CHECK(r->record_files_deleted == r->record_files - 4);
  const robot::RobotModel m = sim::SoakModel(test::QuadrupedRobot());
  std::uint64_t next_tick = 0, replayed = 0, arming = 0;
  for (std::uint32_t k = r->record_files - 4; k < r->record_files; ++k) {
    CAPTURE(k);
    const std::string path = loop::RotatedPath(o.record, k);
    CHECK(std::filesystem::file_size(path) <= o.record_options.max_file_bytes);
    auto log = loop::ReadLog(path);
    REQUIRE_MESSAGE(log.ok(), log.error().message);
    CHECK(log->header.sequence == k);
    CHECK(log->end == (k + 1 == r->record_files ? loop::LogEnd::kStopped : loop::LogEnd::kRotated));
    REQUIRE_FALSE(log->records.empty());
    if (next_tick != 0) CHECK(log->records.front().inputs.tick == next_tick);
    next_tick = log->records.back().outputs.tick + 1;
    loop::SourceFiles files;
    files.policy = o.policy;
    files.self_test = false;
    auto source = loop::LoadSource(m, files);
    REQUIRE_MESSAGE(source.ok(), source.error().message);
    auto replay = loop::Replay(m, *log, source->source.get(), source->hash);
    REQUIRE_MESSAGE(replay.ok(), replay.error().message);
    CHECK_MESSAGE(replay->mismatches == 0, replay->first_mismatch);
    CHECK(replay->compared == replay->ticks);
    replayed += replay->ticks;
    for (const loop::LogOutputs& out : replay->outputs)  // re-arms: ticks arming again after a stop
      if (out.phase == static_cast<std::uint8_t>(loop::Phase::kArming)) ++arming;
  }
  CHECK(next_tick == o.ticks);
  CHECK(arming > 0);  // the replayed files hold stops and re-arms
  std::printf("soak log: %llu records in %u files (%u deleted); the newest 4 replayed alone: %llu ticks, bit for bit\n",
              static_cast<unsigned long long>(r->records), r->record_files, r->record_files_deleted,
              static_cast<unsigned long long>(replayed));
}
