// Set-up-time error handling: a typed code plus a message that names the field and the value.
#pragma once

#include <string>
#include <utility>
#include <variant>

namespace pbppo {

enum class ErrorCode {
  kIo,            // file missing, unreadable, unwritable
  kFormat,        // bytes that are not what the format says (magic, version, CRC, sizes)
  kLimit,         // a size beyond a configured capacity limit
  kInvalidValue,  // a value out of its domain (non-finite weight, bad enum)
  kMismatch,      // two consistent pieces that disagree (layout hash, chained sizes)
  kUnsupported,   // a valid request this build or machine cannot serve
};

const char* ToString(ErrorCode code) noexcept;

struct Error {
  ErrorCode code;
  std::string message;
};

// Result<T>: either a value or an Error. Used only at set-up, never in a tick.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::move(value)) {}      // NOLINT(google-explicit-constructor)
  Result(Error error) : v_(std::move(error)) {}  // NOLINT(google-explicit-constructor)

  bool ok() const noexcept { return v_.index() == 0; }
  explicit operator bool() const noexcept { return ok(); }

  T& value() & { return std::get<0>(v_); }
  const T& value() const& { return std::get<0>(v_); }
  T&& value() && { return std::get<0>(std::move(v_)); }
  T* operator->() { return &std::get<0>(v_); }
  const T* operator->() const { return &std::get<0>(v_); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

  const Error& error() const& { return std::get<1>(v_); }
  Error&& error() && { return std::get<1>(std::move(v_)); }

 private:
  std::variant<T, Error> v_;
};

template <>
class [[nodiscard]] Result<void> {
 public:
  Result() = default;
  Result(Error error) : err_(std::move(error)), ok_(false) {}  // NOLINT(google-explicit-constructor)
  bool ok() const noexcept { return ok_; }
  explicit operator bool() const noexcept { return ok_; }
  const Error& error() const& { return err_; }

 private:
  Error err_{ErrorCode::kFormat, {}};
  bool ok_ = true;
};

using Status = Result<void>;

inline Error MakeError(ErrorCode code, std::string message) {
  return Error{code, std::move(message)};
}

}  // namespace pbppo
