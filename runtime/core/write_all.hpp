// Writing a whole buffer to a file descriptor: interrupted and short writes retried.
#pragma once

#include <cstddef>
#include <cstdint>

namespace pbppo {

// Writes n bytes at the descriptor's offset. Returns how many were written; *error is 0 when all
// were, else the error number of the write that failed (ENOSPC for a write that took nothing).
std::size_t WriteAll(int fd, const std::uint8_t* bytes, std::size_t n, int* error) noexcept;

}  // namespace pbppo
