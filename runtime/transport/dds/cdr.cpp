#include "runtime/transport/dds/cdr.hpp"

#include <cmath>
#include <cstring>
#include <limits>

namespace pbppo::dds {
namespace {

using robot::IdlScalar;

// The `n` bytes at `p` as a little-endian unsigned number (big_endian: reversed).
std::uint64_t Load(const std::byte* p, std::uint32_t n, bool big_endian) noexcept {
  std::uint64_t v = 0;
  for (std::uint32_t k = 0; k < n; ++k) {
    const auto b = static_cast<std::uint64_t>(p[big_endian ? n - 1 - k : k]);
    v |= b << (8 * k);
  }
  return v;
}

void Store(std::uint64_t v, std::uint32_t n, std::byte* p) noexcept {
  for (std::uint32_t k = 0; k < n; ++k) p[k] = static_cast<std::byte>((v >> (8 * k)) & 0xffu);
}

template <typename Int>
Int Saturate(double v) noexcept {
  if (std::isnan(v)) return 0;
  const double r = std::nearbyint(v);
  if (r <= static_cast<double>(std::numeric_limits<Int>::min())) return std::numeric_limits<Int>::min();
  // The largest 64-bit values are not doubles: compare against 2^63 / 2^64 exactly.
  if (r >= static_cast<double>(std::numeric_limits<Int>::max())) return std::numeric_limits<Int>::max();
  return static_cast<Int>(r);
}

std::int64_t SignExtend(std::uint64_t v, std::uint32_t bytes) noexcept {
  const std::uint32_t shift = 64 - 8 * bytes;
  return static_cast<std::int64_t>(v << shift) >> shift;
}

}  // namespace

void WriteCdrHeader(std::byte* sample) noexcept {
  sample[0] = std::byte{0x00};
  sample[1] = std::byte{0x01};  // CDR_LE
  sample[2] = std::byte{0x00};
  sample[3] = std::byte{0x00};
}

bool ReadCdrHeader(const std::byte* sample, bool* big_endian) noexcept {
  if (sample[0] != std::byte{0x00} || (sample[1] != std::byte{0x00} && sample[1] != std::byte{0x01})) return false;
  *big_endian = sample[1] == std::byte{0x00};
  return true;
}

double DecodeScalar(IdlScalar type, std::uint32_t cdr_offset, const std::byte* sample, bool big_endian) noexcept {
  const std::byte* p = sample + kCdrHeaderBytes + cdr_offset;
  const std::uint32_t n = robot::IdlScalarSize(type);
  const std::uint64_t raw = Load(p, n, big_endian);
  switch (type) {
    case IdlScalar::kBool: return raw != 0 ? 1.0 : 0.0;
    case IdlScalar::kChar:
    case IdlScalar::kInt8:
    case IdlScalar::kInt16:
    case IdlScalar::kInt32:
    case IdlScalar::kInt64: return static_cast<double>(SignExtend(raw, n));
    case IdlScalar::kUint8:
    case IdlScalar::kUint16:
    case IdlScalar::kUint32:
    case IdlScalar::kUint64: return static_cast<double>(raw);
    case IdlScalar::kFloat: {
      const auto bits = static_cast<std::uint32_t>(raw);
      float f = 0;
      std::memcpy(&f, &bits, sizeof f);
      return static_cast<double>(f);
    }
    case IdlScalar::kDouble: {
      double d = 0;
      std::memcpy(&d, &raw, sizeof d);
      return d;
    }
  }
  return 0;
}

void EncodeScalar(IdlScalar type, std::uint32_t cdr_offset, double value, std::byte* sample) noexcept {
  std::byte* p = sample + kCdrHeaderBytes + cdr_offset;
  const std::uint32_t n = robot::IdlScalarSize(type);
  std::uint64_t raw = 0;
  switch (type) {
    case IdlScalar::kBool: raw = value != 0 ? 1 : 0; break;
    case IdlScalar::kChar:
    case IdlScalar::kInt8: raw = static_cast<std::uint8_t>(Saturate<std::int8_t>(value)); break;
    case IdlScalar::kInt16: raw = static_cast<std::uint16_t>(Saturate<std::int16_t>(value)); break;
    case IdlScalar::kInt32: raw = static_cast<std::uint32_t>(Saturate<std::int32_t>(value)); break;
    case IdlScalar::kInt64: raw = static_cast<std::uint64_t>(Saturate<std::int64_t>(value)); break;
    case IdlScalar::kUint8: raw = Saturate<std::uint8_t>(value); break;
    case IdlScalar::kUint16: raw = Saturate<std::uint16_t>(value); break;
    case IdlScalar::kUint32: raw = Saturate<std::uint32_t>(value); break;
    case IdlScalar::kUint64: raw = Saturate<std::uint64_t>(value); break;
    case IdlScalar::kFloat: {
      const auto f = static_cast<float>(value);
      std::uint32_t bits = 0;
      std::memcpy(&bits, &f, sizeof bits);
      raw = bits;
      break;
    }
    case IdlScalar::kDouble: std::memcpy(&raw, &value, sizeof raw); break;
  }
  Store(raw, n, p);
}

}  // namespace pbppo::dds
