// Record and replay. A Recorder attached to the loop logs every input a tick consumed (the fields
// of each stream that had a new sample, the links' health, the deadline misses, the requests) and
// the commands it wrote, with the tick of arrival, to a versioned, CRC-guarded binary file; the
// tick queues them (no allocation, lock or file access; drops counted) and a thread writes them.
// Replay (runtime/loop/replay.hpp) runs the same Tick over a log and compares the commands.
//
// Format (little-endian), version 3 (versions 1 and 2 are read too: version 2 has no sequence,
// run or snapshot and ends only as stopped or failed; version 1 differs in the end record):
//   header   "PBPPOLOG" u32 version, u32 n, n bytes of payload, u32 CRC-32 of the payload:
//            u64 robot hash, u64 source hash, f64 tick period, u32 source kind, u32 options,
//            u32 fields, u32 streams, u32 links, u32 commands, u32 motors, u16 + robot name;
//            version 3 then: u32 sequence (0: the first file of a run), u64 run (the same in
//            every file of one recording)
//   records  u8 type, u32 n, n bytes of payload, u32 CRC-32 of type, n and payload:
//            1 inputs   u64 tick, u32 consecutive misses, u8 flags (1 arm, 2 disarm, 4 stop,
//                       8 e-stop, 16 missed, 32 re-arm request), u32 fresh streams, each u32 stream + f64 per field,
//                       u32 links with news, each u32 link + u8 health (1 degraded, 2 fault, 4 lost)
//            2 outputs  u64 tick, u8 phase, u8 mode, f64 per command, u8 per motor (MotorCommand)
//            3 end      u64 records dropped while recording this file (the queue was full); version 2
//                       on: u8 why the log ended (0 the recorder stopped, 1 a write failed, 2 rotated),
//                       u32 the failed write's error number (errno), u64 records not written after
//                       it; version 3 then: u16 + the next file's name (rotated; else empty)
//            4 snapshot the loop's state at a tick boundary (SaveState in runtime/loop/loop.hpp),
//                       the first record of every file but the first of a rotated recording: the
//                       replay starts from it
// A reader refuses a truncated or corrupt log naming the offset and the field.
//
// Rotation (RecordOptions::max_file_bytes, pbppo-controller --record-max-mb): when the next tick's
// records might not fit, the tick takes a snapshot of the loop's state (no allocation; queued as
// chunks beside the records) and the writer ends the file with an end record naming the next,
// opens the next (run.log, run.1.log, run.2.log ...) and writes its header and the snapshot, so
// that every file replays on its own. No file is larger than the size, unless the queue is too full
// to take the snapshot when it falls due (then it is taken at the first tick that can). With
// keep_files (--record-rotate), the oldest files beyond that many are deleted as new ones begin.
// The rotation is decided by the tick from the bytes it queued: the same run rotates at the same
// ticks.
//
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/loop/loop.hpp"

