// A CAN or CAN FD frame as the codecs and the transport see it. No OS header: the SocketCAN
// transport converts to and from struct canfd_frame. Plain data, copyable, fixed size.
#pragma once

#include <cstdint>

namespace pbppo::can {

inline constexpr std::uint32_t kStandardIdMask = 0x7FF;
inline constexpr std::uint32_t kExtendedIdMask = 0x1FFFFFFF;
inline constexpr std::uint8_t kClassicMaxLen = 8;
inline constexpr std::uint8_t kFdMaxLen = 64;

enum FrameFlags : std::uint8_t {
  kFlagFd = 1u << 0,        // CAN FD frame (len up to 64)
  kFlagBrs = 1u << 1,       // FD bit-rate switch
  kFlagEsi = 1u << 2,       // FD error state indicator
  kFlagExtended = 1u << 3,  // 29-bit identifier
  kFlagRtr = 1u << 4,       // classic remote request
  kFlagError = 1u << 5,     // error frame from the controller (id holds the error class)
};

struct CanFrame {
  std::uint64_t timestamp_ns = 0;  // receive time (kernel stamp) or send time; 0 when unknown
  std::uint32_t id = 0;            // 11 or 29 bits, or the error class of an error frame
  std::uint8_t len = 0;            // payload bytes: 0..8 classic, 0..64 FD
  std::uint8_t flags = 0;          // FrameFlags
  std::uint8_t data[kFdMaxLen] = {};

  bool fd() const noexcept { return (flags & kFlagFd) != 0; }
  bool error() const noexcept { return (flags & kFlagError) != 0; }
};

// Valid CAN FD payload lengths are 0..8, 12, 16, 20, 24, 32, 48, 64.
constexpr bool IsValidFdLength(std::uint8_t len) noexcept {
  return len <= 8 || len == 12 || len == 16 || len == 20 || len == 24 || len == 32 || len == 48 || len == 64;
}

}  // namespace pbppo::can
