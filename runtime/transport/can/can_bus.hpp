// One CAN bus as the transport and the HIL's devices use it: drain what arrived, send a batch,
// count. Two implementations: SocketCanBus (socketcan.hpp, the only code that knows sockets) and
// MemoryCanBus (memory_bus.hpp, an in-process bus for lock-step runs where the controller and
// the simulator tick in one thread). Neither allocates after it is made.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "runtime/transport/can/bus_stats.hpp"
#include "runtime/transport/can/can_frame.hpp"

namespace pbppo::can {

class CanBus {
 public:
  CanBus() = default;
  CanBus(const CanBus&) = delete;  // a bus is a device: never copied (nor its implementations)
  CanBus& operator=(const CanBus&) = delete;
  virtual ~CanBus() = default;
  // Drains what arrived until nothing is left or `out` is full; returns the frames written.
  virtual std::size_t Receive(std::span<CanFrame> out) noexcept = 0;
  // Drains like Receive, waiting until at least `want` frames arrived, `out` is full or
  // `timeout_ns` of wall time has passed (a bus with no other thread behind it does not wait).
  virtual std::size_t ReceiveAtLeast(std::span<CanFrame> out, std::size_t want, std::int64_t timeout_ns) noexcept = 0;
  // Sends the frames; those the bus cannot take are counted as dropped, never retried. Returns
  // the number accepted.
  virtual std::size_t Send(std::span<const CanFrame> frames) noexcept = 0;

  virtual const std::string& interface() const noexcept = 0;
  const BusStats& stats() const noexcept { return stats_; }
  BusStats& stats() noexcept { return stats_; }

 protected:
  BusStats stats_;
};

}  // namespace pbppo::can
