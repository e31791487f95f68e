#include "runtime/policy/signature.hpp"

#include <openssl/bio.h>
#include <openssl/evp.h>
#include <openssl/pem.h>

#include <cinttypes>
#include <cstdio>
#include <memory>

#include "runtime/policy/blob.hpp"
#include "runtime/policy/openssl_handles.hpp"

namespace pbppo::policy {
namespace {

constexpr std::string_view kMagic = "pbppo-blob-signature 1";
constexpr std::size_t kMaxSignatureBytes = 4096;
constexpr std::size_t kMaxPolicyLine = 600;

using ossl::Bio;
using ossl::MdCtx;
using ossl::Pkey;

std::string Hex(std::span<const std::uint8_t> b) {
  static const char* d = "0123456789abcdef";
  std::string s;
  for (std::uint8_t c : b) {
    s += d[c >> 4];
    s += d[c & 15];
  }
  return s;
}

bool FromHex(std::string_view s, std::span<std::uint8_t> out) {
  if (s.size() != out.size() * 2) return false;
  auto nib = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    return -1;
  };
  for (std::size_t i = 0; i < out.size(); ++i) {
    const int h = nib(s[2 * i]), l = nib(s[2 * i + 1]);
    if (h < 0 || l < 0) return false;
    out[i] = static_cast<std::uint8_t>(h * 16 + l);
  }
  return true;
}

bool IsHex(std::string_view s, std::size_t n) {
  return s.size() == n && s.find_first_not_of("0123456789abcdef") == std::string_view::npos;
}

bool Printable(std::string_view s) {
  for (char c : s)
    if (c < 0x20 || c > 0x7e) return false;
  return true;
}

// Everything the signature covers.
std::string SignedMessage(const BlobSignature& s) {
  return std::string(kMagic) + "\nkey: " + s.key_id + "\nblob-sha256: " + s.blob_sha256 +
         "\nblob-bytes: " + std::to_string(s.blob_bytes) + "\npolicy: " + s.policy + "\n";
}

std::string Short(const std::string& hex) {
  return hex.substr(0, 16);
}

}  // namespace

std::string Sha256Hex(std::span<const std::uint8_t> bytes) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  EVP_Digest(bytes.data(), bytes.size(), md, &len, EVP_sha256(), nullptr);
  return Hex({md, len});
}

std::string SignaturePathFor(const std::string& blob_path) {
  return PathBeside(blob_path, ".sig");
}

std::string BlobIdentity(std::span<const std::uint8_t> blob) {
  auto spec = DecodeBlob(blob);
  if (!spec) return "not a decodable blob";
  const Provenance& p = spec->provenance;
  char head[96];
  std::snprintf(head, sizeof head, "io_layout 0x%016" PRIx64 ", %zu bytes, ", spec->io_layout_hash, blob.size());
  std::string s = head + p.trainer_version + ", git " + p.git_revision + ", env " + p.environment + ", seed " +
                  std::to_string(p.seed) + ", " + std::to_string(p.env_steps) + " steps";
  return s.substr(0, kMaxPolicyLine);
}

