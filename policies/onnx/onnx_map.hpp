// The mapping file of an ONNX import: which element of the model's input each layout observation
// feeds (or the constant an input element gets), and which layout action each output element is.
// Nothing is guessed: every size and name is stated and checked against both the model and the
// robot's IO layout. Format (docs/onnx_import.md):
//
//   robot: quadruped
//   input: {name: obs, size: 48}
//   output: {name: actions, size: 12}
//   observations:          # one entry per input element, in order
//     - {constant: 0.0}    # an input the robot does not measure
//     - base_ang_vel_x     # a layout observation name
//   actions: [LF_HAA, ...] # one entry per output element, in order: layout action names
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/io_layout.hpp"

namespace pbppo::onnx {

struct Mapping {
  std::string origin;  // the file, for messages
  std::string robot;
  std::string input_name;
  std::uint32_t input_size = 0;
  std::string output_name;
  std::uint32_t output_size = 0;
  // Per input element: the layout observation index, or -1 for a constant.
  std::vector<std::int32_t> input_source;
  std::vector<double> input_constant;  // per input element (used where input_source is -1)
  // Per layout action: the output element that gives it.
  std::vector<std::uint32_t> output_of_action;
};

// Reads a mapping file and checks it against `layout`: the robot name, every name a layout
// observation or action, every layout observation fed exactly once, every layout action given by
// exactly one output element, the list lengths equal to the stated sizes.
Result<Mapping> LoadMapping(const std::string& path, const robot::IoLayout& layout);
Result<Mapping> ParseMapping(const std::string& yaml_text, const std::string& origin, const robot::IoLayout& layout);

}  // namespace pbppo::onnx
