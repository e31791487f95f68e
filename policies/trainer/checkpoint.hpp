// A resumable run's state file, OUT/resume.bin: the command line that started the run (so that
// `pbppo train --resume OUT` runs it again with the same options), the build that wrote it, and the
// runner's state after a whole iteration (Runner::SaveState: the networks and their optimisers, the
// normalisers, every generator, the rollout collected for the next update, each environment's
// episode so far as the actions to replay, the schedule's calls, the log's rows). Written atomically
// every --resume-every iterations and at a stop; removed when the run finishes.
//
// Layout: "PBPPO-RESUME" (12 bytes), version (u32, 1), the arguments (a count, then each a length and
// its bytes), the git revision (length, bytes), the state (length, bytes), then the FNV-1a 64-bit hash
// of everything before it.
#pragma once

#include <string>
#include <vector>

#include "runtime/core/result.hpp"

namespace pbppo::trainer {

inline constexpr const char* kResumeFile = "resume.bin";

struct ResumeFile {
  std::vector<std::string> args;  // pbppo train's arguments, as given
  std::string git_revision;       // of the build that wrote it
  std::vector<char> state;
};

Status WriteResumeFile(const std::string& path, const ResumeFile& file);
// Errors name the file and what is wrong with it (not a resume file, another version, damaged).
Result<ResumeFile> ReadResumeFile(const std::string& path);

}  // namespace pbppo::trainer
