// A command source from its files, as a controller program and a replay load it: a policy blob
// (its signature checked when the robot trusts keys, then checked against the robot's IO layout,
// its golden vectors run through the engine first: the self-test at arming), a joint trajectory file (the robot's own
// stand_trajectory, read with the robot, or another), or none (the loop holds the default pose). `hash` (LogHash of the
// file's bytes) identifies the source in a recorded log. Set-up time only.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/loop/log.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/loop/trajectory_source.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/policy/signature.hpp"

namespace pbppo::loop {

struct SourceFiles {
  std::string policy;                             // a blob ("": none)
  std::string trajectory;                         // a trajectory file ("": none)
  bool self_test = true;                          // run the blob's golden vectors (refuse to arm on a mismatch)
  policy::Kernel kernel = policy::Kernel::kAuto;  // the forward kernel (one this CPU has)
  // More blobs: with them the source is a PolicySet (runtime/loop/policy_set.hpp) that the
  // operator's switch request moves through, `policy` first.
  std::vector<std::string> more_policies;
};

struct LoadedSource {
  std::unique_ptr<policy::PolicyModel> policy;
  std::vector<std::unique_ptr<policy::PolicyModel>> more_policies;  // SourceFiles::more_policies
  std::unique_ptr<CommandSource> source;                            // null: none
  TrajectorySource* trajectory = nullptr;                           // source, when it is a trajectory
  SourceKind kind = SourceKind::kNone;
  std::uint64_t hash = 0;  // several policies: LogHash of their hashes in order
};

// Errors name the file and what is wrong ("refusing to arm: golden vectors: row 3 ...").
// When the robot file names trusted keys (files.trusted_keys), a blob must carry a valid
// signature by one of them (CheckSignature) before anything else is done with it.
Result<LoadedSource> LoadSource(const robot::RobotModel& robot, const SourceFiles& files);

// The Ed25519 public keys the robot trusts: files.trusted_keys (one file) or files.trusted_keys.NAME
// (several), PEM; none: the robot runs unsigned blobs. Errors name the role and the file.
Result<std::vector<policy::PublicKey>> TrustedKeys(const robot::RobotModel& robot);

// The signature check of a blob's bytes against trusted keys (policy::VerifyBlob; none: passes),
// the signature read from `signature_path` (default policy::SignaturePathFor(blob_path)) if it
// exists.
Status CheckSignature(std::span<const policy::PublicKey> trusted, const std::string& blob_path,
                      std::span<const std::uint8_t> blob, const std::string& signature_path = "");

}  // namespace pbppo::loop
