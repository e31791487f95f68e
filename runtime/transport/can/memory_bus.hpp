// An in-process CAN network: the controller's CanTransport and the HIL's emulated devices on the
// same buses without SocketCAN, for lock-step runs in one thread (every test and benchmark that
// needs no kernel, sim-to-sim on every build). A frame sent by one endpoint of a bus is queued
// for every other endpoint of that bus whose identifier filter takes it, as on a wire. Frames
// keep their bytes exactly; the same codecs, tables and quantisation run as over vcan.
//
// Each endpoint's queue has a fixed capacity (frames beyond it are counted as rx_dropped_kernel,
// like a full socket queue); a bus can be cut (Send drops everything and the endpoints read a
// bus-off error frame, once) and restored (a "restarted" error frame). Single-threaded: the
// network is not safe to use from two threads at once.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/transport/can/can_bus.hpp"

namespace pbppo::can {

class MemoryCanNetwork;

class MemoryCanBus final : public CanBus {
 public:
  ~MemoryCanBus() override;
  std::size_t Receive(std::span<CanFrame> out) noexcept override;
  std::size_t ReceiveAtLeast(std::span<CanFrame> out, std::size_t want, std::int64_t timeout_ns) noexcept override;
  std::size_t Send(std::span<const CanFrame> frames) noexcept override;
  const std::string& interface() const noexcept override { return name_; }

 private:
  friend class MemoryCanNetwork;
  MemoryCanBus() = default;
  bool Accepts(std::uint32_t id) const noexcept;
  void Push(const CanFrame& f) noexcept;
  MemoryCanNetwork* net_ = nullptr;
  std::size_t bus_ = 0;
  std::string name_;
  bool fd_ = false, receive_all_ = false;
  std::vector<std::uint32_t> rx_ids_;
  std::vector<CanFrame> ring_;
  std::size_t head_ = 0, size_ = 0;
};

class MemoryCanNetwork {
 public:
  // `bus_names` names the buses ("front", "hind" or "mem0", ...); `queue_frames` is each
  // endpoint's queue capacity.
  explicit MemoryCanNetwork(std::vector<std::string> bus_names, std::size_t queue_frames = 1024);
  ~MemoryCanNetwork();
  MemoryCanNetwork(const MemoryCanNetwork&) = delete;
  MemoryCanNetwork& operator=(const MemoryCanNetwork&) = delete;

  // A new endpoint on bus `bus` (an index), owned by the caller; the network must outlive it.
  // rx_ids: the 11-bit identifiers it receives (empty and !receive_all: none); fd: it takes FD frames.
  Result<std::unique_ptr<MemoryCanBus>> Attach(std::size_t bus, const std::vector<std::uint32_t>& rx_ids, bool fd,
                                               bool receive_all);
  // The index of a bus name, -1 if none.
  int BusIndex(const std::string& name) const noexcept;
  std::size_t bus_count() const noexcept { return names_.size(); }

  // Fault injection: a cut bus carries nothing; its endpoints read one bus-off error frame. Restore
  // sends a "restarted" error frame.
  void SetBusOff(std::size_t bus, bool off) noexcept;
  bool bus_off(std::size_t bus) const noexcept { return off_[bus] != 0; }

 private:
  friend class MemoryCanBus;
  void Deliver(const MemoryCanBus* from, const CanFrame& f) noexcept;
  void Detach(MemoryCanBus* e) noexcept;
  std::vector<std::string> names_;
  std::size_t queue_frames_;
  std::vector<MemoryCanBus*> endpoints_;
  std::vector<std::uint8_t> off_;
};

}  // namespace pbppo::can
