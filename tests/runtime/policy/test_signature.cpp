// Signed blobs (runtime/policy/signature.hpp) with keys made here by OpenSSL: sign, verify, and
// each refusal with its own message: a blob changed after signing, a key the robot does not trust,
// no signature, the signature of another blob, an altered signature file; the signature file's
// parser names the line; keys that are not Ed25519 are refused. And the controller's path:
// LoadSource refuses to arm on an unsigned blob when the robot file names trusted keys.
#include <doctest/doctest.h>
#include <openssl/evp.h>
#include <openssl/pem.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "runtime/core/crc32.hpp"
#include "runtime/loop/source_files.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/signature.hpp"
#include "runtime/robot/robot_model.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;
using namespace pbppo::policy;

namespace {

struct KeyPair {
  std::string private_pem, public_pem;
};

KeyPair MakeKey(const char* type = "ED25519", const EVP_CIPHER* cipher = nullptr) {
  EVP_PKEY* k = std::string(type) == "RSA" ? EVP_PKEY_Q_keygen(nullptr, nullptr, "RSA", static_cast<size_t>(2048))
                                           : EVP_PKEY_Q_keygen(nullptr, nullptr, type);
  REQUIRE(k != nullptr);
  auto to_string = [](BIO* b) {
    char* data = nullptr;
    const long n = BIO_get_mem_data(b, &data);
    std::string s(data, static_cast<std::size_t>(n));
    BIO_free(b);
    return s;
  };
  BIO* priv = BIO_new(BIO_s_mem());
  static char pass[] = "secret";
  PEM_write_bio_PrivateKey(priv, k, cipher, reinterpret_cast<unsigned char*>(pass), cipher ? 6 : 0, nullptr, nullptr);
  BIO* pub = BIO_new(BIO_s_mem());
  PEM_write_bio_PUBKEY(pub, k);
  EVP_PKEY_free(k);
  return {to_string(priv), to_string(pub)};
}

std::vector<std::uint8_t> ReadBlob(const char* name) {
  auto b = ReadFileBytes(test::SourcePath(std::string("tests/data/blobs/") + name), 1u << 26);
  REQUIRE(b.ok());
  return *b;
}

PublicKey Trusted(const KeyPair& k, const std::string& name = "release") {
  auto p = ParsePublicKey(k.public_pem, name);
  REQUIRE_MESSAGE(p.ok(), p.error().message);
  return *p;
}

std::string Signed(const std::vector<std::uint8_t>& blob, const KeyPair& k) {
  auto s = SignBlob(blob, k.private_pem, "release.pem");
  REQUIRE_MESSAGE(s.ok(), s.error().message);
  return FormatSignature(*s);
}

std::string Verify(const std::vector<std::uint8_t>& blob, const std::string* sig, const std::vector<PublicKey>& keys) {
  auto st = VerifyBlob(blob, "p.blob", sig, "p.sig", keys);
  return st.ok() ? std::string("ok") : st.error().message;
}

}  // namespace

TEST_CASE("a signed blob verifies and its signature file round-trips") {
  const KeyPair k = MakeKey();
  const auto blob = ReadBlob("p1.blob");
  const std::string sig = Signed(blob, k);
  CHECK(Verify(blob, &sig, {Trusted(k)}) == "ok");
  auto parsed = ParseSignature(sig, "p.sig");
  REQUIRE(parsed.ok());
  CHECK(FormatSignature(*parsed) == sig);
  CHECK(parsed->blob_bytes == blob.size());
  CHECK(parsed->policy == BlobIdentity(blob));
  CHECK(parsed->policy.rfind("io_layout 0x", 0) == 0);
  CHECK(Verify(blob, nullptr, {}) == "ok");  // no trusted key: the robot runs unsigned blobs
  CHECK(SignaturePathFor("a/b/flat.blob") == "a/b/flat.sig");
  CHECK(SignaturePathFor("policy") == "policy.sig");
}