Result<BlobSignature> ParseSignature(std::string_view text, const std::string& origin) {
  auto fail = [&](int line, const std::string& what) {
    return MakeError(ErrorCode::kFormat, origin + ": line " + std::to_string(line) + ": " + what);
  };
  if (text.size() > kMaxSignatureBytes)
    return MakeError(ErrorCode::kLimit, origin + ": " + std::to_string(text.size()) +
                                            " bytes, more than a signature (" + std::to_string(kMaxSignatureBytes) +
                                            ")");
  std::vector<std::string_view> lines;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t nl = text.find('\n', at);
    if (nl == std::string_view::npos) return fail(static_cast<int>(lines.size()) + 1, "no end of line");
    lines.push_back(text.substr(at, nl - at));
    at = nl + 1;
  }
  if (lines.empty() || lines[0] != kMagic)
    return fail(1, "not a pbppo blob signature (expected '" + std::string(kMagic) + "')");
  static const char* const kFields[] = {"algorithm", "key", "blob-sha256", "blob-bytes", "policy", "signature"};
  if (lines.size() != 7)
    return fail(static_cast<int>(std::min<std::size_t>(lines.size(), 7)) + 1,
                std::to_string(lines.size()) + " lines, a signature has 7");
  std::string_view v[6];
  for (int i = 0; i < 6; ++i) {
    const std::string key = std::string(kFields[i]) + ": ";
    if (lines[static_cast<std::size_t>(i) + 1].substr(0, key.size()) != key)
      return fail(i + 2, "expected field '" + std::string(kFields[i]) + "'");
    v[i] = lines[static_cast<std::size_t>(i) + 1].substr(key.size());
  }
  if (v[0] != "ed25519") return fail(2, "algorithm: '" + std::string(v[0].substr(0, 32)) + "' (only ed25519)");
  BlobSignature s;
  if (!IsHex(v[1], 64)) return fail(3, "key: not 64 lowercase hex digits");
  s.key_id = v[1];
  if (!IsHex(v[2], 64)) return fail(4, "blob-sha256: not 64 lowercase hex digits");
  s.blob_sha256 = v[2];
  if (v[3].empty() || v[3].size() > 12 || v[3].find_first_not_of("0123456789") != std::string_view::npos ||
      (v[3].size() > 1 && v[3][0] == '0'))
    return fail(5, "blob-bytes: '" + std::string(v[3].substr(0, 32)) + "' is not a size");
  s.blob_bytes = std::stoull(std::string(v[3]));
  if (v[4].empty() || v[4].size() > kMaxPolicyLine || !Printable(v[4]))
    return fail(6, "policy: empty, longer than " + std::to_string(kMaxPolicyLine) + " or not printable ASCII");
  s.policy = v[4];
  if (!FromHex(v[5], s.signature)) return fail(7, "signature: not 128 lowercase hex digits");
  return s;
}

std::string FormatSignature(const BlobSignature& s) {
  return std::string(kMagic) + "\nalgorithm: ed25519\nkey: " + s.key_id + "\nblob-sha256: " + s.blob_sha256 +
         "\nblob-bytes: " + std::to_string(s.blob_bytes) + "\npolicy: " + s.policy +
         "\nsignature: " + Hex(s.signature) + "\n";
}

Result<PublicKey> ParsePublicKey(std::string_view pem, const std::string& name) {
  Bio bio(BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size())));
  if (!bio) return MakeError(ErrorCode::kIo, name + ": out of memory");
  Pkey key(PEM_read_bio_PUBKEY(bio.get(), nullptr, nullptr, nullptr));
  if (!key)
    return MakeError(ErrorCode::kFormat,
                     name + ": not a PEM public key ('-----BEGIN PUBLIC KEY-----'; openssl pkey -pubout makes one)");
  if (EVP_PKEY_get_id(key.get()) != EVP_PKEY_ED25519)
    return MakeError(
        ErrorCode::kUnsupported,
        name + ": a " +
            std::string(EVP_PKEY_get0_type_name(key.get()) ? EVP_PKEY_get0_type_name(key.get()) : "non-Ed25519") +
            " key; blobs are signed with Ed25519 keys");
  PublicKey k;
  k.name = name;
  std::size_t len = k.raw.size();
  if (EVP_PKEY_get_raw_public_key(key.get(), k.raw.data(), &len) != 1 || len != k.raw.size())
    return MakeError(ErrorCode::kFormat, name + ": its raw Ed25519 key cannot be read");
  k.id = Sha256Hex(k.raw);
  return k;
}

