// A float64 interpreter of the ONNX graphs the importer accepts, node by node in file order, on
// the model's own weights: the independent reference an imported blob is checked against. It
// shares nothing with the importer's recognition of layers and folding; it knows the semantics of
// each operator (Gemm, MatMul, Add, Sub, Mul, Div, Clip, Relu, LeakyRelu, Elu, Tanh, Identity,
// Flatten) for one row. Set-up/test time code.
#pragma once

#include <span>
#include <vector>

#include "policies/onnx/onnx_graph.hpp"
#include "runtime/core/result.hpp"

namespace pbppo::onnx {

// The model's output for one input row (model.input.size values).
Result<std::vector<double>> Evaluate(const Model& model, std::span<const double> input);

}  // namespace pbppo::onnx