TEST_CASE("each refusal says which case it is") {
  const KeyPair k = MakeKey(), other = MakeKey();
  const auto blob = ReadBlob("p1.blob");
  const std::string sig = Signed(blob, k);
  const std::vector<PublicKey> trusted{Trusted(k)};

  CHECK(Verify(blob, nullptr, trusted)
            .find("refusing to arm: p.blob is not signed (no p.sig): the robot runs only "
                  "policies signed by a trusted key (release ") == 0);

  const std::string by_other = Signed(blob, other);
  CHECK(Verify(blob, &by_other, trusted)
            .find("refusing to arm: p.sig: signed by key " + Trusted(other).id.substr(0, 16) +
                  ", which the robot does not trust (trusted: release " + Trusted(k).id.substr(0, 16) + ")") == 0);

  auto changed = blob;  // one weight byte, CRC repaired: a valid blob, not the one signed
  changed[200] ^= 0x01;
  const std::uint32_t crc = Crc32(changed.data(), changed.size() - 4);
  std::memcpy(changed.data() + changed.size() - 4, &crc, 4);
  REQUIRE(DecodeBlob(changed).ok());
  CHECK(Verify(changed, &sig, trusted).find("refusing to arm: p.blob changed after it was signed (sha256 ") == 0);
  auto corrupt = blob;  // one byte, CRC not repaired
  corrupt[200] ^= 0x01;
  CHECK(Verify(corrupt, &sig, trusted).find("; it no longer decodes as a blob)") != std::string::npos);

  const auto p2 = ReadBlob("p2.blob");
  const std::string sig_p2 = Signed(p2, k);
  const std::string e = Verify(blob, &sig_p2, trusted);
  CHECK(e.find("refusing to arm: p.sig is the signature of another blob (" + BlobIdentity(p2) + "), not of p.blob (" +
               BlobIdentity(blob) + ")") == 0);

  std::string altered = sig;  // the signature's last hex digit
  const std::size_t at = altered.rfind('\n', altered.size() - 2) + std::string("signature: ").size() + 1;
  altered[at + 5] = altered[at + 5] == '0' ? '1' : '0';
  CHECK(Verify(blob, &altered, trusted) ==
        "refusing to arm: p.sig: the signature does not verify with trusted key release: the signature file was "
        "altered, or not made with that key");
  std::string relabelled = sig;  // the policy line, which the signature covers
  const std::size_t pl = relabelled.find("policy: ") + 8;
  relabelled[pl] = 'X';
  CHECK(Verify(blob, &relabelled, trusted).find("does not verify with trusted key release") != std::string::npos);
}

TEST_CASE("the signature parser names the line and the field") {
  const KeyPair k = MakeKey();
  const std::string good = Signed(ReadBlob("p3.blob"), k);
  auto line = [&](int n) {  // the n-th line (1-based) without its newline
    std::size_t at = 0;
    for (int i = 1; i < n; ++i) at = good.find('\n', at) + 1;
    return std::pair<std::size_t, std::size_t>{at, good.find('\n', at) - at};
  };
  auto with = [&](int n, const std::string& text) {
    std::string s = good;
    auto [at, len] = line(n);
    return s.replace(at, len, text);
  };
  auto err = [](const std::string& text) {
    auto r = ParseSignature(text, "p.sig");
    return r.ok() ? std::string("ok") : r.error().message;
  };
  CHECK(err(good) == "ok");
  CHECK(err("") == "p.sig: line 1: not a pbppo blob signature (expected 'pbppo-blob-signature 1')");
  CHECK(err(with(1, "pbppo-blob-signature 2")).find("p.sig: line 1: not a pbppo blob signature") == 0);
  CHECK(err(with(2, "algorithm: rsa")) == "p.sig: line 2: algorithm: 'rsa' (only ed25519)");
  CHECK(err(with(3, "key: 12")) == "p.sig: line 3: key: not 64 lowercase hex digits");
  CHECK(err(with(3, "kee: 12")) == "p.sig: line 3: expected field 'key'");
  CHECK(err(with(4, "blob-sha256: " + std::string(64, 'G'))) ==
        "p.sig: line 4: blob-sha256: not 64 lowercase hex digits");
  CHECK(err(with(5, "blob-bytes: 012")) == "p.sig: line 5: blob-bytes: '012' is not a size");
  CHECK(err(with(5, "blob-bytes: -1")) == "p.sig: line 5: blob-bytes: '-1' is not a size");
  CHECK(err(with(6, "policy: ")).find("p.sig: line 6: policy: empty") == 0);
  CHECK(err(with(7, "signature: abc")) == "p.sig: line 7: signature: not 128 lowercase hex digits");
  CHECK(err(good + "extra\n") == "p.sig: line 8: 8 lines, a signature has 7");
  CHECK(err(good.substr(0, good.size() - 1)) == "p.sig: line 7: no end of line");
  std::string crlf = good;
  crlf.insert(crlf.find('\n'), "\r");
  CHECK(err(crlf).find("p.sig: line 1: not a pbppo blob signature") == 0);
  CHECK(err(std::string(5000, 'a')) == "p.sig: 5000 bytes, more than a signature (4096)");
}

