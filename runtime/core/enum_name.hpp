#pragma once
// The name of an enumerator whose values run 0, 1, ... in declaration order, from a table written
// in that order: `return EnumName(mode, {"nominal", "degraded", "safe-stop", "e-stop"});`. A value
// past the table's end (a cast from a corrupt byte) names itself "?". Where the enumeration states
// its count, the caller keeps the table in a named array and static_asserts its length.
#include <cstddef>

namespace pbppo {

template <typename E, std::size_t N>
constexpr const char* EnumName(E value, const char* const (&names)[N]) noexcept {
  const auto i = static_cast<std::size_t>(value);
  return i < N ? names[i] : "?";
}

}  // namespace pbppo
