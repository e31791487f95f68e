// SocketCAN transport: the only CAN code that knows sockets. One raw socket per bus (CAN FD
// enabled on FD buses), kernel filters for the identifiers in use, non-blocking; each tick
// Receive drains until EAGAIN into a preallocated buffer (recvmmsg) and Send writes a batch with
// one sendmmsg. Error frames are enabled and decoded into BusStats; ENOBUFS and short writes are
// counted, never fatal. Everything is allocated in Open; Receive and Send never allocate.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/transport/can/can_bus.hpp"

namespace pbppo::can {

struct SocketCanOptions {
  std::string interface;              // "can0", "vcan0"
  bool fd = false;                    // enable CAN FD frames (CAN_RAW_FD_FRAMES)
  std::vector<std::uint32_t> rx_ids;  // 11-bit identifiers to receive (kernel filters); empty: none
  bool receive_all = false;           // no filter: every identifier (tools, loggers)
  bool error_frames = true;           // subscribe to all error classes (CAN_ERR_MASK)
  bool loopback_own = false;          // receive our own transmitted frames (CAN_RAW_RECV_OWN_MSGS)
  std::uint32_t rx_batch = 64;        // frames per recvmmsg; also the buffer a Receive may fill
  std::uint32_t tx_batch = 64;        // largest batch Send accepts in one sendmmsg
  int rcvbuf_bytes = 0;               // SO_RCVBUF (0: kernel default)
  int sndbuf_bytes = 0;               // SO_SNDBUF (0: kernel default)
};

class SocketCanBus final : public CanBus {
 public:
  // Opens and configures the socket; errors name the interface and the call that failed.
  static Result<std::unique_ptr<SocketCanBus>> Open(const SocketCanOptions& options);
  ~SocketCanBus() override;

  // Drains the socket until EAGAIN or `out` is full. Data frames go to `out` (with the kernel's
  // receive time); error frames are decoded into stats() and also returned when keep_error_frames.
  // Returns the number of frames written to `out`.
  std::size_t Receive(std::span<CanFrame> out) noexcept override;
  // Lock-step helper: drains like Receive, waiting (poll) until at least `want` frames arrived,
  // `out` is full or `timeout_ns` of wall time has passed. Returns the number of frames written.
  std::size_t ReceiveAtLeast(std::span<CanFrame> out, std::size_t want, std::int64_t timeout_ns) noexcept override;
  // Sends the frames with one sendmmsg per tx_batch; frames the kernel refuses (ENOBUFS, EAGAIN)
  // are counted as dropped, never retried. Returns the number accepted.
  std::size_t Send(std::span<const CanFrame> frames) noexcept override;

  const std::string& interface() const noexcept override { return options_.interface; }
  int fd() const noexcept { return fd_; }
  bool keep_error_frames = false;

 private:
  SocketCanBus() = default;
  struct Buffers;
  SocketCanOptions options_;
  int fd_ = -1;
  std::unique_ptr<Buffers> buf_;
};

// Decodes a SocketCAN error frame (can_id has CAN_ERR_FLAG) into the counters. Pure.
void DecodeErrorFrame(std::uint32_t can_id, const std::uint8_t data[8], BusStats& stats) noexcept;
// Human-readable summary of an error frame, for logs and tools ("bus-off", "controller: rx
// error-passive", ...); writes at most `size` bytes including the terminator.
void DescribeErrorFrame(std::uint32_t can_id, const std::uint8_t data[8], char* out, std::size_t size) noexcept;

}  // namespace pbppo::can