namespace pbppo::loop {

inline constexpr std::uint32_t kLogVersion = 3;

// Why a log ended (its end record).
enum class LogEnd : std::uint8_t { kStopped = 0, kWriteFailed = 1, kRotated = 2 };

enum class SourceKind : std::uint32_t { kNone = 0, kPolicy = 1, kTrajectory = 2 };

struct LogHeader {
  std::uint64_t robot_hash = 0;   // RobotModel::hash
  std::uint64_t source_hash = 0;  // the policy blob's or the trajectory's (LogHash of its bytes)
  double tick_period_s = 0;
  SourceKind source = SourceKind::kNone;
  std::uint32_t options = 0;  // 1: shutdown after the source; 2: stop at the robot's end field
  std::uint32_t fields = 0, streams = 0, links = 0, commands = 0, motors = 0;
  std::string robot;
  // Version 3: the file's place in a rotated recording, and the recording (the recorder sets both).
  std::uint32_t sequence = 0;
  std::uint64_t run = 0;
};

struct RecordOptions {
  std::size_t queue_records = 4096;  // records between the tick and the writer
  // Rotation (see above): 0, one file; else the largest file in bytes (at least the header, a
  // snapshot, the end record and four ticks' records: AttachRecorder says how much).
  std::uint64_t max_file_bytes = 0;
  std::uint32_t keep_files = 0;  // with rotation: the newest files kept (0: all)
};

// The name of file `sequence` of a recording to `path`: path itself for 0, else the sequence
// before the extension (run.log: run.1.log, run.2.log; run: run.1).
std::string RotatedPath(const std::string& path, std::uint32_t sequence);

// FNV-1a 64 of bytes (a blob's, a trajectory's).
std::uint64_t LogHash(std::span<const std::uint8_t> bytes) noexcept;

// The header of a run of `model` (its hash, counts and tick period) with a source.
LogHeader MakeLogHeader(const robot::RobotModel& model, SourceKind source, std::uint64_t source_hash,
                        const LoopOptions& options = {});

class Recorder {
 public:
  // Opens `path` for writing, writes the header, starts the writer thread. Sets SIGXFSZ to be
  // ignored (for the process): past a file size limit a write then fails instead of killing it.
  // The recorder is attached to a loop with AttachRecorder (below).
  static Result<std::unique_ptr<Recorder>> Open(const std::string& path, const robot::RobotModel& model,
                                                const LogHeader& header, const RecordOptions& options = {});
  ~Recorder();  // Stop()
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // The tick's side (noexcept, no allocation): queue a record; dropped (counted) when full.
  void Inputs(const robot::RobotModel& model, const robot::RobotData& data, const rt::TickTiming& timing,
              const TickEvents& events) noexcept;
  void Outputs(const robot::RobotModel& model, const robot::RobotData& data, Phase phase) noexcept;
  // Rotation, at a tick boundary (the tick, after Read, before Inputs): whether the next file is
  // due, and the snapshot that begins it (queued in chunks; when the queue has no room for them,
  // the next tick tries again).
  bool snapshot_due() const noexcept;
  void Snapshot(const robot::RobotModel& model, const robot::RobotData& data, const LoopData& loop) noexcept;
  // Writes what is queued and the end record, closes the file. Idempotent. An error names the file
  // and what failed ("log run.log: write failed after 1359 records: No space left on device; ...").
  Status Stop();

  // Records in the files (whole), dropped by the tick (the queue was full), and queued but not
  // written because a write had failed.
  std::uint64_t records() const noexcept { return written_.load(std::memory_order_relaxed); }
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }
  std::uint64_t not_written() const noexcept { return not_written_.load(std::memory_order_relaxed); }
  // Whether recording has stopped on a failure, and what failed (valid once failed() is true):
  // "write failed after 1359 records: No space left on device", "the file was removed after 88 records".
  bool failed() const noexcept { return failed_.load(std::memory_order_acquire); }
  const std::string& failure() const noexcept { return failure_; }
  // Rotation: files begun (1 without rotation; file k is RotatedPath(path(), k)), files deleted
  // (keep_files).
  std::uint32_t files() const noexcept { return sequence_.load(std::memory_order_relaxed) + 1; }
  std::uint32_t files_deleted() const noexcept { return deleted_.load(std::memory_order_relaxed); }
  const std::string& path() const noexcept { return path_; }  // the first file's

  // After a failed write, at most kBoundaries - 1 whole records are given back to make room for the
  // end record.
  static constexpr std::size_t kBoundaries = 8;

  struct Ring;

 private:
  friend Status AttachRecorder(const robot::RobotModel&, const robot::RobotData&, LoopData&, Recorder*);
  Recorder() = default;
  bool Push(std::uint8_t type, const std::uint8_t* payload, std::size_t n) noexcept;
  void Run();
  void Drain();  // writes (or, after a failure, counts as not written) what is queued
  void TakeChunk(const std::uint8_t* slot);
  void Rotate(std::size_t snapshot_bytes, std::uint64_t dropped_before);
  void Fail(int error, const std::string& what);
  int WriteEnd(LogEnd why, int error, std::uint64_t dropped, const std::string& next);
  std::vector<std::uint8_t> EndRecord(LogEnd why, int error, std::uint64_t dropped, const std::string& next) const;
  std::uint64_t FileDropped() const noexcept;  // dropped since the current file began (as far as written)
  std::string path_;
  LogHeader header_;
  RecordOptions options_;
  int fd_ = -1;
  std::unique_ptr<Ring> ring_;
  std::vector<std::uint8_t> scratch_;  // the record being built (sized at Open)
  // Rotation, the tick's side: the snapshot being queued (sized by AttachRecorder), the bytes
  // queued for the current file, and how many fit in a file (after its header, snapshot and end).
  std::vector<std::uint8_t> snapshot_;
  std::uint64_t queued_bytes_ = 0, budget_ = 0, tick_bytes_ = 0;
  // The writer thread's: a batch of records and their sizes, where the file's whole records end
  // (the last few boundaries, to back off to), whether the end record is written; the snapshot
  // being put together from its chunks; the files kept.
  std::vector<std::uint8_t> batch_;
  std::vector<std::uint32_t> batch_sizes_;
  std::uint64_t boundary_[kBoundaries] = {};  // file offset after record k (k mod kBoundaries)
  std::uint64_t file_bytes_ = 0, end_at_ = 0, file_records_ = 0, file_dropped_from_ = 0;
  std::vector<std::uint8_t> assembled_;
  std::vector<std::string> kept_;  // the files of the recording that still exist, oldest first
  bool ended_ = false;
  int error_ = 0;  // the failed write's error number
  std::atomic<std::uint64_t> written_{0}, dropped_{0}, not_written_{0};
  std::atomic<std::uint32_t> sequence_{0}, deleted_{0};
  std::atomic<bool> stop_{false}, failed_{false};
  std::string failure_;  // written once, before failed_ is set
  std::thread thread_;
};

