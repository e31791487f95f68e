// A message's samples in plain CDR (XCDR1, the encoding Fast DDS and Cyclone DDS give final
// structs), as the robot's IDL lays them out (runtime/robot/idl.hpp): a sample is the 4-byte
// encapsulation header and the data. Samples are written little-endian; either byte order is
// read. Pure functions, no DDS header; real-time safe (no allocation).
//
// Leaves are read as doubles: integers exactly up to 2^53 (beyond, the nearest double), booleans
// as 0 or 1. Written from doubles: floats rounded to nearest, integers rounded to nearest and
// saturated at the type's range (NaN: 0), booleans true when not 0.
#pragma once

#include <cstddef>
#include <cstdint>

#include "runtime/robot/idl.hpp"

namespace pbppo::dds {

inline constexpr std::size_t kCdrHeaderBytes = 4;

// The bytes of one sample of `type`: header and data.
inline std::size_t CdrSampleBytes(const robot::IdlMessage& type) noexcept {
  return kCdrHeaderBytes + type.cdr_size;
}

// Writes the header of a little-endian plain CDR sample (CDR_LE, no options).
void WriteCdrHeader(std::byte* sample) noexcept;
// Writes the header and, for a message with strings or sequences, the lengths of its layout (each
// string empty, each sequence with the layout's count): a sample of `type` ready for its leaves.
void WriteCdrLayout(const robot::IdlMessage& type, std::byte* sample) noexcept;

// The largest sample of a message with strings or sequences taken from the wire (header included).
inline constexpr std::size_t kMaxWireSampleBytes = kCdrHeaderBytes + 65536;
// A sample of a message with strings or sequences as it came (`wire`, `length` bytes, the header
// first) rewritten into the message's layout at `out` (CdrSampleBytes of `type`), in its byte
// order: each leaf's value, each sequence's first elements (the layout's count), each string
// empty. False, `out` not to be used, when the sample is not plain CDR, a length runs past its
// end, a sequence holds fewer elements than the layout or more than its bound, or a string is
// longer than its bound or not terminated. No allocation.
bool NormalizeCdrSample(const robot::IdlMessage& type, const std::byte* wire, std::size_t length,
                        std::byte* out) noexcept;
// Reads a header: true for plain CDR (CDR_BE or CDR_LE), with its byte order in *big_endian;
// false for anything else (parameter lists, XCDR2).
bool ReadCdrHeader(const std::byte* sample, bool* big_endian) noexcept;

// The value of the `type` at `cdr_offset` (from the data's start) in `sample` (header included).
double DecodeScalar(robot::IdlScalar type, std::uint32_t cdr_offset, const std::byte* sample, bool big_endian) noexcept;
// Writes `value` as the `type` at `cdr_offset` (little-endian).
void EncodeScalar(robot::IdlScalar type, std::uint32_t cdr_offset, double value, std::byte* sample) noexcept;

// The same for a leaf of the sample's message.
inline double DecodeLeaf(const robot::IdlLeaf& leaf, const std::byte* sample, bool big_endian) noexcept {
  return DecodeScalar(leaf.type, leaf.cdr_offset, sample, big_endian);
}
inline void EncodeLeaf(const robot::IdlLeaf& leaf, double value, std::byte* sample) noexcept {
  EncodeScalar(leaf.type, leaf.cdr_offset, value, sample);
}

}  // namespace pbppo::dds