Result<BlobSignature> SignBlob(std::span<const std::uint8_t> blob, std::string_view private_pem,
                               const std::string& key_origin) {
  Bio bio(BIO_new_mem_buf(private_pem.data(), static_cast<int>(private_pem.size())));
  if (!bio) return MakeError(ErrorCode::kIo, key_origin + ": out of memory");
  // No passphrase prompt: an encrypted key is refused.
  auto no_pass = [](char*, int, int, void*) -> int { return -1; };
  Pkey key(PEM_read_bio_PrivateKey(bio.get(), nullptr, no_pass, nullptr));
  if (!key)
    return MakeError(ErrorCode::kFormat, key_origin +
                                             ": not an unencrypted PEM private key (openssl genpkey -algorithm "
                                             "ed25519 -out KEY makes one)");
  if (EVP_PKEY_get_id(key.get()) != EVP_PKEY_ED25519)
    return MakeError(ErrorCode::kUnsupported, key_origin + ": not an Ed25519 key; blobs are signed with Ed25519");
  std::array<std::uint8_t, 32> pub{};
  std::size_t len = pub.size();
  if (EVP_PKEY_get_raw_public_key(key.get(), pub.data(), &len) != 1)
    return MakeError(ErrorCode::kFormat, key_origin + ": its public half cannot be read");
  BlobSignature s;
  s.key_id = Sha256Hex(pub);
  s.blob_sha256 = Sha256Hex(blob);
  s.blob_bytes = blob.size();
  s.policy = BlobIdentity(blob);
  const std::string msg = SignedMessage(s);
  MdCtx ctx(EVP_MD_CTX_new());
  std::size_t sig_len = s.signature.size();
  if (!ctx || EVP_DigestSignInit(ctx.get(), nullptr, nullptr, nullptr, key.get()) != 1 ||
      EVP_DigestSign(ctx.get(), s.signature.data(), &sig_len, reinterpret_cast<const unsigned char*>(msg.data()),
                     msg.size()) != 1 ||
      sig_len != s.signature.size())
    return MakeError(ErrorCode::kUnsupported, key_origin + ": signing failed");
  return s;
}

Status VerifyBlob(std::span<const std::uint8_t> blob, const std::string& blob_path, const std::string* signature_text,
                  const std::string& signature_path, std::span<const PublicKey> trusted) {
  if (trusted.empty()) return {};
  std::string names;
  for (const PublicKey& k : trusted) names += (names.empty() ? "" : ", ") + k.name + " " + Short(k.id);
  const std::string refuse = "refusing to arm: ";
  if (signature_text == nullptr)
    return MakeError(ErrorCode::kMismatch, refuse + blob_path + " is not signed (no " + signature_path +
                                               "): the robot runs only policies signed by a trusted key (" + names +
                                               ")");
  auto sig = ParseSignature(*signature_text, signature_path);
  if (!sig) return MakeError(sig.error().code, refuse + sig.error().message);
  const PublicKey* key = nullptr;
  for (const PublicKey& k : trusted)
    if (k.id == sig->key_id) key = &k;
  if (key == nullptr)
    return MakeError(ErrorCode::kMismatch, refuse + signature_path + ": signed by key " + Short(sig->key_id) +
                                               ", which the robot does not trust (trusted: " + names + ")");
  const std::string sha = Sha256Hex(blob);
  if (sha != sig->blob_sha256 || blob.size() != sig->blob_bytes) {
    const std::string now = BlobIdentity(blob);
    if (now == sig->policy || now == "not a decodable blob")
      return MakeError(ErrorCode::kMismatch, refuse + blob_path + " changed after it was signed (sha256 " +
                                                 Short(sig->blob_sha256) + " signed, " + Short(sha) + " now" +
                                                 (now == sig->policy ? "" : "; it no longer decodes as a blob") + ")");
    return MakeError(ErrorCode::kMismatch, refuse + signature_path + " is the signature of another blob (" +
                                               sig->policy + "), not of " + blob_path + " (" + now + ")");
  }
  Pkey pk(EVP_PKEY_new_raw_public_key(EVP_PKEY_ED25519, nullptr, key->raw.data(), key->raw.size()));
  MdCtx ctx(EVP_MD_CTX_new());
  const std::string msg = SignedMessage(*sig);
  if (!pk || !ctx || EVP_DigestVerifyInit(ctx.get(), nullptr, nullptr, nullptr, pk.get()) != 1 ||
      EVP_DigestVerify(ctx.get(), sig->signature.data(), sig->signature.size(),
                       reinterpret_cast<const unsigned char*>(msg.data()), msg.size()) != 1)
    return MakeError(ErrorCode::kMismatch, refuse + signature_path +
                                               ": the signature does not verify with trusted key " + key->name +
                                               ": the signature file was altered, or not made with that key");
  return {};
}

}  // namespace pbppo::policy
