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
//     - [dof_pos_0, dof_pos_1]   # or a list of them (the same as listing them one by one)
//   actions: [LF_HAA, ...] # one entry per output element, in order: layout action names
//
// A model fed stacked history names each term once and states the stacking:
//
//   history: {length: 5, order: term-major, oldest: first}
//   observations:          # one frame's terms, in order; each a name, a list of names or a constant
//     - [base_ang_vel_x, base_ang_vel_y, base_ang_vel_z]
//     - {term: [cmd_vx, cmd_vy], history: 1}   # term-major only: a term with its own frame count
//
// A recurrent model (LSTM or GRU nodes) takes its state as graph inputs and gives the next state
// as graph outputs; the mapping pairs them, each output fed back to its input at the next step:
//
//   state:
//     - {input: h_in, output: h_out}
//     - {input: c_in, output: c_out}
//
// frame-major: frame 1's terms, then frame 2's, ...; term-major: term 1's frames (each frame its
// components), then term 2's, .... oldest first: frames run from length-1 policy steps ago to now;
// last: from now back. Frame k steps ago of element X is the layout's "X@-k" (its history must
// reach that far); a constant is repeated in every frame.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/io_layout.hpp"

namespace pbppo::onnx {

// A recurrent state: the graph input it is read from and the graph output that gives it next.
struct StatePair {
  std::string input;
  std::string output;
};

struct Mapping {
  std::string origin;  // the file, for messages
  std::string robot;
  std::string input_name;
  std::uint32_t input_size = 0;
  std::string output_name;
  std::uint32_t output_size = 0;
  std::vector<StatePair> state;  // a recurrent model's (empty for a feed-forward one)
  // The stacked history the model takes (stacked: the mapping states one).
  bool stacked = false;
  std::uint32_t history_length = 1;
  bool frame_major = false;
  bool oldest_first = false;
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
