// Bounded single-producer single-consumer queue: storage allocated once at construction,
// TryPush/TryPop never allocate, lock or block. The producer (a real-time thread) drops when the
// queue is full and counts it; the consumer is a non-real-time thread. A typed view of ByteQueue
// (byte_records.hpp), which holds records of a size known at set-up.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "runtime/core/byte_records.hpp"

namespace pbppo {

template <typename T>
class SpscQueue {
  static_assert(std::is_trivially_copyable_v<T>, "SpscQueue holds plain values");

 public:
  // Capacity is rounded up to a power of two (at least 2).
  explicit SpscQueue(std::size_t capacity) : q_(sizeof(T), capacity) {}
  SpscQueue(const SpscQueue&) = delete;
  SpscQueue& operator=(const SpscQueue&) = delete;

  std::size_t capacity() const noexcept { return q_.capacity(); }

  // Producer side. False (and the drop counted) when full.
  bool TryPush(const T& v) noexcept { return q_.TryPush(reinterpret_cast<const std::byte*>(&v), 0); }

  // Consumer side.
  bool TryPop(T* out) noexcept { return q_.TryPop(reinterpret_cast<std::byte*>(out), nullptr); }

  std::uint64_t dropped() const noexcept { return q_.dropped(); }

 private:
  ByteQueue q_;
};

}  // namespace pbppo
