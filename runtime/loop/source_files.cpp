#include "runtime/loop/source_files.hpp"

#include <filesystem>

#include "runtime/loop/policy_source.hpp"
#include "runtime/policy/self_test.hpp"
#include "runtime/robot/text_file.hpp"

namespace pbppo::loop {
namespace {

std::span<const std::uint8_t> Bytes(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

}  // namespace

Result<std::vector<policy::PublicKey>> TrustedKeys(const robot::RobotModel& robot) {
  std::vector<policy::PublicKey> keys;
  for (const robot::TrustedKeyFile& k : robot.trusted_keys) {
    const std::string role = k.name == "trusted_keys" ? k.name : "trusted_keys." + k.name;
    auto key = policy::ParsePublicKey(k.file.text, "files." + role + " (" + k.file.path + ")");
    if (!key) return MakeError(key.error().code, robot.path + ": " + key.error().message);
    key->name = k.name;
    keys.push_back(std::move(*key));
  }
  return keys;
}

Status CheckSignature(std::span<const policy::PublicKey> trusted, const std::string& blob_path,
                      std::span<const std::uint8_t> blob, const std::string& signature_path) {
  if (trusted.empty()) return {};
  const std::string sig_path = signature_path.empty() ? policy::SignaturePathFor(blob_path) : signature_path;
  std::error_code ec;
  if (!std::filesystem::exists(sig_path, ec)) return policy::VerifyBlob(blob, blob_path, nullptr, sig_path, trusted);
  auto text = robot::ReadTextFile(sig_path);
  if (!text) return std::move(text).error();
  return policy::VerifyBlob(blob, blob_path, &*text, sig_path, trusted);
}

Result<LoadedSource> LoadSource(const robot::RobotModel& robot, const SourceFiles& files) {
  LoadedSource s;
  if (!files.policy.empty() && !files.trajectory.empty())
    return MakeError(ErrorCode::kInvalidValue, "--policy and --trajectory: one command source at a time");
  if (!files.policy.empty()) {
    auto bytes = robot::ReadTextFile(files.policy);
    if (!bytes) return std::move(bytes).error();
    auto keys = TrustedKeys(robot);
    if (!keys) return std::move(keys).error();
    if (auto st = CheckSignature(*keys, files.policy, Bytes(*bytes)); !st) return st.error();
    auto model = policy::PolicyModel::FromBlob(Bytes(*bytes), {.kernel = files.kernel});
    if (!model) return MakeError(model.error().code, files.policy + ": " + model.error().message);
    s.policy = std::make_unique<policy::PolicyModel>(std::move(*model));
    if (files.self_test)
      if (auto st = policy::SelfTest(*s.policy, files.policy); !st)
        return MakeError(st.error().code, "refusing to arm: " + st.error().message);
    auto src = PolicySource::Create(robot, *s.policy);
    if (!src) return MakeError(src.error().code, files.policy + " on " + robot.path + ": " + src.error().message);
    s.source = std::move(*src);
    s.kind = SourceKind::kPolicy;
    s.hash = LogHash(Bytes(*bytes));
  } else if (!files.trajectory.empty()) {
    // The robot's own trajectory was read with the robot; another file is read here.
    const std::optional<robot::RobotDocument>& own_file = robot.stand_trajectory;
    std::error_code ec;
    const bool own = own_file && std::filesystem::equivalent(own_file->path, files.trajectory, ec);
    auto text = own ? Result<std::string>(own_file->text) : robot::ReadTextFile(files.trajectory);
    if (!text) return std::move(text).error();
    auto t = ParseTrajectory(*text, std::filesystem::path(files.trajectory).filename().string(), robot);
    if (!t) return std::move(t).error();
    auto src = std::make_unique<TrajectorySource>(robot, std::move(*t));
    s.trajectory = src.get();
    s.source = std::move(src);
    s.kind = SourceKind::kTrajectory;
    s.hash = LogHash(Bytes(*text));
  }
  return s;
}

}  // namespace pbppo::loop
