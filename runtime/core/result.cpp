#include "runtime/core/result.hpp"

namespace pbppo {

const char* ToString(ErrorCode code) noexcept {
  switch (code) {
    case ErrorCode::kIo: return "io";
    case ErrorCode::kFormat: return "format";
    case ErrorCode::kLimit: return "limit";
    case ErrorCode::kInvalidValue: return "invalid-value";
    case ErrorCode::kMismatch: return "mismatch";
    case ErrorCode::kUnsupported: return "unsupported";
  }
  return "unknown";
}

}  // namespace pbppo
