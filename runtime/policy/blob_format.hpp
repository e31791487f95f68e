// Frozen policy blob, formats v1 and v2 (docs/policy_blob.md). Shared by the writer and the loader.
// v2 adds recurrent layers (a longer layer record and the recurrent weights); the writer uses v1
// for a policy without them, so feed-forward blobs are the same bytes as before v2 existed.
#pragma once

#include <cstddef>
#include <cstdint>

namespace pbppo::policy {

inline constexpr char kBlobMagic[8] = {'P', 'B', 'P', 'P', 'O', 'P', 'O', 'L'};
inline constexpr std::uint32_t kBlobFormatVersion = 2;       // the newest this code reads
inline constexpr std::uint32_t kBlobFeedForwardVersion = 1;  // written for dense layers only
inline constexpr std::uint32_t kBlobHeaderBytes = 48;
inline constexpr std::uint32_t kLayerRecordBytes = 16;           // v1: in, out, activation, alpha
inline constexpr std::uint32_t kLayerRecordBytesV2 = 24;         // v2: ... kind, flags
inline constexpr std::uint32_t kLayerFlagLinearBeforeReset = 1;  // v2 flags bit 0 (GRU only)

// The fixed header: each field's offset in bytes (its type after it).
enum BlobHeaderOffset : std::size_t {
  kOffMagic = 0,          // 8 bytes
  kOffVersion = 8,        // u32
  kOffHeaderBytes = 12,   // u32
  kOffFileBytes = 16,     // u64
  kOffInputSize = 24,     // u32
  kOffOutputSize = 28,    // u32
  kOffLayerCount = 32,    // u32
  kOffActionHead = 36,    // u32
  kOffIoLayoutHash = 40,  // u64
};

// Capacity limits checked before anything is allocated. Callers may tighten them.
struct BlobLimits {
  std::uint32_t max_input = 1024;
  std::uint32_t max_output = 256;
  std::uint32_t max_layers = 16;
  std::uint32_t max_width = 2048;
  std::uint64_t max_parameters = 16u * 1024u * 1024u;
  std::uint64_t max_file_bytes = 128u * 1024u * 1024u;
  std::uint32_t max_name_bytes = 64;
  std::uint32_t max_text_bytes = 256;
};

}  // namespace pbppo::policy
