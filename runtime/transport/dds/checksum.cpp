#include "runtime/transport/dds/checksum.hpp"

#include <array>
#include <bit>
#include <cstring>

#include "runtime/transport/dds/cdr.hpp"

namespace pbppo::dds {

static_assert(std::endian::native == std::endian::little, "the C layout is written in the host's byte order");

namespace {

constexpr std::uint32_t kPoly = 0x04C11DB7u;

constexpr std::array<std::uint32_t, 256> MakeTable() {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t b = 0; b < 256; ++b) {
    std::uint32_t c = b << 24;
    for (int k = 0; k < 8; ++k) c = (c & 0x80000000u) != 0 ? (c << 1) ^ kPoly : c << 1;
    t[b] = c;
  }
  return t;
}

constexpr std::array<std::uint32_t, 256> kTable = MakeTable();

}  // namespace

std::uint32_t Crc32Mpeg2Words(std::span<const std::uint32_t> words) noexcept {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const std::uint32_t w : words)
    for (int shift = 24; shift >= 0; shift -= 8) crc = (crc << 8) ^ kTable[((crc >> 24) ^ (w >> shift)) & 0xFFu];
  return crc;
}

MessageChecksum::MessageChecksum(const robot::IdlMessage& type, std::uint32_t leaf)
    : words_(type.c_size / 4, 0), cdr_offset_(type.leaves[leaf].cdr_offset) {
  for (const robot::IdlLeaf& l : type.leaves)
    copies_.push_back({l.cdr_offset, l.c_offset, robot::IdlScalarSize(l.type)});
}

std::uint32_t MessageChecksum::Compute(const std::byte* sample, bool big_endian) noexcept {
  auto* c = reinterpret_cast<unsigned char*>(words_.data());
  const std::byte* data = sample + kCdrHeaderBytes;
  for (const Copy& k : copies_) {
    unsigned char v[8];
    std::memcpy(v, data + k.cdr, k.size);
    if (big_endian)
      for (std::uint32_t i = 0; i < k.size / 2; ++i) std::swap(v[i], v[k.size - 1 - i]);
    std::memcpy(c + k.c, v, k.size);  // little-endian hosts (x86-64, arm64): the C layout's bytes
  }
  return Crc32Mpeg2Words(std::span<const std::uint32_t>(words_).first(words_.size() - 1));
}

}  // namespace pbppo::dds
