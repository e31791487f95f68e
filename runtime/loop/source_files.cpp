#include "runtime/loop/source_files.hpp"

#include <filesystem>

#include "runtime/loop/policy_set.hpp"
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

// One blob: checked (signature, the engine, the self-test, the robot's layout) into a source.
struct LoadedPolicy {
  std::unique_ptr<policy::PolicyModel> model;
  std::unique_ptr<CommandSource> source;
  std::uint64_t hash = 0;
};
Result<LoadedPolicy> LoadPolicy(const robot::RobotModel& robot, const std::string& path, const SourceFiles& files,
                                std::span<const policy::PublicKey> keys) {
  LoadedPolicy p;
  auto bytes = robot::ReadTextFile(path);
  if (!bytes) return std::move(bytes).error();
  if (auto st = CheckSignature(keys, path, Bytes(*bytes)); !st) return st.error();
  auto model = policy::PolicyModel::FromBlob(Bytes(*bytes), {.kernel = files.kernel});
  if (!model) return MakeError(model.error().code, path + ": " + model.error().message);
  p.model = std::make_unique<policy::PolicyModel>(std::move(*model));
  if (files.self_test)
    if (auto st = policy::SelfTest(*p.model, path); !st)
      return MakeError(st.error().code, "refusing to arm: " + st.error().message);
  auto src = PolicySource::Create(robot, *p.model);
  if (!src) return MakeError(src.error().code, path + " on " + robot.path + ": " + src.error().message);
  p.source = std::move(*src);
  p.hash = LogHash(Bytes(*bytes));
  return p;
}

Result<LoadedSource> LoadSource(const robot::RobotModel& robot, const SourceFiles& files) {
  LoadedSource s;
  if (!files.policy.empty() && !files.trajectory.empty())
    return MakeError(ErrorCode::kInvalidValue, "--policy and --trajectory: one command source at a time");
  if (files.policy.empty() && !files.more_policies.empty())
    return MakeError(ErrorCode::kInvalidValue, "--switch-policy: needs --policy, the policy that runs first");
  if (!files.more_policies.empty() && robot.op.switch_policy < 0)
    return MakeError(ErrorCode::kInvalidValue,
                     "--switch-policy: " + robot.path + " has no operator.switch_policy field to switch with");
  if (!files.policy.empty()) {
    auto keys = TrustedKeys(robot);
    if (!keys) return std::move(keys).error();
    auto first = LoadPolicy(robot, files.policy, files, *keys);
    if (!first) return std::move(first).error();
    s.policy = std::move(first->model);
    s.source = std::move(first->source);
    s.kind = SourceKind::kPolicy;
    s.hash = first->hash;
    if (!files.more_policies.empty()) {
      std::vector<std::unique_ptr<CommandSource>> sources;
      sources.push_back(std::move(s.source));
      std::vector<std::uint64_t> hashes{s.hash};
      for (const std::string& path : files.more_policies) {
        auto p = LoadPolicy(robot, path, files, *keys);
        if (!p) return std::move(p).error();
        s.more_policies.push_back(std::move(p->model));
        sources.push_back(std::move(p->source));
        hashes.push_back(p->hash);
      }
      s.source = std::make_unique<PolicySet>(robot, std::move(sources));
      s.hash = LogHash({reinterpret_cast<const std::uint8_t*>(hashes.data()), hashes.size() * sizeof(std::uint64_t)});
    }
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
