// Signed policy blobs: a detached Ed25519 signature ("x.sig" beside "x.blob", OpenSSL's libcrypto)
// and the check a controller makes before arming when its robot file names trusted public keys
// (files.trusted_keys). A CRC catches accidents; a signature catches intent: a blob changed after
// signing, a blob signed by a key the robot does not trust, an unsigned blob, or the signature of
// another blob are refused, each with its own message. Set-up time only.
//
// The signature file is text, one field per line, in this order:
//
//   pbppo-blob-signature 1
//   algorithm: ed25519
//   key: <SHA-256 of the raw 32-byte public key, 64 hex digits>
//   blob-sha256: <SHA-256 of the blob's bytes, 64 hex digits>
//   blob-bytes: <the blob's size>
//   policy: <what the blob is: layout hash and provenance, printable ASCII>
//   signature: <Ed25519 signature, 128 hex digits>
//
// The signed message is "pbppo-blob-signature 1\n" followed by the four lines key .. policy as
// they appear in the file, so none of them can be changed without the signature failing.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/core/result.hpp"

namespace pbppo::policy {

struct BlobSignature {
  std::string key_id;       // 64 hex digits
  std::string blob_sha256;  // 64 hex digits
  std::uint64_t blob_bytes = 0;
  std::string policy;  // the blob's identity (BlobIdentity)
  std::array<std::uint8_t, 64> signature{};
};

// Parses a signature file (at most 4 KiB); errors name the origin, the line and the field.
Result<BlobSignature> ParseSignature(std::string_view text, const std::string& origin);
std::string FormatSignature(const BlobSignature& s);

// A trusted Ed25519 public key, from PEM ("-----BEGIN PUBLIC KEY-----").
struct PublicKey {
  std::string name;  // how the robot file names it
  std::string id;    // SHA-256 of the raw key, hex
  std::array<std::uint8_t, 32> raw{};
};
Result<PublicKey> ParsePublicKey(std::string_view pem, const std::string& name);

// What a blob is, for messages and the signature's policy line: its IO-layout hash, size and
// provenance ("io_layout 0x45b7f39b788bf22a, 68025 bytes, pbppo-rt 0.1.0 git 1a2b3c4d5e6f, env ...,
// seed 1, 6000000 steps"), or "not a decodable blob".
std::string BlobIdentity(std::span<const std::uint8_t> blob);

// Signs blob bytes with an unencrypted Ed25519 private key in PEM; errors name `key_origin`.
Result<BlobSignature> SignBlob(std::span<const std::uint8_t> blob, std::string_view private_pem,
                               const std::string& key_origin);

// The check before arming. `signature_text` is the signature file's content, or nullptr when there
// is none. Each refusal names the blob and the signature file and says which case it is.
Status VerifyBlob(std::span<const std::uint8_t> blob, const std::string& blob_path, const std::string* signature_text,
                  const std::string& signature_path, std::span<const PublicKey> trusted);

// The conventional signature path beside a blob: "x.blob" -> "x.sig".
std::string SignaturePathFor(const std::string& blob_path);

// SHA-256 as 64 lowercase hex digits.
std::string Sha256Hex(std::span<const std::uint8_t> bytes);

}  // namespace pbppo::policy
