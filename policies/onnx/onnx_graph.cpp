#include "policies/onnx/onnx_graph.hpp"

#include <cstring>
#include <set>

#include "onnx.pb.h"
#include "runtime/policy/blob.hpp"

namespace pbppo::onnx {
namespace {

Error Fail(const std::string& origin, ErrorCode code, const std::string& what) {
  return MakeError(code, origin + ": " + what);
}

std::string Quoted(const std::string& s) {
  std::string q;
  for (char c : s.substr(0, 80)) q += (c >= 0x20 && c < 0x7f) ? c : '?';
  return "'" + q + (s.size() > 80 ? "...'" : "'");
}

// A tensor's element count from its dimensions, refusing negative dimensions and counts beyond
// the limit (checked before anything is allocated).
Result<std::uint64_t> ElementCount(const ::onnx::TensorProto& t, const std::string& origin, const ReadLimits& limits) {
  std::uint64_t n = 1;
  for (int d = 0; d < t.dims_size(); ++d) {
    const std::int64_t v = t.dims(d);
    if (v < 0)
      return Fail(origin, ErrorCode::kFormat,
                  "tensor " + Quoted(t.name()) + ": dimension " + std::to_string(d) + " is " + std::to_string(v));
    if (v != 0 && n > limits.max_tensor_elements / static_cast<std::uint64_t>(v))
      return Fail(
          origin, ErrorCode::kLimit,
          "tensor " + Quoted(t.name()) + ": more than " + std::to_string(limits.max_tensor_elements) + " elements");
    n *= static_cast<std::uint64_t>(v);
  }
  return n;
}

Result<Tensor> ReadTensor(const ::onnx::TensorProto& t, const std::string& name, const std::string& origin,
                          const ReadLimits& limits) {
  Tensor out;
  out.name = name;
  out.data_type = t.data_type();
  out.dims.assign(t.dims().begin(), t.dims().end());
  if (t.data_location() == ::onnx::TensorProto::EXTERNAL || t.external_data_size() > 0)
    return Fail(origin, ErrorCode::kUnsupported,
                "tensor " + Quoted(name) +
                    " keeps its data in an external file: export with the weights inside the "
                    "model (onnx.save(..., save_as_external_data=False))");
  if (t.has_segment()) return Fail(origin, ErrorCode::kUnsupported, "tensor " + Quoted(name) + " is segmented");
  auto n = ElementCount(t, origin, limits);
  if (!n) return std::move(n).error();
  if (out.data_type == ::onnx::TensorProto::INT64 || out.data_type == ::onnx::TensorProto::INT32) {
    // Axes, starts and ends of shape operators (Unsqueeze, Squeeze, Slice).
    const unsigned width = out.data_type == ::onnx::TensorProto::INT64 ? 8 : 4;
    if (t.has_raw_data()) {
      const std::string& raw = t.raw_data();
      if (raw.size() != *n * width)
        return Fail(origin, ErrorCode::kFormat,
                    "tensor " + Quoted(name) + ": " + std::to_string(raw.size()) + " bytes of data for " +
                        std::to_string(*n) + " integer elements " + out.Shape());
      out.ints.resize(*n);
      for (std::uint64_t k = 0; k < *n; ++k) {
        std::uint64_t bits = 0;
        for (unsigned b = width; b-- > 0;) bits = (bits << 8) | static_cast<std::uint8_t>(raw[k * width + b]);
        if (width == 4) bits = static_cast<std::uint64_t>(static_cast<std::int64_t>(static_cast<std::int32_t>(bits)));
        out.ints[k] = static_cast<std::int64_t>(bits);
      }
    } else if (width == 8 && static_cast<std::uint64_t>(t.int64_data_size()) == *n) {
      out.ints.assign(t.int64_data().begin(), t.int64_data().end());
    } else if (width == 4 && static_cast<std::uint64_t>(t.int32_data_size()) == *n) {
      out.ints.assign(t.int32_data().begin(), t.int32_data().end());
    } else {
      return Fail(origin, ErrorCode::kFormat,
                  "tensor " + Quoted(name) + ": its integer values do not match " + std::to_string(*n) + " elements " +
                      out.Shape());
    }
    return out;
  }
  if (!out.is_float32()) return out;  // the node that uses it refuses it, naming itself
  if (t.has_raw_data()) {
    const std::string& raw = t.raw_data();
    if (raw.size() != *n * 4)
      return Fail(origin, ErrorCode::kFormat,
                  "tensor " + Quoted(name) + ": " + std::to_string(raw.size()) + " bytes of data for " +
                      std::to_string(*n) + " float32 elements " + out.Shape());
    out.values.resize(*n);
    for (std::uint64_t k = 0; k < *n; ++k) {
      std::uint32_t bits = 0;
      for (int b = 3; b >= 0; --b)
        bits = (bits << 8) | static_cast<std::uint8_t>(raw[k * 4 + static_cast<unsigned>(b)]);
      float f;
      std::memcpy(&f, &bits, 4);
      out.values[k] = static_cast<double>(f);
    }
  } else {
    if (static_cast<std::uint64_t>(t.float_data_size()) != *n)
      return Fail(origin, ErrorCode::kFormat,
                  "tensor " + Quoted(name) + ": " + std::to_string(t.float_data_size()) + " float32 values for " +
                      std::to_string(*n) + " elements " + out.Shape());
    out.values.assign(t.float_data().begin(), t.float_data().end());
  }
  return out;
}

Result<Port> ReadPort(const ::onnx::ValueInfoProto& v, const char* what, const std::string& origin) {
  Port p;
  p.name = v.name();
  const std::string where = std::string(what) + " " + Quoted(v.name());
  if (!v.type().has_tensor_type())
    return Fail(origin, ErrorCode::kUnsupported, where + " is not a tensor (sequence, map or optional)");
  const auto& tt = v.type().tensor_type();
  if (tt.elem_type() != ::onnx::TensorProto::FLOAT)
    return Fail(origin, ErrorCode::kUnsupported,
                where + " is " + DataTypeName(tt.elem_type()) + ": the engine takes and gives float32");
  if (!tt.has_shape()) return Fail(origin, ErrorCode::kUnsupported, where + " has no shape");
  const auto& shape = tt.shape();
  const int rank = shape.dim_size();
  if (rank < 1 || rank > 3)
    return Fail(origin, ErrorCode::kUnsupported,
                where + " has rank " + std::to_string(rank) +
                    ": the engine takes [batch, size] or [size] (and a recurrent state [layers, batch, size])");
  const int last = rank - 1;
  p.has_batch = rank >= 2;
  for (int k = 0; k < last; ++k) {
    const auto& b = shape.dim(k);
    const bool batch = k == rank - 2;  // [batch, size] or [layers, batch, size]
    if (!b.has_dim_value() && !batch)
      return Fail(origin, ErrorCode::kUnsupported,
                  where + " dimension " + std::to_string(k) + " is symbolic" +
                      (b.has_dim_param() ? " (" + Quoted(b.dim_param()) + ")" : std::string()) +
                      ": only the batch dimension may be");
    if (batch && b.has_dim_value() && b.dim_value() != 1)
      return Fail(origin, ErrorCode::kUnsupported,
                  where + " has a fixed batch of " + std::to_string(b.dim_value()) + ": the engine runs one row");
    if (!batch && (b.dim_value() < 1 || b.dim_value() > 64))
      return Fail(origin, ErrorCode::kUnsupported,
                  where + " dimension " + std::to_string(k) + " is " + std::to_string(b.dim_value()) + " (1 to 64)");
    p.dims.push_back(b.has_dim_value() ? b.dim_value() : 1);
  }
  const auto& d = shape.dim(last);
  if (!d.has_dim_value())
    return Fail(origin, ErrorCode::kUnsupported,
                where + " dimension " + std::to_string(last) + " is symbolic" +
                    (d.has_dim_param() ? " (" + Quoted(d.dim_param()) + ")" : std::string()) +
                    ": only the batch dimension may be");
  if (d.dim_value() < 1 || d.dim_value() > 65536)
    return Fail(origin, ErrorCode::kUnsupported, where + " has size " + std::to_string(d.dim_value()));
  p.size = static_cast<std::uint32_t>(d.dim_value());
  p.dims.push_back(d.dim_value());
  return p;
}

Result<Attribute> ReadAttribute(const ::onnx::AttributeProto& a, const std::string& node, const std::string& origin) {
  Attribute out;
  out.name = a.name();
  switch (a.type()) {
    case ::onnx::AttributeProto::FLOAT:
      out.kind = Attribute::Kind::kFloat;
      out.f = static_cast<double>(a.f());
      break;
    case ::onnx::AttributeProto::INT:
      out.kind = Attribute::Kind::kInt;
      out.i = a.i();
      break;
    case ::onnx::AttributeProto::FLOATS:
      out.kind = Attribute::Kind::kFloats;
      for (float f : a.floats()) out.floats.push_back(static_cast<double>(f));
      break;
    case ::onnx::AttributeProto::INTS:
      out.kind = Attribute::Kind::kInts;
      out.ints.assign(a.ints().begin(), a.ints().end());
      break;
    case ::onnx::AttributeProto::STRING:
      out.kind = Attribute::Kind::kString;
      out.s = a.s();
      break;
    case ::onnx::AttributeProto::GRAPH:
    case ::onnx::AttributeProto::GRAPHS:
      return Fail(origin, ErrorCode::kUnsupported,
                  node + ": attribute " + Quoted(a.name()) + " holds a subgraph (control flow)");
    default: out.kind = Attribute::Kind::kOther; break;
  }
  return out;
}

}  // namespace

const char* DataTypeName(std::int32_t t) noexcept {
  switch (t) {
    case 1: return "float32";
    case 2: return "uint8";
    case 3: return "int8";
    case 5: return "int16";
    case 6: return "int32";
    case 7: return "int64";
    case 8: return "string";
    case 9: return "bool";
    case 10: return "float16";
    case 11: return "float64";
    case 16: return "bfloat16";
    default: return "an unsupported element type";
  }
}

std::string Tensor::Shape() const {
  std::string s = "[";
  for (std::size_t i = 0; i < dims.size(); ++i) s += (i ? ", " : "") + std::to_string(dims[i]);
  return s + "]";
}

const Attribute* Node::Find(const char* attribute) const noexcept {
  for (const Attribute& a : attributes)
    if (a.name == attribute) return &a;
  return nullptr;
}

std::string Node::Label() const {
  return (name.empty() ? "node #" + std::to_string(index) : "node " + Quoted(name)) + " (" + op + ")";
}

const Port* Model::FindInput(const std::string& name) const noexcept {
  for (const Port& p : inputs)
    if (p.name == name) return &p;
  return nullptr;
}

const Port* Model::FindOutput(const std::string& name) const noexcept {
  for (const Port& p : outputs)
    if (p.name == name) return &p;
  return nullptr;
}

const Tensor* Model::Constant(const std::string& n) const noexcept {
  auto it = constants.find(n);
  return it == constants.end() ? nullptr : &it->second;
}

Result<Model> ParseModel(std::span<const std::uint8_t> bytes, const std::string& origin, const ReadLimits& limits) {
  if (bytes.size() > limits.max_file_bytes)
    return Fail(origin, ErrorCode::kLimit,
                std::to_string(bytes.size()) + " bytes exceeds limit " + std::to_string(limits.max_file_bytes));
  ::onnx::ModelProto m;
  if (bytes.empty() || !m.ParseFromArray(bytes.data(), static_cast<int>(bytes.size())))
    return Fail(origin, ErrorCode::kFormat,
                "not an ONNX model (the protobuf does not parse: truncated, corrupted or another format)");
  if (!m.has_graph() || m.graph().node_size() == 0)
    return Fail(origin, ErrorCode::kFormat, "not an ONNX model (no graph, or a graph without nodes)");
  if (m.ir_version() < 3 || m.ir_version() > 100)
    return Fail(origin, ErrorCode::kUnsupported, "IR version " + std::to_string(m.ir_version()) + " (3 and later)");
  Model out;
  out.origin = origin;
  out.ir_version = m.ir_version();
  out.producer_name = m.producer_name();
  out.producer_version = m.producer_version();
  for (const auto& os : m.opset_import())
    if (os.domain().empty() || os.domain() == "ai.onnx") out.opset = os.version();
  if (out.opset < 7 || out.opset > 22)
    return Fail(origin, ErrorCode::kUnsupported,
                out.opset == 0 ? std::string("no default-domain operator set imported")
                               : "operator set " + std::to_string(out.opset) + " (7 to 22 are read)");
  const ::onnx::GraphProto& g = m.graph();
  if (static_cast<std::uint64_t>(g.node_size()) > limits.max_nodes)
    return Fail(origin, ErrorCode::kLimit,
                std::to_string(g.node_size()) + " nodes exceeds limit " + std::to_string(limits.max_nodes));
  if (g.sparse_initializer_size() > 0)
    return Fail(origin, ErrorCode::kUnsupported,
                "sparse initializer " + Quoted(g.sparse_initializer(0).values().name()) + ": export dense weights");
  for (const auto& t : g.initializer()) {
    auto r = ReadTensor(t, t.name(), origin, limits);
    if (!r) {  // name the nodes that use it
      std::string users;
      for (int i = 0; i < g.node_size(); ++i)
        for (const std::string& in : g.node(i).input())
          if (in == t.name()) {
            Node n;
            n.index = static_cast<std::size_t>(i);
            n.name = g.node(i).name();
            n.op = g.node(i).op_type();
            users += (users.empty() ? " (input of " : ", ") + n.Label();
          }
      return MakeError(r.error().code, r.error().message + (users.empty() ? "" : users + ")"));
    }
    out.constants[t.name()] = std::move(*r);
  }
  // Inputs that are not initializers (older exporters list the weights as inputs too).
  std::vector<const ::onnx::ValueInfoProto*> inputs;
  for (const auto& v : g.input())
    if (!out.constants.count(v.name())) inputs.push_back(&v);
  for (int i = 0; i < g.node_size(); ++i) {
    const ::onnx::NodeProto& n = g.node(i);
    Node node;
    node.index = static_cast<std::size_t>(i);
    node.name = n.name();
    node.op = n.op_type();
    node.domain = n.domain();
    node.inputs.assign(n.input().begin(), n.input().end());
    node.outputs.assign(n.output().begin(), n.output().end());
    for (const auto& a : n.attribute()) {
      if (a.type() == ::onnx::AttributeProto::TENSOR && node.op == "Constant" && a.name() == "value") {
        if (node.outputs.size() != 1) return Fail(origin, ErrorCode::kFormat, node.Label() + ": needs one output");
        auto t = ReadTensor(a.t(), node.outputs[0], origin, limits);
        if (!t) return std::move(t).error();
        out.constants[node.outputs[0]] = std::move(*t);
        continue;
      }
      auto attr = ReadAttribute(a, node.Label(), origin);
      if (!attr) return std::move(attr).error();
      node.attributes.push_back(std::move(*attr));
    }
    if (node.op == "Constant" && (node.domain.empty() || node.domain == "ai.onnx")) {
      if (node.outputs.size() != 1) return Fail(origin, ErrorCode::kFormat, node.Label() + ": needs one output");
      if (out.constants.count(node.outputs[0])) continue;  // held a tensor: read above
      Tensor t;                                            // value_float / value_floats
      t.name = node.outputs[0];
      t.data_type = 1;
      if (const Attribute* a = node.Find("value_float"); a && a->kind == Attribute::Kind::kFloat) {
        t.values = {static_cast<double>(static_cast<float>(a->f))};
      } else if (const Attribute* b = node.Find("value_floats"); b && b->kind == Attribute::Kind::kFloats) {
        t.values = b->floats;
        t.dims = {static_cast<std::int64_t>(b->floats.size())};
      } else {
        t.data_type = 0;  // an integer or string constant: refused where it is used
      }
      out.constants[t.name] = std::move(t);
      continue;
    }
    out.nodes.push_back(std::move(node));
  }
  auto node_using = [&](const std::string& value) {
    std::string users;
    for (const Node& n : out.nodes)
      for (std::size_t k = 0; k < n.inputs.size(); ++k)
        if (n.inputs[k] == value) users += (users.empty() ? "" : ", ") + n.Label() + " input " + std::to_string(k);
    return users.empty() ? std::string("no node") : users;
  };
  for (const Node& n : out.nodes)
    if (n.op == "RNN" || n.op == "Scan" || n.op == "Loop" || n.op == "If")
      return Fail(origin, ErrorCode::kUnsupported,
                  n.Label() + ": a control-flow or plain RNN operator: the engine runs chains of layers, LSTM and GRU");
  if (inputs.empty()) return Fail(origin, ErrorCode::kUnsupported, "no graph input (weights must be initializers)");
  if (g.output_size() == 0) return Fail(origin, ErrorCode::kUnsupported, "no graph output");
  // Which input is the observation and which are a recurrent state is the mapping's to say
  // (onnx_map.hpp): the importer picks them by name.
  // A port the engine could not take is refused here when it is the only one; among several, the
  // importer refuses it if the mapping uses it (or the graph's extra inputs or outputs first).
  for (const auto* v : inputs) {
    auto port = ReadPort(*v, "input", origin);
    if (!port && inputs.size() == 1) return std::move(port).error();
    Port p = port ? std::move(*port) : Port{};
    if (!port) p.problem = port.error().message;
    p.name = v->name();
    p.users = node_using(v->name());
    out.inputs.push_back(std::move(p));
  }
  for (const auto& v : g.output()) {
    auto port = ReadPort(v, "output", origin);
    if (!port && g.output_size() == 1) return std::move(port).error();
    Port p = port ? std::move(*port) : Port{};
    if (!port) p.problem = port.error().message;
    p.name = v.name();
    out.outputs.push_back(std::move(p));
  }
  out.input = out.inputs.front();
  out.output = out.outputs.front();
  std::set<std::string> produced;
  for (const Port& p : out.inputs) produced.insert(p.name);
  for (const auto& [name, t] : out.constants) produced.insert(name);
  for (const Node& n : out.nodes) {  // ONNX requires topological order: refuse what is not
    for (const std::string& v : n.inputs)
      if (!v.empty() && !produced.count(v))
        return Fail(origin, ErrorCode::kFormat, n.Label() + ": input " + Quoted(v) + " is produced by no earlier node");
    for (const std::string& v : n.outputs) produced.insert(v);
  }
  return out;
}

Result<Model> ReadModelFile(const std::string& path, const ReadLimits& limits) {
  auto bytes = policy::ReadFileBytes(path, limits.max_file_bytes);
  if (!bytes) return std::move(bytes).error();
  return ParseModel(*bytes, path, limits);
}

}  // namespace pbppo::onnx