// Attaches `recorder` (nullptr: detaches) to the loop of `model` (with its data), sizing the
// snapshot that begins each rotated file; refused where RecordOptions::max_file_bytes cannot hold a
// header, a snapshot, an end record and four ticks' records ("... needs at least 10240 bytes").
Status AttachRecorder(const robot::RobotModel& model, const robot::RobotData& data, LoopData& loop, Recorder* recorder);

// A log as read back.
struct LogInputs {
  std::uint64_t tick = 0;
  std::uint32_t consecutive_misses = 0;
  std::uint8_t flags = 0;
  std::vector<std::uint32_t> streams;  // fresh streams
  std::vector<double> values;          // their fields, stream by stream
  std::vector<std::pair<std::uint32_t, std::uint8_t>> links;
};

struct LogOutputs {
  std::uint64_t tick = 0;
  std::uint8_t phase = 0, mode = 0;
  std::vector<double> commands;
  std::vector<std::uint8_t> motors;
};

struct LogRecord {
  std::uint8_t type = 0;
  std::size_t offset = 0;  // in the file
  LogInputs inputs;
  LogOutputs outputs;
};

struct Log {
  std::uint32_t version = kLogVersion;
  LogHeader header;
  std::vector<std::uint8_t> snapshot;  // the state the file starts from (a rotated recording's later files)
  std::vector<LogRecord> records;
  std::uint64_t dropped = 0;
  bool complete = false;  // an end record closes it
  // Why it ended (version 2 end records; a version 1 log ends kStopped): a failed write's error
  // number and the records not written after it.
  LogEnd end = LogEnd::kStopped;
  std::uint32_t end_error = 0;
  std::uint64_t not_written = 0;
  std::string next;  // kRotated: the next file's name
  // A log read with LogTail::kAcceptCut that ends without its end record: where its whole records
  // end (an offset in the file) and why the rest is not there ("the file ends inside record 1360
  // (inputs): it needs 95 bytes, 41 are left", "no end record after record 1359").
  std::size_t cut_at = 0;
  std::string cut_reason;
};

// How a log that ends without its end record is read: refused (kStrict), or (kAcceptCut) read up
// to its last whole record, as a recording cut short by a full disk or a crash leaves it. Damage
// before the end (a record whose CRC fails, a field out of range) is refused either way.
enum class LogTail : std::uint8_t { kStrict, kAcceptCut };

// Parses a whole log. `origin` names it in errors: "run.log: offset 312: record 5 (inputs): field
// 'values': truncated (needs 312 bytes, 40 left)", "...: CRC 0x1234abcd does not match 0x...".
// With a model, the counts are checked against it too (a log of another robot is refused).
Result<Log> ParseLog(std::span<const std::uint8_t> bytes, const std::string& origin, LogTail tail = LogTail::kStrict);
Result<Log> ReadLog(const std::string& path, LogTail tail = LogTail::kStrict);

// How a log ends, in words: "stopped", "a write failed: No space left on device (28); 2000
// records not written after it", "rotated: the recording goes on in run.2.log", or (a log cut
// short) the cut's reason.
std::string DescribeEnd(const Log& log);

}  // namespace pbppo::loop
