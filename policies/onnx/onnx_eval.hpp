// A float64 interpreter of the ONNX graphs the importer accepts, node by node in file order, on
// the model's own weights: the independent reference an imported blob is checked against. It
// shares nothing with the importer's recognition of layers and folding; it knows the semantics of
// each operator (Gemm, MatMul, Add, Sub, Mul, Div, Clip, Relu, LeakyRelu, Elu, Tanh, Identity,
// Flatten, Unsqueeze, Squeeze, Slice, Concat, and LSTM and GRU as the ONNX operators define them)
// for one row. Set-up/test time code.
#pragma once

#include <map>
#include <span>
#include <string>
#include <vector>

#include "policies/onnx/onnx_graph.hpp"
#include "runtime/core/result.hpp"

namespace pbppo::onnx {

// Values by graph input or output name, row-major, the batch dimension 1.
using Feeds = std::map<std::string, std::vector<double>>;

// Every graph output of the model for every graph input given (each of its port's element count).
Result<Feeds> EvaluateGraph(const Model& model, const Feeds& inputs);

// The model's first output for one input row of its first input (model.input.size values).
Result<std::vector<double>> Evaluate(const Model& model, std::span<const double> input);

}  // namespace pbppo::onnx
