// Writing and loading frozen policy blobs (format v1). Set-up time only.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/policy/blob_format.hpp"
#include "runtime/policy/policy_spec.hpp"

namespace pbppo::policy {

// Checks every field of a spec: sizes against `limits`, chained layer widths, array lengths,
// finite values, positive 1/std and clip, low <= high, names, a leaky_relu alpha in [0, 1] (and
// alpha 0 on every other layer). Errors name the field and value.
Status ValidateSpec(const PolicySpec& spec, const BlobLimits& limits = {});

// Serialises a valid spec (validated first) into blob bytes, CRC included.
Result<std::vector<std::uint8_t>> EncodeBlob(const PolicySpec& spec);

// Parses and validates blob bytes. Sizes are checked against `limits` before any allocation.
Result<PolicySpec> DecodeBlob(std::span<const std::uint8_t> bytes, const BlobLimits& limits = {});

// Reads a whole file (at most limits.max_file_bytes) and decodes it; errors start with the path.
Result<PolicySpec> ReadBlobFile(const std::string& path, const BlobLimits& limits = {});

// A file beside a blob: its extension replaced ("x.blob" -> "x" + extension), or added when it
// has none. The golden vectors (GoldenPathFor) and the signature (SignaturePathFor) live there.
std::string PathBeside(const std::string& blob_path, const std::string& extension);

// Reads a whole file of at most `max_bytes` (checked before reading); errors start with the path.
Result<std::vector<std::uint8_t>> ReadFileBytes(const std::string& path, std::uint64_t max_bytes);

// Writes bytes to `path` atomically: a temporary file beside it, fsync, rename. On failure the
// previous file at `path`, if any, is untouched and no temporary is left behind.
Status WriteFileAtomic(const std::string& path, std::span<const std::uint8_t> bytes);

// Several files together, each as WriteFileAtomic writes one: every temporary file written and
// flushed before the first rename, the renames in the order given. An error while writing (a path
// that is a folder, a missing folder, a full disk) leaves every previous file untouched and no
// temporary behind; a rename that fails after others succeeded names the files already replaced.
struct FileBytes {
  std::string path;
  std::span<const std::uint8_t> bytes;
};
Status WriteFilesAtomic(std::span<const FileBytes> files);

// EncodeBlob + WriteFileAtomic.
Status WriteBlobFile(const std::string& path, const PolicySpec& spec);

}  // namespace pbppo::policy
