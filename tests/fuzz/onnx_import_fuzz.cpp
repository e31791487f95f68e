// libFuzzer target: arbitrary bytes into the ONNX reader and importer (policies/onnx). A model is
// refused with a message, or imported into a blob that acts as its graph (the importer's own check)
// and runs on the engine with actions inside the action map's limits. The layout is made to fit the
// model's input and output sizes, so that mutations reach the importer behind the reader. Further
// graph inputs are paired with further outputs of the same shape, in order, as a recurrent
// model's state (the mapping's state), so that mutations of recurrent models reach their wiring;
// an imported recurrent policy runs several steps with its state carried.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "policies/onnx/onnx_import.hpp"
#include "runtime/policy/policy_model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pbppo;
  onnx::ReadLimits limits;
  limits.max_tensor_elements = 1u << 16;  // keep each input fast
  limits.max_nodes = 64;
  auto model = onnx::ParseModel({data, size}, "fuzz.onnx", limits);
  if (!model) {
    if (model.error().message.rfind("fuzz.onnx: ", 0) != 0) std::abort();
    return 0;
  }
  if (model->output.size > 8) return 0;
  const std::uint32_t n_obs = model->input.size < 8 ? model->input.size : 8;
  robot::IoLayout layout;
  layout.robot = "fuzzbot";
  onnx::Mapping map;
  map.origin = "fuzz.yaml";
  map.robot = "fuzzbot";
  map.input_name = model->input.name;
  map.input_size = model->input.size;
  map.output_name = model->output.name;
  map.output_size = model->output.size;
  for (std::uint32_t j = 0; j < n_obs; ++j) layout.observations.push_back({.name = "o" + std::to_string(j)});
  for (std::uint32_t j = 0; j < model->input.size; ++j) {
    map.input_source.push_back(j < n_obs ? static_cast<std::int32_t>(j) : -1);
    map.input_constant.push_back(j < n_obs ? 0.0 : 0.25);
  }
  std::vector<bool> paired(model->outputs.size(), false);
  for (std::size_t i = 1; i < model->inputs.size(); ++i)
    for (std::size_t j = 1; j < model->outputs.size(); ++j)
      if (!paired[j] && model->outputs[j].dims == model->inputs[i].dims && !model->inputs[i].dims.empty()) {
        paired[j] = true;
        map.state.push_back({model->inputs[i].name, model->outputs[j].name});
        break;
      }
  for (std::uint32_t k = 0; k < model->output.size; ++k) {
    layout.actions.push_back({.name = "a" + std::to_string(k),
                              .command = "c" + std::to_string(k),
                              .scale = 0.5,
                              .offset = 0.1,
                              .low = -2.0,
                              .high = 2.0});
    map.output_of_action.push_back(model->output.size - 1 - k);
  }
  auto imp = onnx::Import(*model, map, layout, {.golden_rows = 4});
  if (!imp) {
    if (imp.error().message.empty()) std::abort();
    return 0;
  }
  if (!(imp->check_max_ratio <= 1.0)) std::abort();
  auto pm = policy::PolicyModel::FromSpec(imp->spec);
  if (!pm) std::abort();  // a spec the importer validated must load
  auto pd = policy::MakePolicyData(*pm);
  if (!pd) std::abort();
  if (pm->recurrent() != imp->spec.Recurrent() || pd->state().size() != pm->state_size()) std::abort();
  for (int step = 0; step < 3; ++step) {
    for (std::size_t i = 0; i < pd->observation().size(); ++i)
      pd->observation()[i] = static_cast<float>((i + static_cast<std::size_t>(step)) % 5) - 2.0f;
    const policy::ForwardStatus st = policy::Forward(*pm, *pd);
    for (std::size_t k = 0; k < pd->action().size(); ++k) {
      const float a = pd->action()[k];
      if (std::isnan(a)) {
        if (st != policy::ForwardStatus::kNonFiniteAction) std::abort();
      } else if (!(a >= imp->spec.action_low[k] && a <= imp->spec.action_high[k])) {
        std::abort();
      }
    }
  }
  return 0;
}
