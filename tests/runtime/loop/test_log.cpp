// Record and replay in memory: a recorded run (the AUV's robot, a policy, samples that go stale,
// a stop) replays to bit-identical commands; a log of other files or another policy is refused
// naming what differs; a truncated or corrupt log is refused naming the offset and the field; a
// write that fails or a file removed while recording stops the recording at once, the file valid.
#include <doctest/doctest.h>
#include <sys/resource.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/core/crc32.hpp"
#include "runtime/loop/log.hpp"
#include "runtime/loop/policy_source.hpp"
#include "runtime/loop/replay.hpp"
#include "runtime/loop/state_bytes.hpp"
#include "runtime/policy/blob.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/scripted_transport.hpp"
#include "tests/support/test_paths.hpp"
#include "tests/support/text_edit.hpp"

using namespace pbppo;

namespace {

struct Recorded {
  std::string path;
  std::vector<std::uint8_t> bytes;
  std::uint64_t source_hash = 0;
  std::string stop_error;  // Recorder::Stop's, if it failed
  std::string failure;     // Recorder::failure(), if it failed
  std::uint64_t records = 0, not_written = 0;
  std::uint32_t files = 0, deleted = 0;  // rotation
};

// Called after each tick with the tick's number and the recorder (inside the count of the tick's
// allocations: it allocates nothing).
using EachTick = std::function<void(std::uint64_t, const loop::Recorder&)>;

policy::PolicySpec Spec(const robot::RobotModel& m, std::uint64_t seed) {
  policy::PolicySpec s =
      policy::MakeRandomSpec({m.io->observation_size(), 32, 32, m.io->action_size()}, policy::Activation::kTanh, seed);
  robot::ApplyLayoutToSpec(*m.io, s);
  return s;
}

// The AUV's sample of tick k (a pose, 16 sonar beams, the route's bearing) into the transport;
// `sample` is scratch holding every field.
void PutSample(const robot::RobotModel& m, std::uint64_t k, double x, double y, double yaw, double bearing,
               std::vector<double>& sample, test::ScriptedTransport& t) {
  sample[static_cast<std::size_t>(m.FieldIndex("tick"))] = static_cast<double>(k);
  sample[static_cast<std::size_t>(m.FieldIndex("x_m"))] = x;
  sample[static_cast<std::size_t>(m.FieldIndex("y_m"))] = y;
  sample[static_cast<std::size_t>(m.FieldIndex("yaw_rad"))] = yaw;
  sample[static_cast<std::size_t>(m.FieldIndex("sonar_beams"))] = 16;
  for (std::uint32_t i = 0; i < 16; ++i)
    sample[static_cast<std::size_t>(m.FieldIndex(robot::ExpandIndex("sonar_{i}_m", i)))] = 3.0 + (k + i) % 9;
  sample[static_cast<std::size_t>(m.FieldIndex("route_bearing_rad"))] = bearing;
  t.Put(m, 0, sample);
}

// 300 ticks of the AUV: a sample most ticks (a unicycle's pose), none from tick 200 (stale,
// then lost), an e-stop never; the log and its bytes. `come_back`: the samples come again from
// tick 230 and a person asks to re-arm at tick 262.
Recorded Record(const std::string& name, std::uint64_t seed = 1, const EachTick& each_tick = {}, bool come_back = false,
                const loop::RecordOptions& options = {}) {
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
  auto rec = loop::Recorder::Open(r.path, m, h, options);
  REQUIRE_MESSAGE(rec.ok(), rec.error().message);
  const Status attached = loop::AttachRecorder(m, d, *l, rec->get());
  REQUIRE_MESSAGE(attached.ok(), attached.error().message);
  l->Arm();
  std::vector<double> sample(m.fields.size(), 0.0);
  double x = 0, y = 0, yaw = 0;
  std::uint64_t allocations = 0;
  {
    AllocationScope scope;
    for (std::uint64_t k = 0; k < 300; ++k) {
      if ((k < 200 || (come_back && k >= 230)) && k % 7 != 3) {  // some samples missed: stale for a tick
        // (come_back: wrapped, as the vehicle reports it; else the heading leaves its bounds:
        // invalid samples before the silence)
        PutSample(m, k, x, y, come_back ? std::remainder(yaw, 2 * std::numbers::pi) : yaw,
                  std::sin(0.05 * static_cast<double>(k)), sample, t);
      }
      if (k == 150) t.SetHealth(0, {true, false, false});  // one tick of a degraded link
      if (k == 151) t.SetHealth(0, {});
      if (k == 280) l->RequestStop();
      if (come_back && k == 262) l->RequestRearm();
      rt::TickTiming timing;
      timing.tick = k;
      if (loop::Tick(m, d, *l, ts, timing) != loop::TickStatus::kRunning) break;
      if (each_tick) each_tick(k, **rec);
      yaw += t.command[1] * 0.1;
      x += t.command[0] * std::cos(yaw) * 0.1;
      y += t.command[0] * std::sin(yaw) * 0.1;
    }
    allocations = scope.count();
  }
  CHECK(allocations == 0);
  if (come_back)
    CHECK(std::string(l->recovery().last) ==
          "re-armed on request after 32 healthy ticks (stopped by: stale sample, lost peer)");
  const Status stopped = (*rec)->Stop();
  if (!stopped) r.stop_error = stopped.error().message;
  if (!each_tick) REQUIRE_MESSAGE(stopped.ok(), r.stop_error);
  CHECK((*rec)->dropped() == 0);
  r.records = (*rec)->records();
  r.files = (*rec)->files();
  r.deleted = (*rec)->files_deleted();
  r.not_written = (*rec)->not_written();
  if ((*rec)->failed()) r.failure = (*rec)->failure();
  std::ifstream f(r.path, std::ios::binary);
  r.bytes.assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  return r;
}

// Replays a log against the policy of Record(seed 1); every command must match.
loop::ReplayResult ReplayOf(const loop::Log& log, std::uint64_t source_hash) {
  const robot::RobotModel& m = test::AuvRobot();
  auto policy = policy::PolicyModel::FromSpec(Spec(m, 1));
  REQUIRE(policy.ok());
  auto source = loop::PolicySource::Create(m, *policy);
  REQUIRE(source.ok());
  auto replay = loop::Replay(m, log, source->get(), source_hash);
  REQUIRE_MESSAGE(replay.ok(), replay.error().message);
  CHECK_MESSAGE(replay->mismatches == 0, replay->first_mismatch);
  return std::move(*replay);
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

TEST_CASE("log: a run the supervisor stopped and a person re-armed replays bit for bit, the request recorded") {
  const Recorded r = Record("rearm", 1, {}, true);
  auto log = loop::ReadLog(r.path);
  REQUIRE_MESSAGE(log.ok(), log.error().message);
  std::uint64_t requests = 0;
  for (const loop::LogRecord& rec : log->records)
    if (rec.type == 1 && (rec.inputs.flags & 32) != 0) {
      ++requests;
      CHECK(rec.inputs.tick == 262);
    }
  CHECK(requests == 1);
  const loop::ReplayResult replay = ReplayOf(*log, r.source_hash);
  CHECK(replay.compared == replay.ticks);
  // Lost (e-stop), then re-armed at the request: the policy drives again, in the replay too.
  const std::string csv = loop::FormatOutputs(test::AuvRobot(), replay.outputs);
  CHECK(csv.find(",e-stop,") != std::string::npos);
  CHECK(csv.find("\n262,run,nominal,") != std::string::npos);
  CHECK(csv.find("\n261,run,e-stop,") != std::string::npos);
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
  bad[8] = 4;
  CHECK(Refusal(bad) == "run.log: offset 8: header: field 'version': 4 (this reader knows 1 to 3)");
  bad[8] = 0;
  CHECK(Refusal(bad) == "run.log: offset 8: header: field 'version': 0 (this reader knows 1 to 3)");
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

namespace {

// Replays a log's records against the policy of Record(seed 1): the number of commands compared.
std::uint64_t ReplaysExactly(const loop::Log& log, std::uint64_t source_hash) {
  return ReplayOf(log, source_hash).compared;
}

// Waits (at most 10 s) for the recorder's writer to notice a failure.
bool WaitForFailure(const loop::Recorder& rec) {
  for (int i = 0; i < 10000 && !rec.failed(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  return rec.failed();
}

}  // namespace

TEST_CASE(
    "log: a write that fails (past a file size limit) stops recording at once - whole records, an end record naming "
    "the error") {
  const Recorded whole = Record("fsize_whole");
  auto full = loop::ParseLog(whole.bytes, "run.log");
  REQUIRE(full.ok());
  const std::size_t n = full->records.size();
  REQUIRE(n > 400);
  // The limit falls inside record `mid`; the tick that queued it, and a later one where the test
  // waits for the writer to notice (the run goes on after it).
  const std::size_t mid = n / 2;
  const loop::LogRecord& at = full->records[mid];
  const std::uint64_t tick = at.type == 1 ? at.inputs.tick : at.outputs.tick;
  const rlim_t limit = at.offset + 17;
  rlimit old{};
  REQUIRE(getrlimit(RLIMIT_FSIZE, &old) == 0);
  rlimit lim = old;
  lim.rlim_cur = limit;
  REQUIRE(setrlimit(RLIMIT_FSIZE, &lim) == 0);
  std::uint64_t noticed_at = ~std::uint64_t{0};
  const Recorded r = Record("fsize", 1, [&](std::uint64_t k, const loop::Recorder& rec) {
    if (k == tick + 5) WaitForFailure(rec);
    if (rec.failed() && noticed_at == ~std::uint64_t{0}) noticed_at = k;
  });
  const std::string& failure = r.failure;
  REQUIRE(setrlimit(RLIMIT_FSIZE, &old) == 0);
  // Noticed while the loop ran (the ticks after it went on, allocating nothing: Record checks).
  CHECK(noticed_at <= tick + 5);
  CHECK(failure.rfind("write failed after ", 0) == 0);
  CHECK(failure.find(std::string(" records: ") + std::strerror(EFBIG)) != std::string::npos);
  CHECK(r.stop_error.rfind("log " + r.path + ": " + failure + "; ", 0) == 0);
  CHECK(r.stop_error.find(std::strerror(EFBIG)) != std::string::npos);
  CHECK(r.stop_error.find("records not written; the file holds " + std::to_string(r.records) +
                          " whole records and its end record") != std::string::npos);
  // The file: below the limit, read strictly, its whole records and the end record naming why.
  CHECK(r.bytes.size() <= limit);
  auto log = loop::ParseLog(r.bytes, "run.log");
  REQUIRE_MESSAGE(log.ok(), log.error().message);
  CHECK(log->complete);
  CHECK(log->end == loop::LogEnd::kWriteFailed);
  CHECK(log->end_error == EFBIG);
  CHECK(log->records.size() == r.records);
  CHECK(r.records <= mid);
  CHECK(r.records + loop::Recorder::kBoundaries > mid);  // at most a few records backed off for the end
  CHECK(log->not_written == r.not_written);              // the final count, written over the first end record
  CHECK(log->not_written > 0);
  CHECK(r.records + r.not_written == n);  // every record is either in the file or counted
  CHECK(loop::DescribeEnd(*log) == std::string("a write failed: ") + std::strerror(EFBIG) + " (" +
                                       std::to_string(EFBIG) + "); " + std::to_string(log->not_written) +
                                       " records not written after it");
  // What is in the file replays bit for bit.
  CHECK(ReplaysExactly(*log, r.source_hash) > 50);
}

TEST_CASE("log: a log whose directory is removed while recording is noticed - the loop goes on") {
  const std::string dir = test::ScratchDir("log_removed");
  // The directory is removed by another thread at tick 100 (the tick's thread allocates nothing).
  std::atomic<bool> go{false}, removed{false};
  std::thread remover([&] {
    while (!go.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    std::filesystem::remove_all(dir);
    removed.store(true);
  });
  bool noticed = false;
  const Recorded r = Record("removed", 1, [&](std::uint64_t k, const loop::Recorder& rec) {
    if (k != 100) return;
    go.store(true);
    while (!removed.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    noticed = WaitForFailure(rec);
  });
  remover.join();
  CHECK(noticed);
  CHECK(r.failure.rfind("the file was removed after ", 0) == 0);
  CHECK(r.stop_error.find(": the file was removed after ") != std::string::npos);
  CHECK(r.stop_error.find(", without its end record") != std::string::npos);
  CHECK(r.not_written > 0);
  CHECK_FALSE(std::filesystem::exists(r.path));
}

TEST_CASE("log: a log cannot be opened where nothing can be written - the error names the path and why") {
  const robot::RobotModel& m = test::AuvRobot();
  const std::string path = test::ScratchDir("log_nowhere") + "/no/such/dir/run.log";
  auto rec = loop::Recorder::Open(path, m, loop::MakeLogHeader(m, loop::SourceKind::kNone, 0));
  REQUIRE_FALSE(rec.ok());
  CHECK(rec.error().message == "log " + path + ": cannot write: " + std::strerror(ENOENT));
}

namespace {

// A version 3 log (one file, no snapshot) as an older recorder wrote it: the header without the
// sequence and the run, the end record of `end_bytes` (version 1: 8, dropped; version 2: 21).
std::vector<std::uint8_t> AsVersion(const std::vector<std::uint8_t>& v3, std::uint32_t version, std::size_t end_bytes) {
  auto log = loop::ParseLog(v3, "v3.log");
  REQUIRE(log.ok());
  REQUIRE(log->snapshot.empty());
  std::uint32_t n = 0;
  std::memcpy(&n, &v3[12], 4);
  const std::uint32_t shorter = n - 12;  // without u32 sequence, u64 run
  std::vector<std::uint8_t> b(v3.begin(), v3.begin() + 16 + shorter);
  std::memcpy(&b[8], &version, 4);
  std::memcpy(&b[12], &shorter, 4);
  const std::uint32_t hcrc = Crc32(&b[16], shorter);
  b.insert(b.end(), reinterpret_cast<const std::uint8_t*>(&hcrc), reinterpret_cast<const std::uint8_t*>(&hcrc) + 4);
  // The records, then the end record (32 bytes in version 3: no next file).
  const std::size_t first = 16 + n + 4;
  b.insert(b.end(), v3.begin() + static_cast<long>(first), v3.end() - 32);
  const std::size_t end = b.size();
  const auto len = static_cast<std::uint32_t>(end_bytes);
  b.push_back(3);
  b.insert(b.end(), reinterpret_cast<const std::uint8_t*>(&len), reinterpret_cast<const std::uint8_t*>(&len) + 4);
  b.insert(b.end(), end_bytes, 0);
  const std::uint32_t crc = Crc32(&b[end], b.size() - end);
  b.insert(b.end(), reinterpret_cast<const std::uint8_t*>(&crc), reinterpret_cast<const std::uint8_t*>(&crc) + 4);
  return b;
}

}  // namespace

TEST_CASE("log: version 1 and 2 logs (no sequence or run, shorter end records) are still read and replayed") {
  const Recorded r = Record("version1");
  for (const auto& [version, end_bytes] : {std::pair<std::uint32_t, std::size_t>{1, 8}, {2, 21}}) {
    CAPTURE(version);
    auto log = loop::ParseLog(AsVersion(r.bytes, version, end_bytes), "old.log");
    REQUIRE_MESSAGE(log.ok(), log.error().message);
    CHECK(log->version == version);
    CHECK(log->complete);
    CHECK(log->end == loop::LogEnd::kStopped);
    CHECK(log->header.sequence == 0);
    CHECK(loop::DescribeEnd(*log) == "stopped");
    CHECK(ReplaysExactly(*log, r.source_hash) > 100);
  }
  // Version 2's fields in a version 1 end record are refused (bytes after the last field).
  auto v1 = loop::ParseLog(AsVersion(r.bytes, 1, 8), "old.log");
  REQUIRE(v1.ok());
  CHECK(Refusal(AsVersion(r.bytes, 1, 21))
            .find("record " + std::to_string(v1->records.size()) + " (end): 13 bytes after the last field") !=
        std::string::npos);
}

// ---- rotation --------------------------------------------------------------------------------

namespace {

std::vector<std::uint8_t> Bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

}  // namespace

TEST_CASE("log: a rotated recording - every file at most the size, each replays on its own, together the whole run") {
  const Recorded whole = Record("rotate_whole", 1, {}, true);
  auto all = loop::ParseLog(whole.bytes, "whole.log");
  REQUIRE(all.ok());
  loop::RecordOptions ro;
  ro.max_file_bytes = whole.bytes.size() / 5;
  const Recorded r = Record("rotate", 1, {}, true, ro);
  INFO("whole log ", whole.bytes.size(), " bytes, files of at most ", ro.max_file_bytes);
  CHECK(r.stop_error.empty());
  CHECK(r.files >= 6);
  CHECK(r.deleted == 0);
  CHECK(r.records == whole.records);
  // File by file: its own sequence, the same run, an end record naming the next; the replay of each
  // alone matches the commands the whole run's replay gave at the same ticks.
  const loop::ReplayResult reference = ReplayOf(*all, whole.source_hash);
  std::uint64_t run = 0, records = 0, next_tick = 0;
  std::size_t at = 0;  // in the reference's outputs
  for (std::uint32_t k = 0; k < r.files; ++k) {
    CAPTURE(k);
    const std::string path = loop::RotatedPath(r.path, k);
    const std::vector<std::uint8_t> bytes = Bytes(path);
    CHECK(bytes.size() <= ro.max_file_bytes);
    auto log = loop::ParseLog(bytes, path);
    REQUIRE_MESSAGE(log.ok(), log.error().message);
    CHECK(log->complete);
    CHECK(log->header.sequence == k);
    if (k == 0) run = log->header.run;
    CHECK(log->header.run == run);
    CHECK(log->snapshot.empty() == (k == 0));
    if (k + 1 < r.files) {
      CHECK(log->end == loop::LogEnd::kRotated);
      CHECK(log->next == loop::RotatedPath("run.log", k + 1));
      CHECK(loop::DescribeEnd(*log) == "rotated: the recording goes on in " + log->next);
    } else {
      CHECK(log->end == loop::LogEnd::kStopped);
    }
    REQUIRE_FALSE(log->records.empty());
    CHECK(log->records.front().type == 1);  // a file begins at a tick boundary
    CHECK(log->records.front().inputs.tick == next_tick);
    next_tick = log->records.back().outputs.tick + 1;
    records += log->records.size();
    const loop::ReplayResult replay = ReplayOf(*log, r.source_hash);
    REQUIRE(at + replay.outputs.size() <= reference.outputs.size());
    for (const loop::LogOutputs& o : replay.outputs) {
      const loop::LogOutputs& want = reference.outputs[at++];
      CHECK(o.tick == want.tick);
      CHECK(std::memcmp(o.commands.data(), want.commands.data(), 8 * o.commands.size()) == 0);
    }
  }
  CHECK(records == all->records.size());
  CHECK(at == reference.outputs.size());
  CHECK_FALSE(std::filesystem::exists(loop::RotatedPath(r.path, r.files)));
  // The same run rotates at the same ticks: the tick decides, from the bytes it queued.
  const Recorded again = Record("rotate_again", 1, {}, true, ro);
  CHECK(again.files == r.files);
  for (std::uint32_t k = 0; k < r.files; ++k) {
    auto a = loop::ParseLog(Bytes(loop::RotatedPath(r.path, k)), "a");
    auto b = loop::ParseLog(Bytes(loop::RotatedPath(again.path, k)), "b");
    REQUIRE((a.ok() && b.ok()));
    CHECK(a->records.front().inputs.tick == b->records.front().inputs.tick);
    CHECK(a->snapshot == b->snapshot);
  }
}

TEST_CASE("log: a rotated recording keeps the newest files - the oldest deleted as new ones begin") {
  const Recorded whole = Record("keep_whole");
  loop::RecordOptions ro;
  ro.max_file_bytes = whole.bytes.size() / 6;
  ro.keep_files = 3;
  const Recorded r = Record("keep", 1, {}, false, ro);
  CHECK(r.stop_error.empty());
  REQUIRE(r.files > 3);
  CHECK(r.deleted == r.files - 3);
  for (std::uint32_t k = 0; k < r.files; ++k) {
    CAPTURE(k);
    const std::string path = loop::RotatedPath(r.path, k);
    CHECK(std::filesystem::exists(path) == (k + 3 >= r.files));
    if (k + 3 < r.files) continue;
    auto log = loop::ReadLog(path);
    REQUIRE_MESSAGE(log.ok(), log.error().message);
    CHECK(ReplaysExactly(*log, r.source_hash) > 10);
  }
}

TEST_CASE("log: rotation refused where a file cannot hold a snapshot, and stopped where the next file cannot begin") {
  const robot::RobotModel& m = test::AuvRobot();
  auto policy = policy::PolicyModel::FromSpec(Spec(m, 1));
  REQUIRE(policy.ok());
  auto source = loop::PolicySource::Create(m, *policy);
  REQUIRE(source.ok());
  robot::RobotData d = robot::MakeRobotData(m);
  auto l = loop::MakeLoopData(m, source->get());
  const std::string dir = test::ScratchDir("log_rotate_small");
  loop::RecordOptions ro;
  ro.max_file_bytes = 1000;
  auto rec = loop::Recorder::Open(dir + "/run.log", m, loop::MakeLogHeader(m, loop::SourceKind::kPolicy, 1), ro);
  REQUIRE(rec.ok());
  const Status st = loop::AttachRecorder(m, d, *l, rec->get());
  REQUIRE_FALSE(st.ok());
  CHECK(st.error().message.rfind("log " + dir +
                                     "/run.log: a file of at most 1000 bytes cannot hold a header, a "
                                     "snapshot of the loop (",
                                 0) == 0);
  CHECK(st.error().message.find(" bytes), an end record and four ticks (") != std::string::npos);
  CHECK(l->recorder == nullptr);
  REQUIRE((*rec)->Stop().ok());

  // The next file's name is taken by a directory: recording stops at the rotation, the file before
  // it ends with an end record naming the error and replays; the loop went on.
  const Recorded whole = Record("blocked_whole");
  ro.max_file_bytes = whole.bytes.size() / 4;
  // (Made by another thread at the first tick: the tick's thread allocates nothing.)
  std::atomic<const loop::Recorder*> go{nullptr};
  std::atomic<bool> made{false};
  std::thread maker([&] {
    while (go.load() == nullptr) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    std::filesystem::create_directories(loop::RotatedPath(go.load()->path(), 1));
    made.store(true);
  });
  const Recorded r = Record(
      "blocked", 1,
      [&](std::uint64_t k, const loop::Recorder& recording) {
        if (k != 0) return;
        go.store(&recording);
        while (!made.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      },
      false, ro);
  maker.join();
  CHECK(r.files == 1);
  CHECK(r.failure.rfind("cannot begin the next file " + loop::RotatedPath(r.path, 1) + " after ", 0) == 0);
  CHECK(r.failure.find(std::strerror(EISDIR)) != std::string::npos);
  CHECK(r.not_written > 0);
  auto log = loop::ParseLog(r.bytes, "run.log");
  REQUIRE_MESSAGE(log.ok(), log.error().message);
  CHECK(log->end == loop::LogEnd::kWriteFailed);
  CHECK(log->end_error == EISDIR);
  CHECK(r.bytes.size() <= ro.max_file_bytes);
  CHECK(ReplaysExactly(*log, r.source_hash) > 10);
}

TEST_CASE("log: a later file whose snapshot is damaged or missing is refused naming what is wrong") {
  const Recorded whole = Record("snap_whole");
  loop::RecordOptions ro;
  ro.max_file_bytes = whole.bytes.size() / 3;
  const Recorded r = Record("snap", 1, {}, false, ro);
  REQUIRE(r.files >= 2);
  const std::vector<std::uint8_t> b = Bytes(loop::RotatedPath(r.path, 1));
  auto log = loop::ParseLog(b, "run.1.log");
  REQUIRE(log.ok());
  REQUIRE_FALSE(log->snapshot.empty());
  const robot::RobotModel& m = test::AuvRobot();
  auto policy = policy::PolicyModel::FromSpec(Spec(m, 1));
  auto source = loop::PolicySource::Create(m, *policy);
  // Cut short by 8 bytes (the CRC made anew: damage the CRC does not see).
  loop::Log cut = *log;
  cut.snapshot.resize(cut.snapshot.size() - 8);
  auto refused = loop::Replay(m, cut, source->get(), r.source_hash);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message.rfind("replay: snapshot: field 'policy.", 0) == 0);
  CHECK(refused.error().message.find("': truncated (needs 8 bytes, 0 left)") != std::string::npos);
  // Bytes left over.
  loop::Log bad = *log;
  bad.snapshot.push_back(0);
  refused = loop::Replay(m, bad, source->get(), r.source_hash);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message == "replay: snapshot: 1 bytes after the last field");
  // A later file without its snapshot.
  loop::Log none = *log;
  none.snapshot.clear();
  refused = loop::Replay(m, none, source->get(), r.source_hash);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message == "replay: file 1 of a rotated recording has no snapshot to start from");
  // A snapshot record anywhere but first is refused by the reader.
  std::vector<std::uint8_t> twice = b;
  const std::size_t snap_at = 16 + [&] {
    std::uint32_t n = 0;
    std::memcpy(&n, &b[12], 4);
    return n + 4;
  }();
  const std::size_t snap_len = 9 + log->snapshot.size();
  const std::size_t second = log->records[1].offset;
  twice.insert(twice.begin() + static_cast<long>(second), b.begin() + static_cast<long>(snap_at),
               b.begin() + static_cast<long>(snap_at + snap_len));
  CHECK(Refusal(twice).find(": record 2 (snapshot): a snapshot is only the first record") != std::string::npos);
}

TEST_CASE(
    "log: a command source's silence (zero_after) - its fields read 0, no fault, and the run replays bit for "
    "bit") {
  // The AUV with its sample stream made a command source: older than 3 periods, every field reads 0.
  const test::RobotFileEdits edits("auv", "log_zero_after");
  // (Every field's range must hold 0: the beam count's too.)
  std::ofstream(edits.path()) << test::ReplaceOnce(
      test::ReplaceOnce(test::ReadText(test::SourcePath("models/auv/robot.yaml")),
                        "    stale_after: {degraded: 1, safe_stop: 2, lost: 20}  # sample periods without a new "
                        "sample; lost: e-stop\n",
                        "    zero_after: 3\n"),
      "{name: sonar_beams, min: 16, max: 16}", "{name: sonar_beams, min: 0, max: 16}");
  auto loaded = robot::LoadRobotModel(edits.path());
  REQUIRE_MESSAGE(loaded.ok(), loaded.error().message);
  const robot::RobotModel& m = *loaded;
  REQUIRE(m.streams[0].zero_after_ticks == 3);
  auto policy = policy::PolicyModel::FromSpec(Spec(m, 1));
  REQUIRE(policy.ok());
  auto source = loop::PolicySource::Create(m, *policy);
  REQUIRE(source.ok());
  robot::RobotData d = robot::MakeRobotData(m);
  auto l = loop::MakeLoopData(m, source->get());
  test::ScriptedTransport t(m);
  robot::Transport* ts[] = {&t};
  const std::string path = test::ScratchDir("log_zero_after_run") + "/run.log";
  auto rec = loop::Recorder::Open(path, m, loop::MakeLogHeader(m, loop::SourceKind::kPolicy, 1));
  REQUIRE_MESSAGE(rec.ok(), rec.error().message);
  REQUIRE(loop::AttachRecorder(m, d, *l, rec->get()).ok());
  l->Arm();
  std::vector<double> sample(m.fields.size(), 0.0);
  const auto x = static_cast<std::size_t>(m.FieldIndex("x_m"));
  bool zero_after_silence = true;
  for (std::uint64_t k = 0; k < 160; ++k) {
    if (k < 100 && k % 7 != 3) {  // samples until tick 100, some missed (one tick without)
      PutSample(m, k, 1.0 + 0.01 * static_cast<double>(k), 0.0, 0.0, 0.0, sample, t);
    }
    rt::TickTiming timing;
    timing.tick = k;
    REQUIRE(loop::Tick(m, d, *l, ts, timing) == loop::TickStatus::kRunning);
    if (k <= 102) CHECK(d.fields[x] > 0.9);  // a missed sample or three keep the last values
    if (k >= 103) zero_after_silence = zero_after_silence && d.fields[x] == 0.0;
  }
  CHECK(zero_after_silence);
  CHECK(l->mode_changes().empty());  // the silence is no fault
  REQUIRE((*rec)->Stop().ok());
  auto log = loop::ReadLog(path);
  REQUIRE_MESSAGE(log.ok(), log.error().message);
  auto replay = loop::Replay(m, *log, source->get(), 1);
  REQUIRE_MESSAGE(replay.ok(), replay.error().message);
  CHECK(replay->ticks == 160);
  CHECK(replay->compared == replay->ticks);
  CHECK_MESSAGE(replay->mismatches == 0, replay->first_mismatch);
}

TEST_CASE("log: a snapshot written by a build with fewer phases or operator requests loads, the rest zero") {
  // The loop's per-phase and per-request arrays grow at their end as phases and requests are added.
  const std::uint64_t older[9] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  std::vector<std::uint8_t> bytes(4 + sizeof older + 4 + 13 * 8);
  loop::StateWriter w(bytes.data(), bytes.size());
  w.PutSpan<std::uint64_t>(older);
  std::uint64_t longer[13] = {};
  w.PutSpan<std::uint64_t>(longer);
  REQUIRE_FALSE(w.overflow());
  std::array<std::uint64_t, 11> now{};
  now.fill(77);
  loop::StateReader r(bytes);
  REQUIRE(r.GetSpanUpTo<std::uint64_t>(now, "loop.phase_start"));
  CHECK(now[0] == 1);
  CHECK(now[8] == 9);
  CHECK(now[9] == 0);
  CHECK(now[10] == 0);
  CHECK_FALSE(r.GetSpanUpTo<std::uint64_t>(now, "loop.phase_start"));  // a later build's: more than this one has
  CHECK(r.error() == "field 'loop.phase_start': 13 values, this build has 11");
}
