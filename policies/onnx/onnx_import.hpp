// ONNX actors into checked policy blobs (pbppo import-onnx). The importer walks the graph from its
// input to its output as one chain of nodes and recognises what MLP actors exported by rsl_rl,
// stable-baselines3 and similar trainers are made of:
//
//   input normaliser   Sub / Div / Mul / Add by constants, then an optional symmetric Clip
//                      -> the blob's normaliser (or, without a Clip, folded into the first layer)
//   layers             Gemm (transB 0 or 1, alpha, beta), or MatMul then Add, each followed by at
//                      most one of Relu, Tanh, Elu (alpha 1), LeakyRelu (alpha in [0, 1]);
//                      LSTM and GRU nodes (one forward step, default activations, no peepholes,
//                      GRU linear_before_reset 0 or 1) between Unsqueeze and Squeeze nodes, as
//                      torch exports them, their initial_h / initial_c graph inputs (or one-layer
//                      Slices of them) and Y_h / Y_c graph outputs (or Concats of them) paired in
//                      the mapping's state
//   output map         Mul / Add / Sub / Div by constants and Clip after the last layer
//                      -> folded into the blob's action map with the robot layout's own
//   Identity, Flatten (axis 1) and Constant nodes pass through.
//
// The mapping file (onnx_map.hpp) says which input element each layout observation feeds and
// which output element each layout action is; constant inputs are folded into the first layer's
// bias. Anything the engine cannot run exactly is refused, naming the node and its operator:
// other operators, branches, non-constant weights, non-float32 weights, a non-unit Elu alpha,
// dynamic dimensions other than the batch; a recurrent node run backwards or both ways, with
// peepholes, other activations, a clip, sequence lengths, a state that is not a graph input or
// whose next state is not fed back to it.
//
// The blob is then checked against an independent float64 evaluation of the original graph
// (onnx_eval.hpp) on its golden-vector rows before anything is written.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "policies/onnx/onnx_graph.hpp"
#include "policies/onnx/onnx_map.hpp"
#include "runtime/core/result.hpp"
#include "runtime/policy/policy_spec.hpp"
#include "runtime/policy/reference.hpp"
#include "runtime/robot/io_layout.hpp"

namespace pbppo::onnx {

struct ImportOptions {
  std::string source_name;    // the ONNX file's name, for the provenance
  std::string source_sha256;  // its SHA-256 (hex)
  std::string importer;       // "pbppo-rt 0.x (git abc)" for the provenance
  std::uint64_t golden_seed = 1;
  std::size_t golden_rows = 32;
};

struct Imported {
  policy::PolicySpec spec;
  policy::GoldenVectors golden;
  // What was recognised, one line per piece ("normaliser: Sub 'x' / Div 'y' / Clip 'z' at 100").
  std::vector<std::string> notes;
  bool graph_normaliser = false;  // the graph held an observation normaliser ahead of its first layer
  // The check against the graph evaluation: the largest |difference| over the golden rows and
  // all actions, and the largest difference in units of its tolerance (<= 1 passes).
  double check_max_abs = 0;
  double check_max_ratio = 0;
};

// The tolerance of the check (commands): each golden row's float32 error bound twice (the folding
// rounds parameters to float32 once more) plus 1e-5 relative for the normaliser's conversion.
double CheckTolerance(double bound, double value) noexcept;

Result<Imported> Import(const Model& model, const Mapping& mapping, const robot::IoLayout& layout,
                        const ImportOptions& options);

// The model's input row for a layout observation (the mapping's order, its constants).
std::vector<double> InputRow(const Mapping& mapping, std::span<const float> layout_observation);
// The commands the layout's action map makes of a model output row: per layout action,
// clamp(scale * output + offset, low, high), in float64.
std::vector<double> CommandsOf(const Mapping& mapping, const robot::IoLayout& layout, std::span<const double> output);
// The commands the graph itself gives (onnx_eval.hpp, float64) for layout observations in order:
// a recurrent model's state outputs fed back to its state inputs from one row to the next, zero at
// the start (the engine's state at arming).
Result<std::vector<std::vector<double>>> GraphCommands(const Model& model, const Mapping& mapping,
                                                       const robot::IoLayout& layout,
                                                       const std::vector<std::vector<float>>& observations);

}  // namespace pbppo::onnx
