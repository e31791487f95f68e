// LatestMailbox and SpscQueue (latest_mailbox.hpp, spsc_queue.hpp) for records whose size is
// known only at set-up (a DDS message's bytes, sized by its IDL): storage allocated once at
// construction, Write/Read and TryPush/TryPop never allocate, lock or block. Each record carries
// a stamp (the time it arrived, or any 64-bit value the writer gives it).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>

namespace pbppo {

// Latest value, one writer thread and one reader thread (a triple buffer, as LatestMailbox).
class ByteMailbox {
 public:
  explicit ByteMailbox(std::size_t record_size)
      : size_(record_size), bytes_(std::make_unique<std::byte[]>(3 * (record_size > 0 ? record_size : 1))) {}
  ByteMailbox(const ByteMailbox&) = delete;
  ByteMailbox& operator=(const ByteMailbox&) = delete;

  std::size_t record_size() const noexcept { return size_; }

  // Writer side: record_size() bytes from `record`. Returns the version given (1 for the first).
  std::uint64_t Write(const std::byte* record, std::int64_t stamp) noexcept {
    std::memcpy(Slot(write_index_), record, size_);
    meta_[write_index_] = {++written_, stamp};
    const std::uint32_t prev = ready_.exchange(write_index_ | kFresh, std::memory_order_acq_rel);
    write_index_ = prev & kIndexMask;
    published_.store(written_, std::memory_order_release);
    return written_;
  }

  // Reader side: the newest record into `out` (record_size() bytes) and its stamp; its version, 0
  // (nothing copied) while nothing has been written.
  std::uint64_t Read(std::byte* out, std::int64_t* stamp) noexcept {
    if ((ready_.load(std::memory_order_relaxed) & kFresh) != 0) {
      const std::uint32_t prev = ready_.exchange(read_index_, std::memory_order_acq_rel);
      read_index_ = prev & kIndexMask;
    }
    const Meta& m = meta_[read_index_];
    if (m.version == 0) return 0;
    std::memcpy(out, Slot(read_index_), size_);
    if (stamp != nullptr) *stamp = m.stamp;
    return m.version;
  }

  // Any thread: the number of writes so far.
  std::uint64_t version() const noexcept { return published_.load(std::memory_order_acquire); }

 private:
  static constexpr std::uint32_t kFresh = 4u;
  static constexpr std::uint32_t kIndexMask = 3u;
  struct Meta {
    std::uint64_t version = 0;
    std::int64_t stamp = 0;
  };
  std::byte* Slot(std::uint32_t i) noexcept { return bytes_.get() + i * size_; }
  std::size_t size_;
  std::unique_ptr<std::byte[]> bytes_;
  Meta meta_[3];
  std::uint32_t write_index_ = 0;  // writer's own slot
  std::uint32_t read_index_ = 2;   // reader's own slot
  std::uint64_t written_ = 0;      // writer only
  alignas(64) std::atomic<std::uint32_t> ready_{1};
  alignas(64) std::atomic<std::uint64_t> published_{0};
};

// Bounded single-producer single-consumer queue of records (as SpscQueue): the producer drops
// and counts when full.
class ByteQueue {
 public:
  // Capacity is rounded up to a power of two (at least 2).
  ByteQueue(std::size_t record_size, std::size_t capacity) : size_(record_size) {
    std::size_t c = 2;
    while (c < capacity) c <<= 1u;
    mask_ = c - 1;
    bytes_ = std::make_unique<std::byte[]>(c * (record_size > 0 ? record_size : 1));
    stamps_ = std::make_unique<std::int64_t[]>(c);
  }
  ByteQueue(const ByteQueue&) = delete;
  ByteQueue& operator=(const ByteQueue&) = delete;

  std::size_t capacity() const noexcept { return mask_ + 1; }
  std::size_t record_size() const noexcept { return size_; }

  bool TryPush(const std::byte* record, std::int64_t stamp) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_cache_ > mask_) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ > mask_) {
        dropped_.fetch_add(1, std::memory_order_relaxed);
        return false;
      }
    }
    std::memcpy(bytes_.get() + (head & mask_) * size_, record, size_);
    stamps_[head & mask_] = stamp;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  bool TryPop(std::byte* out, std::int64_t* stamp) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return false;
    }
    std::memcpy(out, bytes_.get() + (tail & mask_) * size_, size_);
    if (stamp != nullptr) *stamp = stamps_[tail & mask_];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  std::size_t size_;
  std::unique_ptr<std::byte[]> bytes_;
  std::unique_ptr<std::int64_t[]> stamps_;
  std::size_t mask_ = 0;
  alignas(64) std::atomic<std::size_t> head_{0};
  std::size_t tail_cache_ = 0;  // producer's view of tail
  alignas(64) std::atomic<std::size_t> tail_{0};
  std::size_t head_cache_ = 0;  // consumer's view of head
  alignas(64) std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace pbppo
