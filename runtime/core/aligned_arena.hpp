// One aligned heap block, carved up at set-up. Nothing is allocated after construction.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>

namespace pbppo {

inline constexpr std::size_t kCacheLine = 64;

constexpr std::size_t AlignUp(std::size_t n, std::size_t a = kCacheLine) noexcept {
  return (n + a - 1) / a * a;
}

struct AlignedFree {
  void operator()(void* p) const noexcept { std::free(p); }
};

// Owns `bytes` of zeroed, 64-byte-aligned memory.
class AlignedBlock {
 public:
  AlignedBlock() = default;
  explicit AlignedBlock(std::size_t bytes) : size_(AlignUp(bytes == 0 ? kCacheLine : bytes)) {
    void* p = std::aligned_alloc(kCacheLine, size_);
    if (p == nullptr) throw std::bad_alloc();
    for (std::size_t i = 0; i < size_; ++i) static_cast<unsigned char*>(p)[i] = 0;
    ptr_.reset(p);
  }
  std::byte* data() noexcept { return static_cast<std::byte*>(ptr_.get()); }
  const std::byte* data() const noexcept { return static_cast<const std::byte*>(ptr_.get()); }
  std::size_t size() const noexcept { return size_; }

 private:
  std::unique_ptr<void, AlignedFree> ptr_;
  std::size_t size_ = 0;
};

// Computes offsets of 64-byte-aligned float arrays inside one block.
class ArenaPlan {
 public:
  // Reserves `count` floats; returns the byte offset of the first one.
  std::size_t Floats(std::size_t count) noexcept {
    const std::size_t at = bytes_;
    bytes_ += AlignUp(count * sizeof(float));
    return at;
  }
  std::size_t bytes() const noexcept { return bytes_; }

 private:
  std::size_t bytes_ = 0;
};

}  // namespace pbppo
