#include "runtime/transport/can/memory_bus.hpp"

#include <linux/can/error.h>

#include <algorithm>

#include "runtime/transport/can/socketcan.hpp"

namespace pbppo::can {

MemoryCanNetwork::MemoryCanNetwork(std::vector<std::string> bus_names, std::size_t queue_frames)
    : names_(std::move(bus_names)), queue_frames_(std::max<std::size_t>(queue_frames, 1)), off_(names_.size(), 0) {}

MemoryCanNetwork::~MemoryCanNetwork() {
  for (MemoryCanBus* e : endpoints_) e->net_ = nullptr;
}

Result<std::unique_ptr<MemoryCanBus>> MemoryCanNetwork::Attach(std::size_t bus,
                                                               const std::vector<std::uint32_t>& rx_ids, bool fd,
                                                               bool receive_all) {
  if (bus >= names_.size())
    return MakeError(ErrorCode::kInvalidValue,
                     "memory CAN network: bus " + std::to_string(bus) + " of " + std::to_string(names_.size()));
  std::unique_ptr<MemoryCanBus> e(new MemoryCanBus());
  e->net_ = this;
  e->bus_ = bus;
  e->name_ = names_[bus];
  e->fd_ = fd;
  e->receive_all_ = receive_all;
  e->rx_ids_ = rx_ids;
  std::sort(e->rx_ids_.begin(), e->rx_ids_.end());
  e->ring_.resize(queue_frames_);
  endpoints_.push_back(e.get());
  return e;
}

int MemoryCanNetwork::BusIndex(const std::string& name) const noexcept {
  const auto it = std::find(names_.begin(), names_.end(), name);
  return it == names_.end() ? -1 : static_cast<int>(it - names_.begin());
}

void MemoryCanNetwork::SetBusOff(std::size_t bus, bool off) noexcept {
  if (bus >= off_.size() || (off_[bus] != 0) == off) return;
  off_[bus] = off ? 1 : 0;
  CanFrame err;
  err.flags = kFlagError;
  err.id = off ? CAN_ERR_BUSOFF : CAN_ERR_RESTARTED;
  err.len = 8;
  for (MemoryCanBus* e : endpoints_)
    if (e->bus_ == bus) e->Push(err);
}

void MemoryCanNetwork::Deliver(const MemoryCanBus* from, const CanFrame& f) noexcept {
  for (MemoryCanBus* e : endpoints_)
    if (e != from && e->bus_ == from->bus_ && e->Accepts(f.id) && (e->fd_ || !f.fd())) e->Push(f);
}

void MemoryCanNetwork::Detach(MemoryCanBus* e) noexcept {
  endpoints_.erase(std::remove(endpoints_.begin(), endpoints_.end(), e), endpoints_.end());
}

MemoryCanBus::~MemoryCanBus() {
  if (net_ != nullptr) net_->Detach(this);
}

bool MemoryCanBus::Accepts(std::uint32_t id) const noexcept {
  return receive_all_ || std::binary_search(rx_ids_.begin(), rx_ids_.end(), id);
}

void MemoryCanBus::Push(const CanFrame& f) noexcept {
  if (size_ == ring_.size()) {
    ++stats_.rx_dropped_kernel;  // a full queue, as a socket's
    return;
  }
  ring_[(head_ + size_) % ring_.size()] = f;
  ++size_;
}

std::size_t MemoryCanBus::Receive(std::span<CanFrame> out) noexcept {
  std::size_t n = 0;
  while (size_ > 0 && n < out.size()) {
    const CanFrame& f = ring_[head_];
    head_ = (head_ + 1) % ring_.size();
    --size_;
    if (f.error()) {
      DecodeErrorFrame(f.id, f.data, stats_);
      continue;
    }
    ++stats_.rx_frames;
    out[n++] = f;
  }
  if (size_ > 0) ++stats_.rx_buffer_full;
  return n;
}

std::size_t MemoryCanBus::ReceiveAtLeast(std::span<CanFrame> out, std::size_t, std::int64_t) noexcept {
  return Receive(out);  // one thread: whatever the peer sent has arrived
}

std::size_t MemoryCanBus::Send(std::span<const CanFrame> frames) noexcept {
  if (net_ == nullptr || net_->off_[bus_] != 0) {
    stats_.tx_dropped += frames.size();
    return 0;
  }
  std::size_t accepted = 0;
  for (const CanFrame& f : frames) {
    const bool ok = f.fd() ? fd_ && IsValidFdLength(f.len) : f.len <= kClassicMaxLen;
    if (!ok) {
      ++stats_.tx_errors;
      continue;
    }
    net_->Deliver(this, f);
    ++stats_.tx_frames;
    ++accepted;
  }
  return accepted;
}

}  // namespace pbppo::can
