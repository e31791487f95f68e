// Record and replay in memory: a recorded run (the AUV's robot, a policy, samples that go stale,
// a stop) replays to bit-identical commands; a log of other files or another policy is refused
// naming what differs; a truncated or corrupt log is refused naming the offset and the field.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/loop/log.hpp"
#include "runtime/loop/policy_source.hpp"
#include "runtime/loop/replay.hpp"
#include "runtime/policy/blob.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/scripted_transport.hpp"

using namespace pbppo;

namespace {

struct Recorded {
  std::string path;
  std::vector<std::uint8_t> bytes;
  std::uint64_t source_hash = 0;
};

policy::PolicySpec Spec(const robot::RobotModel& m, std::uint64_t seed) {
  policy::PolicySpec s =
      policy::MakeRandomSpec({m.io->observation_size(), 32, 32, m.io->action_size()}, policy::Activation::kTanh, seed);
  robot::ApplyLayoutToSpec(*m.io, s);
  return s;
}

// 300 ticks of the AUV: a sample most ticks (a unicycle's pose), none from tick 200 (stale,
// then lost), an e-stop never; the log and its bytes.
Recorded Record(const std::string& name, std::uint64_t seed = 1) {
  const robot::RobotModel& m = test::AuvRobot();
  auto policy = policy::PolicyModel::FromSpec(Spec(m, seed));
  REQUIRE(policy.ok());
  auto source = loop::PolicySource::Create(m, *policy);
  REQUIRE(source.ok());
  robot::RobotData d = robot::MakeRobotData(m);
  auto l = loop::MakeLoopData(m, source->get());
  test::ScriptedTransport t(m);
  robot::Transport* ts[] = {&t};
  Recorded r;
  r.path = test::ScratchDir("log_" + name) + "/run.log";
  r.source_hash = seed;
  const loop::LogHeader h = loop::MakeLogHeader(m, loop::SourceKind::kPolicy, r.source_hash);
  auto rec = loop::Recorder::Open(r.path, m, h);
  REQUIRE_MESSAGE(rec.ok(), rec.error().message);
  l->recorder = rec->get();
  l->Arm();
  std::vector<double> sample(m.fields.size(), 0.0);
  double x = 0, y = 0, yaw = 0;
  std::uint64_t allocations = 0;
  {
    AllocationScope scope;
    for (std::uint64_t k = 0; k < 300; ++k) {
      if (k < 200 && k % 7 != 3) {  // some samples missed: stale for a tick
        sample[static_cast<std::size_t>(m.FieldIndex("tick"))] = static_cast<double>(k);
        sample[static_cast<std::size_t>(m.FieldIndex("x_m"))] = x;
        sample[static_cast<std::size_t>(m.FieldIndex("y_m"))] = y;
        sample[static_cast<std::size_t>(m.FieldIndex("yaw_rad"))] = yaw;
        sample[static_cast<std::size_t>(m.FieldIndex("sonar_beams"))] = 16;
        for (std::uint32_t i = 0; i < 16; ++i)
          sample[static_cast<std::size_t>(m.FieldIndex(robot::ExpandIndex("sonar_{i}_m", i)))] = 3.0 + (k + i) % 9;
        sample[static_cast<std::size_t>(m.FieldIndex("route_bearing_rad"))] = std::sin(0.05 * static_cast<double>(k));
        t.Put(m, 0, sample);
      }
      if (k == 150) t.SetHealth(0, {true, false, false});  // one tick of a degraded link
      if (k == 151) t.SetHealth(0, {});
      if (k == 280) l->RequestStop();
      rt::TickTiming timing;
      timing.tick = k;
      if (loop::Tick(m, d, *l, ts, timing) != loop::TickStatus::kRunning) break;
      yaw += t.command[1] * 0.1;
      x += t.command[0] * std::cos(yaw) * 0.1;
      y += t.command[0] * std::sin(yaw) * 0.1;
    }
    allocations = scope.count();
  }
  CHECK(allocations == 0);
  REQUIRE((*rec)->Stop().ok());
  CHECK((*rec)->dropped() == 0);
  std::ifstream f(r.path, std::ios::binary);
  r.bytes.assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  return r;
}

std::string Refusal(std::vector<std::uint8_t> bytes) {
  auto log = loop::ParseLog(bytes, "run.log");
  REQUIRE_FALSE(log.ok());
  return log.error().message;
}

}  // namespace

TEST_CASE("log: a recorded run replays to bit-identical commands - phases, modes, every command") {
  const Recorded r = Record("replay");
  auto log = loop::ReadLog(r.path);
  REQUIRE_MESSAGE(log.ok(), log.error().message);
  CHECK(log->complete);
  CHECK(log->header.robot == "auv");
  const robot::RobotModel& m = test::AuvRobot();
  auto policy = policy::PolicyModel::FromSpec(Spec(m, 1));
  REQUIRE(policy.ok());
  auto source = loop::PolicySource::Create(m, *policy);
  REQUIRE(source.ok());
  auto replay = loop::Replay(m, *log, source->get(), r.source_hash);
  REQUIRE_MESSAGE(replay.ok(), replay.error().message);
  CHECK(replay->ticks == 281);  // the stop at tick 280 ends an AUV's run at once
  CHECK(replay->compared == replay->ticks);
  CHECK_MESSAGE(replay->mismatches == 0, replay->first_mismatch);
  // The run went through nominal, stale samples and the stop: the replay saw the same.
  const std::string csv = loop::FormatOutputs(m, replay->outputs);
  CHECK(csv.find(",degraded,") != std::string::npos);
  CHECK(csv.rfind("280,done,") != std::string::npos);

  // Another policy: refused before any tick.
  auto other = policy::PolicyModel::FromSpec(Spec(m, 2));
  auto other_source = loop::PolicySource::Create(m, *other);
  auto refused = loop::Replay(m, *log, other_source->get(), 2);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message.find("source_hash") != std::string::npos);
  // The same policy under a wrong claim replays, and differs: the comparison is real.
  auto differs = loop::Replay(m, *log, other_source->get(), r.source_hash);
  REQUIRE(differs.ok());
  CHECK(differs->mismatches > 0);
  CHECK(differs->first_mismatch.find(": command '") != std::string::npos);
  // The robot's files changed.
  robot::RobotModel changed = m;
  changed.hash ^= 1;
  refused = loop::Replay(changed, *log, source->get(), r.source_hash);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message.find("the robot's files changed since the recording") != std::string::npos);
}

