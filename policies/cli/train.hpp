// `pbppo train`: its flags fill one trainer::TrainOptions (checked as they are read: errors name
// the flag and the value), and Train() runs it with a progress line and a clean Ctrl-C.
#pragma once

#include <string>
#include <vector>

#include "policies/envs/registry.hpp"
#include "policies/trainer/options.hpp"

namespace CLI {
class App;
}

namespace pbppo::cli {

// --env, --models and every environment's own flags that `use` takes (envs::FlagsFor): pbppo
// train's or pbppo eval's.
void AddEnvOptions(CLI::App& sub, envs::EnvOptions& env, envs::EnvFlag::Use use);
// `resume` (null: no --resume flag) receives --resume's folder.
void AddTrainOptions(CLI::App& sub, trainer::TrainOptions& options, bool& quiet, std::string* resume = nullptr);
// `args`: the arguments after `train`, as given (resume.bin records them; with --resume, only
// --threads and --quiet may be among them).
int Train(trainer::TrainOptions options, bool quiet, const std::string& resume, const std::vector<std::string>& args);

}  // namespace pbppo::cli
