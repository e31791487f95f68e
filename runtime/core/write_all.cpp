#include "runtime/core/write_all.hpp"

#include <unistd.h>

#include <cerrno>

namespace pbppo {

std::size_t WriteAll(int fd, const std::uint8_t* bytes, std::size_t n, int* error) noexcept {
  std::size_t done = 0;
  *error = 0;
  while (done < n) {
    const ssize_t w = ::write(fd, bytes + done, n - done);
    if (w > 0) {
      done += static_cast<std::size_t>(w);
    } else if (w < 0 && errno == EINTR) {
      continue;
    } else {
      *error = w < 0 ? errno : ENOSPC;  // a write of 0 bytes: the device takes no more
      break;
    }
  }
  return done;
}

}  // namespace pbppo
