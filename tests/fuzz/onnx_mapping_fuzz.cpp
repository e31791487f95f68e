// libFuzzer target: arbitrary text as an ONNX import's mapping file (policies/onnx/onnx_map.cpp),
// against a layout whose elements keep several frames, so that mutations reach stacked histories
// in both orders. A mapping is refused with a message naming the file, or parsed into one source
// per input element in which every layout observation is fed exactly once and every action is
// given by exactly one output element.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "policies/onnx/onnx_map.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pbppo;
  static const robot::IoLayout layout = [] {
    auto l = robot::ParseIoLayout(R"(
robot: histbot
observations:
  - {name: p, history: 3}
  - {name: v0, history: 3}
  - {name: v1, history: 3}
  - {name: c}
actions: [{name: a0, command: c0}, {name: a1, command: c1}]
)",
                                  "histbot.yaml");
    if (!l) std::abort();
    return *l;
  }();
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto map = onnx::ParseMapping(text, "fuzz.yaml", layout);
  if (!map) {
    if (map.error().message.rfind("fuzz.yaml", 0) != 0) std::abort();
    return 0;
  }
  const std::uint32_t n = layout.observation_size();
  if (map->input_source.size() != map->input_size || map->input_constant.size() != map->input_size) std::abort();
  std::vector<int> fed(n, 0);
  for (std::int32_t s : map->input_source) {
    if (s < -1 || s >= static_cast<std::int32_t>(n)) std::abort();
    if (s >= 0) ++fed[static_cast<std::size_t>(s)];
  }
  for (int f : fed)
    if (f != 1) std::abort();
  if (map->output_of_action.size() != layout.action_size()) std::abort();
  std::vector<int> given(map->output_size, 0);
  for (std::uint32_t o : map->output_of_action) {
    if (o >= map->output_size) std::abort();
    ++given[o];
  }
  for (int g : given)
    if (g > 1) std::abort();
  return 0;
}
