// An ONNX model as plain data: its one input and output, its constants (initializers and Constant
// nodes, float32 only, read as doubles) and its nodes in file order. The only reader of ONNX files
// in the project (ReadOnnxModel); what it refuses is what no importer could run exactly: a file
// that is not an ONNX model, external or sparse data, symbolic dimensions other than the batch,
// control flow, operator sets of other domains. Set-up time only.
#pragma once

#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"

namespace pbppo::onnx {

// A constant tensor. Only float32 tensors carry values; others keep their type for the refusal
// that names the node using them.
struct Tensor {
  std::string name;
  std::int32_t data_type = 0;  // TensorProto.DataType: 1 float32, 10 float16, 11 float64, ...
  std::vector<std::int64_t> dims;
  std::vector<double> values;      // float32 values, exactly (empty unless data_type is float32)
  std::vector<std::int64_t> ints;  // int64 and int32 values (axes, starts, ends of shape operators)

  bool is_float32() const noexcept { return data_type == 1; }
  std::string Shape() const;  // "[512, 48]", "[]" for a scalar
};

const char* DataTypeName(std::int32_t data_type) noexcept;

struct Attribute {
  std::string name;
  enum class Kind : std::uint8_t { kFloat, kInt, kFloats, kInts, kString, kOther } kind = Kind::kOther;
  double f = 0;
  std::int64_t i = 0;
  std::vector<double> floats;
  std::vector<std::int64_t> ints;
  std::string s;
};

struct Node {
  std::size_t index = 0;  // position in the graph
  std::string name;
  std::string op;
  std::string domain;               // "" for the default operator set
  std::vector<std::string> inputs;  // "" marks an omitted optional input
  std::vector<std::string> outputs;
  std::vector<Attribute> attributes;

  const Attribute* Find(const char* attribute) const noexcept;
  // "node 'actor.0' (Gemm)", or "node #3 (Gemm)" when it has no name: how errors name it.
  std::string Label() const;
};

// A graph input or output: a float32 tensor [batch, size] (or [size]), or a recurrent state
// [layers, batch, size].
struct Port {
  std::string name;
  std::uint32_t size = 0;          // the last dimension
  bool has_batch = false;          // rank 2 or 3
  std::vector<std::int64_t> dims;  // the batch as 1
  std::string users;               // inputs: "node 'x' (Gemm) input 0, ..." or "no node", for messages
  std::string problem;             // why the engine cannot take it (empty if it can): one of several ports
};

struct Model {
  std::string origin;  // the file name, for messages
  std::int64_t ir_version = 0;
  std::int64_t opset = 0;  // of the default domain
  std::string producer_name;
  std::string producer_version;
  // Every graph input that is not an initializer, and every graph output, in file order. The
  // importer takes the mapping's input and output from them, and its state inputs and outputs.
  std::vector<Port> inputs;
  std::vector<Port> outputs;
  Port input;   // inputs[0]
  Port output;  // outputs[0]
  std::map<std::string, Tensor> constants;
  std::vector<Node> nodes;

  const Tensor* Constant(const std::string& name) const noexcept;
  const Port* FindInput(const std::string& name) const noexcept;
  const Port* FindOutput(const std::string& name) const noexcept;
};

// Limits checked before anything is allocated from a size in the file.
struct ReadLimits {
  std::uint64_t max_file_bytes = 256u * 1024u * 1024u;
  std::uint64_t max_tensor_elements = 16u * 1024u * 1024u;
  std::uint32_t max_nodes = 4096;
};

// Parses ONNX bytes; `origin` starts every error ("rsl_rl.onnx: ...").
Result<Model> ParseModel(std::span<const std::uint8_t> bytes, const std::string& origin, const ReadLimits& limits = {});
// Reads and parses a file; errors start with the path.
Result<Model> ReadModelFile(const std::string& path, const ReadLimits& limits = {});

}  // namespace pbppo::onnx
