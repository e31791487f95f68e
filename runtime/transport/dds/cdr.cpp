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

void WriteCdrLayout(const robot::IdlMessage& type, std::byte* sample) noexcept {
  WriteCdrHeader(sample);
  for (const robot::IdlItem& item : type.items) {
    if (item.kind == robot::IdlItem::Kind::kLeaf) continue;
    const bool string = item.kind == robot::IdlItem::Kind::kString;
    Store(string ? 1u : item.elements.size(), 4, sample + kCdrHeaderBytes + item.cdr_offset);
    if (string) sample[kCdrHeaderBytes + item.cdr_offset + 4] = std::byte{0};
  }
}

bool NormalizeCdrSample(const robot::IdlMessage& type, const std::byte* wire, std::size_t length,
                        std::byte* out) noexcept {
  bool big_endian = false;
  if (length < kCdrHeaderBytes || !ReadCdrHeader(wire, &big_endian)) return false;
  const std::byte* data = wire + kCdrHeaderBytes;
  const std::size_t size = length - kCdrHeaderBytes;
  std::byte* to = out + kCdrHeaderBytes;
  std::memcpy(out, wire, kCdrHeaderBytes);
  std::size_t at = 0;
  // The next `n`-byte primitive's place (aligned to its size), false past the end.
  auto next = [&](std::uint32_t n, std::size_t* where) {
    at = (at + n - 1) / n * n;
    if (at > size || size - at < n) return false;
    *where = at;
    at += n;
    return true;
  };
  // A length in the layout, in the sample's byte order.
  auto store_length = [&](std::uint32_t value, std::uint32_t offset) {
    for (std::uint32_t k = 0; k < 4; ++k)
      to[offset + (big_endian ? 3 - k : k)] = static_cast<std::byte>((value >> (8 * k)) & 0xffu);
  };
  for (const robot::IdlItem& item : type.items) {
    std::size_t where = 0;
    if (item.kind == robot::IdlItem::Kind::kLeaf) {
      const robot::IdlLeaf& l = type.leaves[item.leaf];
      const std::uint32_t n = robot::IdlScalarSize(l.type);
      if (!next(n, &where)) return false;
      std::memcpy(to + l.cdr_offset, data + where, n);
      continue;
    }
    if (!next(4, &where)) return false;
    const auto count = static_cast<std::uint32_t>(Load(data + where, 4, big_endian));
    if (item.kind == robot::IdlItem::Kind::kString) {
      // The length counts the terminating NUL (0: an empty string some writers send without one).
      if (count > size - at || (item.bound != 0 && count > item.bound + 1u)) return false;
      if (count > 0 && data[at + count - 1] != std::byte{0}) return false;
      at += count;
      store_length(1, item.cdr_offset);
      to[item.cdr_offset + 4] = std::byte{0};
      continue;
    }
    const std::uint32_t n = robot::IdlScalarSize(item.element);
    if (count < item.elements.size() || (item.bound != 0 && count > item.bound)) return false;
    if (count > 0) at = (at + n - 1) / n * n;
    if (at > size || (size - at) / n < count) return false;
    for (std::size_t k = 0; k < item.elements.size(); ++k)
      std::memcpy(to + type.leaves[item.elements[k]].cdr_offset, data + at + k * n, n);
    at += static_cast<std::size_t>(count) * n;
    store_length(static_cast<std::uint32_t>(item.elements.size()), item.cdr_offset);
  }
  return true;
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