TEST_CASE("log: a truncated or corrupt log is refused naming the offset and the field") {
  const Recorded r = Record("corrupt");
  const std::vector<std::uint8_t>& b = r.bytes;
  REQUIRE(b.size() > 1000);
  CHECK(Refusal({b.begin(), b.begin() + 10}) ==
        "run.log: offset 0: header: field 'magic': truncated (needs 16 bytes, 10 left)");
  auto bad = b;
  bad[0] = 'X';
  CHECK(Refusal(bad) == "run.log: offset 0: header: field 'magic': not a pbppo log (PBPPOLOG)");
  bad = b;
  bad[8] = 2;
  CHECK(Refusal(bad) == "run.log: offset 8: header: field 'version': 2 (this reader knows 1)");
  bad = b;
  bad[20] ^= 0x40;  // inside the header's payload
  CHECK(Refusal(bad).find("header: CRC does not match its payload") != std::string::npos);
  // The first record starts after the header; flip a byte inside it.
  auto log = loop::ParseLog(b, "run.log");
  REQUIRE(log.ok());
  const std::size_t first = log->records[0].offset;
  bad = b;
  bad[first + 9] ^= 0x01;
  CHECK(Refusal(bad) ==
        "run.log: offset " + std::to_string(first) + ": record 0 (inputs): CRC does not match the record");
  // Cut inside the third record's payload, and at a record boundary.
  const std::size_t third = log->records[2].offset;
  const std::string cut = Refusal({b.begin(), b.begin() + static_cast<long>(third) + 12});
  CHECK(cut.find("run.log: offset " + std::to_string(third + 5) + ": record 2 (inputs): field 'payload': truncated") ==
        0);
  CHECK(Refusal({b.begin(), b.begin() + static_cast<long>(third)}) ==
        "run.log: offset " + std::to_string(third) + ": end: no end record: the log is truncated");
}

TEST_CASE("log: a log cut short (a full disk) is read up to its last whole record, and those replay bit for bit") {
  const Recorded r = Record("cut");
  const std::vector<std::uint8_t>& b = r.bytes;
  auto whole = loop::ParseLog(b, "run.log");
  REQUIRE(whole.ok());
  const std::size_t n = whole->records.size();
  REQUIRE(n > 100);
  const robot::RobotModel& m = test::AuvRobot();
  auto policy = policy::PolicyModel::FromSpec(Spec(m, 1));
  REQUIRE(policy.ok());
  auto source = loop::PolicySource::Create(m, *policy);
  REQUIRE(source.ok());
  // Cut inside record 100's payload, inside its length field, and at its start (a boundary).
  const std::size_t at = whole->records[100].offset;
  for (std::size_t extra : {std::size_t{12}, std::size_t{3}, std::size_t{0}}) {
    CAPTURE(extra);
    const std::vector<std::uint8_t> cut(b.begin(), b.begin() + static_cast<long>(at + extra));
    // Read strictly, it is refused as before.
    CHECK_FALSE(loop::ParseLog(cut, "run.log").ok());
    auto log = loop::ParseLog(cut, "run.log", loop::LogTail::kAcceptCut);
    REQUIRE_MESSAGE(log.ok(), log.error().message);
    CHECK_FALSE(log->complete);
    CHECK(log->records.size() == 100);
    CHECK(log->cut_at == (extra == 0 ? cut.size() : at));
    if (extra == 0) {
      CHECK(log->cut_reason == "no end record after record 99");
    } else {
      // Inside the length field the record's type is not read yet; inside the payload it is.
      const std::string type = whole->records[100].type == 1 ? "inputs" : "outputs";
      const std::string where = extra == 3 ? "record 100:" : "record 100 (" + type + "):";
      CHECK(log->cut_reason.rfind("the file ends inside " + where, 0) == 0);
      CHECK(log->cut_reason.find(std::to_string(cut.size() - at) + " are left") != std::string::npos);
    }
    auto replay = loop::Replay(m, *log, source->get(), r.source_hash);
    REQUIRE_MESSAGE(replay.ok(), replay.error().message);
    CHECK(replay->compared > 40);
    CHECK_MESSAGE(replay->mismatches == 0, replay->first_mismatch);
  }
  // Damage before the end is refused even when a cut is accepted.
  auto bad = b;
  bad[whole->records[50].offset + 9] ^= 0x01;
  const std::vector<std::uint8_t> bad_cut(bad.begin(), bad.begin() + static_cast<long>(at + 12));
  auto refused = loop::ParseLog(bad_cut, "run.log", loop::LogTail::kAcceptCut);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message.find("record 50 (") != std::string::npos);
  CHECK(refused.error().message.find("CRC does not match the record") != std::string::npos);
}
