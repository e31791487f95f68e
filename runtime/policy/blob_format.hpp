// Frozen policy blob, format v1 (docs/policy_blob.md). Shared by the writer and the loader.
#pragma once

#include <cstddef>
#include <cstdint>

namespace pbppo::policy {

inline constexpr char kBlobMagic[8] = {'P', 'B', 'P', 'P', 'O', 'P', 'O', 'L'};
inline constexpr std::uint32_t kBlobFormatVersion = 1;
inline constexpr std::uint32_t kBlobHeaderBytes = 48;
inline constexpr std::uint32_t kLayerRecordBytes = 16;

// Fixed header offsets.
inline constexpr std::size_t kOffMagic = 0;
inline constexpr std::size_t kOffVersion = 8;
inline constexpr std::size_t kOffHeaderBytes = 12;
inline constexpr std::size_t kOffFileBytes = 16;
inline constexpr std::size_t kOffInputSize = 24;
inline constexpr std::size_t kOffOutputSize = 28;
inline constexpr std::size_t kOffLayerCount = 32;
inline constexpr std::size_t kOffActionHead = 36;
inline constexpr std::size_t kOffIoLayoutHash = 40;

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