TEST_CASE("keys that are not Ed25519, encrypted or not keys at all are refused") {
  const KeyPair rsa = MakeKey("RSA");
  CHECK(ParsePublicKey(rsa.public_pem, "ops.pub").error().message ==
        "ops.pub: a RSA key; blobs are signed with Ed25519 keys");
  CHECK(ParsePublicKey("hello", "ops.pub").error().message.find("ops.pub: not a PEM public key") == 0);
  const auto blob = ReadBlob("p1.blob");
  CHECK(SignBlob(blob, rsa.private_pem, "rsa.pem").error().message ==
        "rsa.pem: not an Ed25519 key; blobs are signed with Ed25519");
  const KeyPair enc = MakeKey("ED25519", EVP_aes_256_cbc());
  CHECK(
      SignBlob(blob, enc.private_pem, "enc.pem").error().message.find("enc.pem: not an unencrypted PEM private key") ==
      0);
  CHECK(SignBlob(blob, MakeKey().public_pem, "pub.pem").error().message.find("pub.pem: not an unencrypted PEM") == 0);
}

TEST_CASE("LoadSource: a robot that trusts keys arms only on a blob signed by one of them") {
  const std::string dir = test::CopyRobotFolder("auv", "signature_robot");
  const KeyPair k = MakeKey();
  std::filesystem::create_directories(dir + "/keys");
  std::ofstream(dir + "/keys/release.pub") << k.public_pem;
  {  // files.trusted_keys.release
    std::ifstream in(dir + "/robot.yaml");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string files = "files:\n";
    REQUIRE(text.find(files) != std::string::npos);
    text.insert(text.find(files) + files.size(), "  trusted_keys: {release: keys/release.pub}\n");
    std::ofstream(dir + "/robot.yaml") << text;
  }
  auto robot = robot::LoadRobotModel(dir + "/robot.yaml");
  REQUIRE_MESSAGE(robot.ok(), robot.error().message);
  auto keys = loop::TrustedKeys(*robot);
  REQUIRE(keys.ok());
  CHECK(keys->size() == 1);
  const std::string scratch = test::ScratchDir("signature_blobs");
  const std::string blob = scratch + "/auv.blob";
  std::filesystem::copy_file(test::SourcePath("policies/frozen/auv_nav/auv_nav.blob"), blob);
  std::filesystem::copy_file(test::SourcePath("policies/frozen/auv_nav/auv_nav.golden"), scratch + "/auv.golden");
  loop::SourceFiles files;
  files.policy = blob;
  auto unsigned_load = loop::LoadSource(*robot, files);
  REQUIRE_FALSE(unsigned_load.ok());
  CHECK(unsigned_load.error().message.find("refusing to arm: " + blob + " is not signed") == 0);
  auto bytes = ReadFileBytes(blob, 1u << 26);
  REQUIRE(bytes.ok());
  std::ofstream(SignaturePathFor(blob)) << Signed(*bytes, k);
  auto signed_load = loop::LoadSource(*robot, files);
  CHECK_MESSAGE(signed_load.ok(), signed_load.error().message);
  // A robot file naming a key that is not a public key fails to give its keys, naming it.
  std::ofstream(dir + "/keys/release.pub") << "not a key";
  auto bad = robot::LoadRobotModel(dir + "/robot.yaml");
  REQUIRE(bad.ok());
  CHECK(loop::TrustedKeys(*bad).error().message.find("files.trusted_keys.release (") != std::string::npos);
}
