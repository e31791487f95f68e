// Latest-value mailbox for one writer thread and one reader thread (a triple buffer): the writer
// never waits for the reader and the reader always gets the newest complete value, never a mix of
// two writes. Storage is inside the object; Write and Read never allocate, lock or block, so the
// real-time tick can read what a transport thread wrote. Three slots: the writer fills its own
// slot, then swaps it with the shared "ready" slot; the reader swaps the ready slot with its own
// only when it is newer. Every value carries the version the writer gave it (1, 2, 3 ...).
#pragma once

#include <atomic>
#include <cstdint>
#include <type_traits>

namespace pbppo {

template <typename T>
class LatestMailbox {
  static_assert(std::is_trivially_copyable_v<T>, "LatestMailbox holds plain values");

 public:
  LatestMailbox() = default;
  LatestMailbox(const LatestMailbox&) = delete;
  LatestMailbox& operator=(const LatestMailbox&) = delete;

  // Writer side. Returns the version given to `v` (1 for the first write).
  std::uint64_t Write(const T& v) noexcept {
    Slot& s = slots_[write_index_];
    s.value = v;
    s.version = ++written_;
    // Publish our slot as the ready one and take the previous ready slot as our next.
    const std::uint32_t prev = ready_.exchange(write_index_ | kFresh, std::memory_order_acq_rel);
    write_index_ = prev & kIndexMask;
    published_.store(written_, std::memory_order_release);
    return written_;
  }

  // Reader side: copies the newest value into *out and returns its version; 0 (and *out left
  // alone) while nothing has been written. Reading twice without a write returns the same value.
  std::uint64_t Read(T* out) noexcept {
    if ((ready_.load(std::memory_order_relaxed) & kFresh) != 0) {
      const std::uint32_t prev = ready_.exchange(read_index_, std::memory_order_acq_rel);
      read_index_ = prev & kIndexMask;
    }
    const Slot& s = slots_[read_index_];
    if (s.version == 0) return 0;
    *out = s.value;
    return s.version;
  }

  // Any thread: the number of writes so far (the version of the newest value).
  std::uint64_t version() const noexcept { return published_.load(std::memory_order_acquire); }

 private:
  static constexpr std::uint32_t kFresh = 4u;
  static constexpr std::uint32_t kIndexMask = 3u;
  struct Slot {
    T value{};
    std::uint64_t version = 0;
  };
  Slot slots_[3];
  std::uint32_t write_index_ = 0;  // writer's own slot
  std::uint32_t read_index_ = 2;   // reader's own slot
  std::uint64_t written_ = 0;      // writer only
  alignas(64) std::atomic<std::uint32_t> ready_{1};
  alignas(64) std::atomic<std::uint64_t> published_{0};
};

}  // namespace pbppo
