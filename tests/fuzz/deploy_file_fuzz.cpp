// libFuzzer target: any text as a deploy file (pbppo import-onnx --deploy, policies/onnx/
// deploy_file.hpp: a deploy.yaml, or an Isaac Lab env.yaml read with the seed's joint order) for
// the shipped quadruped and a model of 51 inputs and 12 outputs (the seeds fit it). The file is refused with a message
// naming it, or read into an IO layout and a mapping that its own readers accepted, one action per policy joint and
// every model input fed from the layout or a constant.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "policies/onnx/deploy_file.hpp"
#include "policies/onnx/rsl_rl_agent.hpp"
#include "runtime/policy/policy_spec.hpp"
#include "runtime/robot/robot_model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pbppo;
  static const robot::RobotModel* robot = [] {
    auto r = robot::LoadRobotModel(std::string(PBPPO_SOURCE_DIR) + "/models/quadruped/robot.yaml");
    if (!r) std::abort();
    return new robot::RobotModel(std::move(*r));
  }();
  static const onnx::Model* model = [] {
    auto* m = new onnx::Model;
    m->origin = "fuzz.onnx";
    m->inputs = {{"obs", 51, true, {1, 51}, "", ""}};
    m->outputs = {{"actions", 12, true, {1, 12}, "", ""}};
    m->input = m->inputs[0];
    m->output = m->outputs[0];
    return m;
  }();
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto d = onnx::ParseDeployFile(text, "fuzz.yaml", *robot, *model, "l.yaml", "m.yaml");
  // An Isaac Lab env.yaml is refused for want of the articulation's joint order: again with the seed's. Only that
  // refusal: another message may quote the file's text, and a deploy.yaml is refused any joint order.
  if (!d && d.error().message.rfind("fuzz.yaml: top level: an Isaac Lab env.yaml does not hold the articulation's "
                                    "joint order",
                                    0) == 0) {
    static const std::vector<std::string> joints = {"LF_HAA", "RF_HAA", "LH_HAA", "RH_HAA", "LF_HFE", "RF_HFE",
                                                    "LH_HFE", "RH_HFE", "LF_KFE", "RF_KFE", "LH_KFE", "RH_KFE"};
    d = onnx::ParseDeployFile(text, "fuzz.yaml", *robot, *model, "l.yaml", "m.yaml", joints);
  }
  // The same text as the run's agent.yaml: read or refused naming the file; read, the actor checks
  // of two graphs (an MLP and an LSTM ahead of one) refuse naming it too, and its clip_actions
  // reaches the deploy reader.
  static const policy::PolicySpec* mlp =
      new policy::PolicySpec(policy::MakeRandomSpec({51, 128, 64, 32, 12}, policy::Activation::kElu, 1));
  static const policy::PolicySpec* lstm = new policy::PolicySpec(policy::MakeRandomRecurrentSpec(
      {51, 64, 32, 12}, policy::Activation::kElu, 0, policy::LayerKind::kLstm, false, 2));
  auto agent = onnx::ParseAgentFile(text, "fuzz.yaml");
  if (!agent) {
    if (agent.error().message.rfind("fuzz.yaml", 0) != 0) std::abort();
  } else {
    for (const policy::PolicySpec* s : {mlp, lstm})
      for (bool normalises : {false, true})
        if (auto c = onnx::CheckActor(*agent, *s, normalises); !c && c.error().message.rfind("fuzz.yaml", 0) != 0)
          std::abort();
    if (agent->clip_actions > 0) {
      auto clipped = onnx::ParseDeployFile(text, "fuzz.yaml", *robot, *model, "l.yaml", "m.yaml", {}, &*agent);
      if (clipped && d) {
        for (std::size_t k = 0; k < clipped->layout.actions.size(); ++k)
          if (clipped->layout.actions[k].low < d->layout.actions[k].low ||
              clipped->layout.actions[k].high > d->layout.actions[k].high)
            std::abort();  // a clip only narrows
      }
    }
  }
  if (!d) {
    const std::string& m = d.error().message;
    if (m.rfind("fuzz.yaml", 0) != 0 && m.rfind("l.yaml", 0) != 0 && m.rfind("m.yaml", 0) != 0) std::abort();
    return 0;
  }
  if (d->layout.actions.empty() || d->mapping.output_of_action.size() != d->layout.actions.size()) std::abort();
  if (d->mapping.input_source.size() != 51) std::abort();
  const auto n = static_cast<std::int32_t>(d->layout.observation_size());
  for (std::int32_t s : d->mapping.input_source)
    if (s < -1 || s >= n) std::abort();
  return 0;
}
