// Bounded single-producer single-consumer queue: storage allocated once at construction,
// TryPush/TryPop never allocate, lock or block. The producer (a real-time thread) drops when the
// queue is full and counts it; the consumer is a non-real-time thread.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace pbppo {

template <typename T>
class SpscQueue {
 public:
  // Capacity is rounded up to a power of two (at least 2).
  explicit SpscQueue(std::size_t capacity) {
    std::size_t c = 2;
    while (c < capacity) c <<= 1u;
    mask_ = c - 1;
    slots_ = std::make_unique<T[]>(c);
  }
  SpscQueue(const SpscQueue&) = delete;
  SpscQueue& operator=(const SpscQueue&) = delete;

  std::size_t capacity() const noexcept { return mask_ + 1; }

  // Producer side. False (and the drop counted) when full.
  bool TryPush(const T& v) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_cache_ > mask_) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ > mask_) {
        dropped_.fetch_add(1, std::memory_order_relaxed);
        return false;
      }
    }
    slots_[head & mask_] = v;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  // Consumer side.
  bool TryPop(T* out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return false;
    }
    *out = slots_[tail & mask_];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  std::unique_ptr<T[]> slots_;
  std::size_t mask_ = 0;
  alignas(64) std::atomic<std::size_t> head_{0};
  std::size_t tail_cache_ = 0;  // producer's view of tail
  alignas(64) std::atomic<std::size_t> tail_{0};
  std::size_t head_cache_ = 0;  // consumer's view of head
  alignas(64) std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace pbppo
