// The trainer's state as bytes, and back: what ranks exchange (the rollout's samples, evaluation
// returns) and what a resumable checkpoint holds (checkpoint.hpp). Values are copied as they are in
// memory (the same build reads what it wrote); a reader that runs out of bytes or is left with
// some throws std::runtime_error naming what it was reading.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace pbppo::trainer {

class ByteWriter {
 public:
  template <typename T>
  void Put(const T* p, std::size_t n) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* b = reinterpret_cast<const char*>(p);
    bytes_.insert(bytes_.end(), b, b + n * sizeof(T));
  }
  template <typename T>
  void Put(const T& v) {
    Put(&v, 1);
  }
  // A vector or an Eigen matrix: its size, then its elements.
  template <typename T>
  void PutVector(const std::vector<T>& v) {
    Put(static_cast<std::uint64_t>(v.size()));
    Put(v.data(), v.size());
  }
  template <typename Derived>
  void PutMatrix(const Eigen::PlainObjectBase<Derived>& m) {
    Put(static_cast<std::int64_t>(m.rows()));
    Put(static_cast<std::int64_t>(m.cols()));
    Put(m.data(), static_cast<std::size_t>(m.size()));
  }
  void PutString(const std::string& s) {
    Put(static_cast<std::uint64_t>(s.size()));
    Put(s.data(), s.size());
  }
  const std::vector<char>& bytes() const noexcept { return bytes_; }
  std::vector<char>& bytes() noexcept { return bytes_; }

 private:
  std::vector<char> bytes_;
};

class ByteReader {
 public:
  // `what` names the bytes in errors ("rank 1's rollout", "'runs/x/resume.bin'").
  ByteReader(const char* data, std::size_t size, std::string what) : p_(data), size_(size), what_(std::move(what)) {}

  template <typename T>
  void Get(T* out, std::size_t n, const char* field = "data") {
    static_assert(std::is_trivially_copyable_v<T>);
    if (n > (size_ - at_) / sizeof(T)) Fail(field, "ends at byte " + std::to_string(size_));
    std::memcpy(out, p_ + at_, n * sizeof(T));
    at_ += n * sizeof(T);
  }
  template <typename T>
  T Get(const char* field = "data") {
    T v{};
    Get(&v, 1, field);
    return v;
  }
  // A vector of any length (bounded by the bytes left), or of exactly `expect` elements.
  template <typename T>
  void GetVector(std::vector<T>& v, const char* field, std::int64_t expect = -1) {
    const auto n = Get<std::uint64_t>(field);
    if (n > (size_ - at_) / sizeof(T))
      Fail(field, "holds " + std::to_string(n) + " elements, more than the bytes left");
    if (expect >= 0 && n != static_cast<std::uint64_t>(expect))
      Fail(field, "holds " + std::to_string(n) + " elements, not " + std::to_string(expect));
    v.resize(static_cast<std::size_t>(n));
    Get(v.data(), v.size(), field);
  }
  // A matrix of exactly the shape `m` has.
  template <typename Derived>
  void GetMatrix(Eigen::PlainObjectBase<Derived>& m, const char* field) {
    const auto rows = Get<std::int64_t>(field), cols = Get<std::int64_t>(field);
    if (rows != m.rows() || cols != m.cols())
      Fail(field, "is " + std::to_string(rows) + " x " + std::to_string(cols) + ", not " + std::to_string(m.rows()) +
                      " x " + std::to_string(m.cols()));
    Get(m.data(), static_cast<std::size_t>(m.size()), field);
  }
  std::string GetString(const char* field) {
    std::vector<char> v;
    GetVector(v, field);
    return {v.begin(), v.end()};
  }
  void CheckEnd() const {
    if (at_ != size_) Fail("its end", "has " + std::to_string(size_ - at_) + " bytes left over");
  }
  std::size_t position() const noexcept { return at_; }

 private:
  [[noreturn]] void Fail(const char* field, const std::string& what) const {
    throw std::runtime_error(what_ + ": " + field + " at byte " + std::to_string(at_) + " " + what);
  }
  const char* p_;
  std::size_t size_, at_ = 0;
  std::string what_;
};

}  // namespace pbppo::trainer
