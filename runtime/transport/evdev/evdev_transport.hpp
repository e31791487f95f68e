// A gamepad or joystick through Linux evdev (robot.yaml transports of kind evdev; the mapping is
// runtime/robot/transport_spec.hpp's EvdevTransportSpec). Every tick Read drains the device's
// events without blocking, applies each report (the events up to a SYN_REPORT, as evdev means
// them) to the axes and buttons it holds, and writes the mapped fields as a fresh sample of the
// transport's stream: the device's state, every tick it is there.
//
// The device (`device`) is a character device (/dev/input/eventN, or a stable
// /dev/input/by-id/... name that comes back when the pad is plugged in again) or a regular file of
// recorded events (the kernel's struct input_event records as reading the device gives them on a
// 64-bit machine: s64 seconds, s64 microseconds, u16 type, u16 code, s32 value, little-endian; a
// `cat /dev/input/eventN > file` records one). A file is played on the tick clock: an event t
// seconds after the file's first is applied at the first tick at least t after the transport's
// first Read, so a run from a file is the same on every machine; its end is the device going away.
//
// A lost device (read fails: unplugged, out of range, the file's end) is a lost command source:
// the fields read 0 at once (sticks centred, buttons released: a dead-man drops), one fresh
// sample says so, and the stream then falls silent until the device is back (looked for every
// reopen_s; a device whose axis ranges are not the robot file's is refused, said in the summary,
// and looked for again). Events of codes the robot file does not map are counted, not applied; a
// SYN_DROPPED (the kernel's buffer overflowed) discards the report in progress, and the state is
// read back from the device (EVIOCGABS, EVIOCGKEY). Nothing is allocated after Open.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/robot_data.hpp"
#include "runtime/robot/robot_model.hpp"

namespace pbppo::evdev {

// One event record as the device gives it (x86-64 and arm64 Linux: struct input_event).
struct EventRecord {
  std::int64_t sec = 0, usec = 0;
  std::uint16_t type = 0, code = 0;
  std::int32_t value = 0;
};
static_assert(sizeof(EventRecord) == 24);

// Writes records as a device would give them (tests and tools making recorded event files).
Status WriteEventFile(const std::string& path, const std::vector<EventRecord>& records);

struct EvdevStats {
  std::uint64_t events = 0, reports = 0;  // applied events, SYN_REPORTs
  std::uint64_t unmapped = 0;             // events of codes the robot file does not map
  std::uint64_t dropped = 0;              // SYN_DROPPED
  std::uint64_t opens = 0, losses = 0;    // the device found, lost
  std::uint64_t refused = 0;              // opens refused (axis ranges)
  std::uint64_t out_of_range = 0;         // ticks an axis held a value outside its range
};

// What the caller (a command line: --gamepad PATH) sets.
struct EvdevOptions {
  std::string device;  // in place of the robot file's device ("": the robot file's)
};

class EvdevTransport final : public robot::Transport {
 public:
  // The transport `transport` of `model` (kind evdev). A device that is not there yet is no error
  // (it is looked for every reopen_s); a recorded file that cannot be read, or whose size is not
  // a whole number of records, is.
  static Result<std::unique_ptr<EvdevTransport>> Open(const robot::RobotModel& model, const std::string& transport,
                                                      const EvdevOptions& options = {});
  ~EvdevTransport() override;

  void Read(const robot::RobotModel& model, robot::RobotData& data) noexcept override;
  void Write(const robot::RobotModel&, robot::RobotData&) noexcept override {}
  std::string Summary() const override;

  // The device is there (a recorded file: until its end).
  bool present() const noexcept { return fd_ >= 0 || file_open_; }
  const EvdevStats& stats() const noexcept { return stats_; }
  // The last refusal of a device ("" : none).
  const char* refusal() const noexcept { return refusal_; }

 private:
  EvdevTransport() = default;
  void TryOpen(std::uint64_t tick) noexcept;
  void Lose() noexcept;
  void Apply(const EventRecord& e) noexcept;
  void Resync() noexcept;
  void Emit(const robot::RobotModel& model, robot::RobotData& data) noexcept;

  const robot::RobotModel* model_ = nullptr;
  robot::EvdevTransportSpec spec_;
  std::uint32_t first_field_ = 0, field_count_ = 0;
  double tick_s_ = 0;
  std::uint64_t reopen_ticks_ = 1, next_open_tick_ = 0;
  int fd_ = -1;
  // A recorded file: its records and the next one; the ticks are counted from the first Read.
  bool is_file_ = false, file_open_ = false;
  std::vector<EventRecord> file_;
  std::size_t file_at_ = 0;
  bool started_ = false, lost_sample_due_ = false;
  std::uint64_t start_tick_ = 0;
  // Per axis, per button: the state in force (the last report) and the one being reported.
  std::vector<std::int32_t> axis_value_, axis_pending_;
  std::vector<std::uint8_t> button_value_, button_pending_;
  bool discard_ = false;     // after SYN_DROPPED: until the next SYN_REPORT
  std::vector<double> out_;  // per field of the stream: what it reads (rate limits from here)
  std::array<EventRecord, 64> buf_{};
  EvdevStats stats_;
  char refusal_[200] = {};
  std::int32_t last_out_of_range_ = 0;
  int last_out_of_range_code_ = 0;
};

}  // namespace pbppo::evdev
