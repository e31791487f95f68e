// The loop's state as bytes: what a log's snapshot holds (runtime/loop/log.hpp), so that a log
// rotated in the middle of a run replays on its own. StateWriter appends to a fixed buffer (or
// only counts, to size that buffer at set-up) and never allocates; StateReader reads it back and
// names the first field that does not fit this robot or source ("field 'loop.q0': 8 values, this
// robot has 12").
//
// Layout: each value little-endian as it is in memory (the supported hosts are little-endian), a
// bool one byte (0 or 1); each span a u32 count, then its elements. Structures are written field by
// field by their owners (no padding bytes in a log: the same run writes the same bytes).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <type_traits>

namespace pbppo::loop {

class StateWriter {
 public:
  StateWriter() = default;  // counts only: size() is what a buffer needs
  StateWriter(std::uint8_t* buffer, std::size_t capacity) noexcept : p_(buffer), capacity_(capacity) {}

  template <typename T>
  void Put(const T& v) noexcept {
    static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>);
    if constexpr (std::is_same_v<T, bool>) {
      const std::uint8_t b = v ? 1 : 0;
      Bytes(&b, 1);
    } else {
      Bytes(&v, sizeof v);
    }
  }
  template <typename T>
  void PutSpan(std::span<const T> s) noexcept {
    static_assert((std::is_arithmetic_v<T> || std::is_enum_v<T>) && !std::is_same_v<T, bool>);
    Put(static_cast<std::uint32_t>(s.size()));
    Bytes(s.data(), s.size_bytes());
  }

  std::size_t size() const noexcept { return size_; }
  bool overflow() const noexcept { return overflow_; }  // a buffer too small (nothing written past it)

 private:
  void Bytes(const void* v, std::size_t n) noexcept {
    if (p_ != nullptr) {
      if (size_ + n > capacity_) {
        overflow_ = true;
      } else if (n > 0) {
        std::memcpy(p_ + size_, v, n);
      }
    }
    size_ += n;
  }
  std::uint8_t* p_ = nullptr;
  std::size_t capacity_ = 0, size_ = 0;
  bool overflow_ = false;
};

class StateReader {
 public:
  explicit StateReader(std::span<const std::uint8_t> bytes) noexcept : b_(bytes) {}

  // False (and error() set, the first only) when the bytes end before the value.
  template <typename T>
  bool Get(T& v, const char* field) {
    static_assert((std::is_arithmetic_v<T> || std::is_enum_v<T>) && !std::is_same_v<T, bool>);  // bools: GetBool
    if (!Need(sizeof v, field)) return false;
    std::memcpy(&v, b_.data() + at_, sizeof v);
    at_ += sizeof v;
    return true;
  }
  // The stored count must be the span's size (this robot's, this source's).
  template <typename T>
  bool GetSpan(std::span<T> s, const char* field) {
    static_assert((std::is_arithmetic_v<T> || std::is_enum_v<T>) && !std::is_same_v<T, bool>);
    if (!GetCount(s.size(), field) || !Need(s.size_bytes(), field)) return false;
    if (!s.empty()) std::memcpy(s.data(), b_.data() + at_, s.size_bytes());
    at_ += s.size_bytes();
    return true;
  }
  // A span that a later build lengthened (the loop's phases, the operator's requests): up to the
  // span's size stored, the rest zero.
  template <typename T>
  bool GetSpanUpTo(std::span<T> s, const char* field) {
    static_assert((std::is_arithmetic_v<T> || std::is_enum_v<T>) && !std::is_same_v<T, bool>);
    std::uint32_t n = 0;
    if (!Get(n, field)) return false;
    if (n > s.size())
      return Fail(std::string("field '") + field + "': " + std::to_string(n) + " values, this build has " +
                  std::to_string(s.size()));
    if (!Need(n * sizeof(T), field)) return false;
    std::fill(s.begin(), s.end(), T{});
    if (n > 0) std::memcpy(s.data(), b_.data() + at_, n * sizeof(T));
    at_ += n * sizeof(T);
    return true;
  }
  bool GetBool(bool& v, const char* field) {
    std::uint8_t raw = 0;
    if (!Get(raw, field)) return false;
    if (raw > 1) return Fail(std::string("field '") + field + "': " + std::to_string(raw) + " is not 0 or 1");
    v = raw != 0;
    return true;
  }
  // A count stored as a u32 that must be `want` (this robot's, this source's).
  bool GetCount(std::size_t want, const char* field) {
    std::uint32_t n = 0;
    if (!Get(n, field)) return false;
    if (n == want) return true;
    return Fail(std::string("field '") + field + "': " + std::to_string(n) + " values, this robot and source have " +
                std::to_string(want));
  }
  // An enumeration stored as one byte, which must be below `count`.
  template <typename T>
  bool GetBelow(T& v, std::uint32_t count, const char* field) {
    std::uint8_t raw = 0;
    if (!Get(raw, field)) return false;
    if (raw >= count)
      return Fail(std::string("field '") + field + "': " + std::to_string(raw) + " is not below " +
                  std::to_string(count));
    v = static_cast<T>(raw);
    return true;
  }
  bool Fail(const std::string& what) {
    if (error_.empty()) error_ = what;
    return false;
  }

  std::size_t left() const noexcept { return b_.size() - at_; }
  const std::string& error() const noexcept { return error_; }

 private:
  bool Need(std::size_t n, const char* field) {
    if (b_.size() - at_ >= n) return true;
    return Fail(std::string("field '") + field + "': truncated (needs " + std::to_string(n) + " bytes, " +
                std::to_string(b_.size() - at_) + " left)");
  }
  std::span<const std::uint8_t> b_;
  std::size_t at_ = 0;
  std::string error_;
};

}  // namespace pbppo::loop
