// A message's checksum as some robots' low-level messages carry it (robot.yaml `checksum`,
// runtime/robot/transport_spec.hpp): CRC-32/MPEG-2 (polynomial 0x04C11DB7, initial 0xFFFFFFFF, no
// reflection, no final XOR) over the message laid out as a little-endian C struct with natural
// alignment, taken as 32-bit words fed most significant bit first, every word but the last (the
// checksum itself). Fed word by word MSB first, the CRC equals the byte-wise CRC-32/MPEG-2 of each
// word's bytes from the most significant, which is how the table below runs. Set-up allocates the
// C layout's buffer; Compute does not allocate.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "runtime/robot/idl.hpp"

namespace pbppo::dds {

// CRC-32/MPEG-2 of `words`, each fed most significant bit first.
std::uint32_t Crc32Mpeg2Words(std::span<const std::uint32_t> words) noexcept;

class MessageChecksum {
 public:
  // `type`'s checksum in `leaf` (a uint32 that is the C struct's last word: the robot file's reader checks).
  MessageChecksum(const robot::IdlMessage& type, std::uint32_t leaf);
  // The checksum of a CDR sample (header included) in either byte order.
  std::uint32_t Compute(const std::byte* sample, bool big_endian) noexcept;
  // The leaf's CDR offset (where the checksum travels).
  std::uint32_t cdr_offset() const noexcept { return cdr_offset_; }
  // The C layout of the last sample Compute saw (padding zero).
  std::span<const std::uint32_t> c_words() const noexcept { return words_; }

 private:
  struct Copy {
    std::uint32_t cdr = 0, c = 0, size = 0;
  };
  std::vector<Copy> copies_;
  std::vector<std::uint32_t> words_;  // the C struct
  std::uint32_t cdr_offset_ = 0;
};

}  // namespace pbppo::dds
