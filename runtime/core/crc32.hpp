// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320; the zlib/PNG checksum).
#pragma once

#include <cstddef>
#include <cstdint>

namespace pbppo {

// Continues a CRC: pass the previous result as `crc` (0 to start).
std::uint32_t Crc32(const void* data, std::size_t size, std::uint32_t crc = 0) noexcept;

}  // namespace pbppo
