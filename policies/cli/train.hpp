// `pbppo train`: its flags fill one trainer::TrainOptions (checked as they are read: errors name
// the flag and the value), and Train() runs it with a progress line and a clean Ctrl-C.
#pragma once

#include "policies/trainer/options.hpp"

namespace CLI {
class App;
}

namespace pbppo::cli {

// The environment's flags, shared by train and eval: --env, --layout, --terrain, --commands,
// --contact-forces, --models.
void AddEnvOptions(CLI::App& sub, envs::EnvOptions& env);
void AddTrainOptions(CLI::App& sub, trainer::TrainOptions& options, bool& quiet);
int Train(trainer::TrainOptions options, bool quiet);

}  // namespace pbppo::cli
