// Latest-value mailbox for one writer thread and one reader thread (a triple buffer): the writer
// never waits for the reader and the reader always gets the newest complete value, never a mix of
// two writes. Storage is allocated once, at construction; Write and Read never allocate, lock or
// block, so the real-time tick can read what a transport thread wrote. Three slots: the writer
// fills its own slot, then swaps it with the shared "ready" slot; the reader swaps the ready slot
// with its own only when it is newer. Every value carries the version the writer gave it (1, 2,
// 3 ...). A typed view of ByteMailbox (byte_records.hpp), which holds records of a size known at
// set-up.
#pragma once

#include <cstdint>
#include <type_traits>

#include "runtime/core/byte_records.hpp"

namespace pbppo {

template <typename T>
class LatestMailbox {
  static_assert(std::is_trivially_copyable_v<T>, "LatestMailbox holds plain values");

 public:
  LatestMailbox() : box_(sizeof(T)) {}
  LatestMailbox(const LatestMailbox&) = delete;
  LatestMailbox& operator=(const LatestMailbox&) = delete;

  // Writer side. Returns the version given to `v` (1 for the first write).
  std::uint64_t Write(const T& v) noexcept { return box_.Write(reinterpret_cast<const std::byte*>(&v), 0); }

  // Reader side: copies the newest value into *out and returns its version; 0 (and *out left
  // alone) while nothing has been written. Reading twice without a write returns the same value.
  std::uint64_t Read(T* out) noexcept { return box_.Read(reinterpret_cast<std::byte*>(out), nullptr); }

  // Any thread: the number of writes so far (the version of the newest value).
  std::uint64_t version() const noexcept { return box_.version(); }

 private:
  ByteMailbox box_;
};

}  // namespace pbppo
