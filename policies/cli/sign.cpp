#include "policies/cli/sign.hpp"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>

#include "runtime/loop/source_files.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/signature.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/robot/text_file.hpp"

namespace pbppo::cli {
namespace {

int Fail(const char* cmd, const std::string& m) {
  std::fprintf(stderr, "pbppo %s: %s\n", cmd, m.c_str());
  return 1;
}

constexpr std::uint64_t kMaxBlobBytes = policy::BlobLimits{}.max_file_bytes;

}  // namespace

CLI::App* AddSign(CLI::App& app, SignOptions& o) {
  auto* c = app.add_subcommand("sign", "Sign a policy blob with an Ed25519 key (a detached signature beside it)");
  c->add_option("blob", o.blob, "Policy blob")->required();
  c->add_option("--key", o.key, "Ed25519 private key, PEM, unencrypted (tools/security/make_signing_key.sh)")
      ->required();
  c->add_option("--out", o.out, "Signature file (default: the blob's name with .sig)");
  return c;
}

CLI::App* AddVerify(CLI::App& app, VerifyOptions& o) {
  auto* c = app.add_subcommand("verify", "Check a policy blob's signature as a controller does before arming");
  c->add_option("blob", o.blob, "Policy blob")->required();
  auto* robot = c->add_option("--robot", o.robot, "Robot file: its trusted keys (files.trusted_keys)");
  auto* keys = c->add_option("--key", o.keys, "A trusted Ed25519 public key, PEM (repeatable)");
  robot->excludes(keys);
  c->add_option("--signature", o.signature, "Signature file (default: the blob's name with .sig)");
  return c;
}

int Sign(const SignOptions& o) {
  auto blob = policy::ReadFileBytes(o.blob, kMaxBlobBytes);
  if (!blob) return Fail("sign", blob.error().message);
  if (auto spec = policy::DecodeBlob(*blob); !spec)
    return Fail("sign", o.blob + ": not a valid blob, not signed: " + spec.error().message);
  auto key = robot::ReadTextFile(o.key);
  if (!key) return Fail("sign", key.error().message);
  auto sig = policy::SignBlob(*blob, *key, o.key);
  if (!sig) return Fail("sign", sig.error().message);
  const std::string out = o.out.empty() ? policy::SignaturePathFor(o.blob) : o.out;
  const std::string text = policy::FormatSignature(*sig);
  if (auto st = policy::WriteFileAtomic(out, {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()}); !st)
    return Fail("sign", st.error().message);
  std::printf("signed %s (sha256 %s) with key %s: %s\n", o.blob.c_str(), sig->blob_sha256.c_str(),
              sig->key_id.substr(0, 16).c_str(), out.c_str());
  return 0;
}

int Verify(const VerifyOptions& o) {
  std::vector<policy::PublicKey> keys;
  if (!o.robot.empty()) {
    auto robot = robot::LoadRobotModel(o.robot);
    if (!robot) return Fail("verify", robot.error().message);
    auto k = loop::TrustedKeys(*robot);
    if (!k) return Fail("verify", k.error().message);
    if (k->empty()) return Fail("verify", o.robot + ": files: no trusted_keys (the robot runs unsigned blobs)");
    keys = std::move(*k);
  }
  for (const std::string& path : o.keys) {
    auto pem = robot::ReadTextFile(path);
    if (!pem) return Fail("verify", pem.error().message);
    auto k = policy::ParsePublicKey(*pem, std::filesystem::path(path).filename().string());
    if (!k) return Fail("verify", path + ": " + k.error().message);
    keys.push_back(std::move(*k));
  }
  if (keys.empty()) return Fail("verify", "no trusted key: give --robot or --key");
  auto blob = policy::ReadFileBytes(o.blob, kMaxBlobBytes);
  if (!blob) return Fail("verify", blob.error().message);
  if (auto st = loop::CheckSignature(keys, o.blob, *blob, o.signature); !st) return Fail("verify", st.error().message);
  std::printf("verified %s: signed by a trusted key, unchanged since\n", o.blob.c_str());
  return 0;
}

}  // namespace pbppo::cli
