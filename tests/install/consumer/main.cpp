// A user's controller project: loads a blob through the installed runtime and runs it.
#include <cmath>
#include <cstdio>

#include "runtime/policy/policy_model.hpp"

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  auto model = pbppo::policy::PolicyModel::FromFile(argv[1]);
  if (!model) {
    std::fprintf(stderr, "%s\n", model.error().message.c_str());
    return 1;
  }
  auto data = pbppo::policy::MakePolicyData(*model);
  if (!data) return 1;
  for (float& o : data->observation()) o = 0.25f;
  if (pbppo::policy::Forward(*model, *data) != pbppo::policy::ForwardStatus::kOk) return 1;
  for (float a : data->action()) {
    if (!std::isfinite(a)) return 1;
  }
  std::printf("consumer: %u -> %u policy ran, action[0] = %g (kernel %s)\n", model->input_size(), model->output_size(),
              static_cast<double>(data->action()[0]), pbppo::policy::ToString(model->kernel()));
  return 0;
}
