// candump-compatible logging (`candump -L` format, readable by can-utils' canplayer/log2asc and
// python-can):
//   (1700000000.123456) vcan0 123#DEADBEEF        classic, 11-bit id
//   (1700000000.123456) vcan0 1F334455#1122       classic, 29-bit id
//   (1700000000.123456) vcan0 123#R               remote request
//   (1700000000.123456) vcan0 123##1DEADBEEF      CAN FD; the digit after ## is the flags (1 BRS, 2 ESI)
//   (1700000000.123456) vcan0 20000040#0000000000000000   error frame (CAN_ERR_FLAG | class)
// The real-time side only copies frames into a bounded SPSC queue (drop when full, counted); a
// non-real-time thread formats and writes them.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/core/spsc_queue.hpp"
#include "runtime/transport/can/can_frame.hpp"

namespace pbppo::can {

inline constexpr std::size_t kCandumpLineMax = 200;  // longest line incl. newline and terminator

// Formats one line (with '\n'); returns its length, or 0 if `size` is too small. No allocation.
std::size_t FormatCandumpLine(std::uint64_t time_ns, std::string_view iface, const CanFrame& f, char* out,
                              std::size_t size) noexcept;

struct CandumpRecord {
  std::uint64_t time_ns = 0;
  char iface[16] = {};
  CanFrame frame;
};
// Parses one line (trailing '\n' optional). False on anything that is not a candump -L line.
bool ParseCandumpLine(std::string_view line, CandumpRecord* out) noexcept;

class CandumpLogger {
 public:
  // Opens `path` for writing and starts the writer thread. `interfaces[i]` names bus i.
  static Result<std::unique_ptr<CandumpLogger>> Open(const std::string& path, std::vector<std::string> interfaces,
                                                     std::size_t queue_capacity = 4096);
  ~CandumpLogger();  // Stop()
  CandumpLogger(const CandumpLogger&) = delete;
  CandumpLogger& operator=(const CandumpLogger&) = delete;

  // Real-time side: copies the frame into the queue; false (counted) when full. Never blocks.
  bool Push(std::uint32_t bus, const CanFrame& frame) noexcept;
  // Writes everything queued, then stops the thread and closes the file. Idempotent.
  void Stop();

  std::uint64_t dropped() const noexcept { return queue_.dropped(); }
  std::uint64_t written() const noexcept { return written_.load(std::memory_order_relaxed); }
  std::uint64_t write_errors() const noexcept { return write_errors_.load(std::memory_order_relaxed); }

 private:
  struct Item {
    std::uint32_t bus;
    CanFrame frame;
  };
  CandumpLogger(std::FILE* file, std::vector<std::string> interfaces, std::size_t capacity);
  void Run();
  std::size_t DrainOnce();

  std::FILE* file_;
  std::vector<std::string> interfaces_;
  SpscQueue<Item> queue_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> written_{0};
  std::atomic<std::uint64_t> write_errors_{0};
  std::thread thread_;
};

}  // namespace pbppo::can
