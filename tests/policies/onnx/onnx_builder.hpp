// Builds small ONNX models in the tests (the same protobuf schema the importer reads), one node
// at a time along a chain, with weights from a fixed seed.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "onnx.pb.h"

namespace pbppo::test {

class OnnxBuilder {
 public:
  explicit OnnxBuilder(int inputs, int opset = 17, std::uint32_t seed = 7) : width_(inputs), rng_(seed) {
    m_.set_ir_version(8);
    m_.set_producer_name("onnx-builder");
    m_.set_producer_version("1");
    auto* os = m_.add_opset_import();
    os->set_domain("");
    os->set_version(opset);
    g_ = m_.mutable_graph();
    g_->set_name("actor");
    Port(g_->add_input(), "obs", inputs);
    cur_ = "obs";
  }

  ::onnx::GraphProto& graph() { return *g_; }
  ::onnx::ModelProto& model() { return m_; }
  const std::string& current() const { return cur_; }
  int width() const { return width_; }
  void set_width(int w) { width_ = w; }  // after a layer added by hand

  std::vector<float> Random(std::size_t n, float scale) {
    std::normal_distribution<float> d(0.0f, scale);
    std::vector<float> v(n);
    for (float& x : v) x = d(rng_);
    return v;
  }

  // A float32 initializer.
  std::string Const(const std::string& name, std::vector<std::int64_t> dims, const std::vector<float>& values) {
    auto* t = g_->add_initializer();
    t->set_name(name);
    t->set_data_type(::onnx::TensorProto::FLOAT);
    for (auto d : dims) t->add_dims(d);
    for (float v : values) t->add_float_data(v);
    return name;
  }

  // A node on the chain: `inputs` may name "$" for the current value. Returns the node.
  ::onnx::NodeProto* Node(const std::string& op, std::vector<std::string> inputs, const std::string& name = "") {
    auto* n = g_->add_node();
    n->set_op_type(op);
    n->set_name(name.empty() ? op + "_" + std::to_string(count_) : name);
    for (auto& in : inputs) n->add_input(in == "$" ? cur_ : in);
    cur_ = "v" + std::to_string(count_++);
    n->add_output(cur_);
    return n;
  }

  static void Attr(::onnx::NodeProto* n, const std::string& name, float f) {
    auto* a = n->add_attribute();
    a->set_name(name);
    a->set_type(::onnx::AttributeProto::FLOAT);
    a->set_f(f);
  }
  static void AttrInt(::onnx::NodeProto* n, const std::string& name, std::int64_t i) {
    auto* a = n->add_attribute();
    a->set_name(name);
    a->set_type(::onnx::AttributeProto::INT);
    a->set_i(i);
  }

  // Gemm with transB=1 (torch's Linear), random weights.
  ::onnx::NodeProto* Gemm(int out, const std::string& name = "") {
    const std::string k = std::to_string(count_);
    Const("W" + k, {out, width_}, Random(static_cast<std::size_t>(out * width_), 0.5f));
    Const("b" + k, {out}, Random(static_cast<std::size_t>(out), 0.1f));
    auto* n = Node("Gemm", {"$", "W" + k, "b" + k}, name);
    AttrInt(n, "transB", 1);
    width_ = out;
    return n;
  }
  // MatMul by [in, out] then Add of the bias.
  void MatMulAdd(int out) {
    const std::string k = std::to_string(count_);
    Const("M" + k, {width_, out}, Random(static_cast<std::size_t>(out * width_), 0.5f));
    Const("c" + k, {out}, Random(static_cast<std::size_t>(out), 0.1f));
    Node("MatMul", {"$", "M" + k});
    Node("Add", {"$", "c" + k});
    width_ = out;
  }
  // An elementwise op with a per-element constant, the chain first or second.
  ::onnx::NodeProto* Elementwise(const std::string& op, const std::vector<float>& c, bool chain_first = true) {
    const std::string k = "e" + std::to_string(count_);
    Const(k,
          c.size() == 1 ? std::vector<std::int64_t>{} : std::vector<std::int64_t>{static_cast<std::int64_t>(c.size())},
          c);
    return Node(op, chain_first ? std::vector<std::string>{"$", k} : std::vector<std::string>{k, "$"});
  }
  ::onnx::NodeProto* Clip(float lo, float hi) {
    const std::string k = std::to_string(count_);
    Const("lo" + k, {}, {lo});
    Const("hi" + k, {}, {hi});
    return Node("Clip", {"$", "lo" + k, "hi" + k});
  }

  // Names the current value as the output "actions" and serialises.
  std::string Bytes(const std::string& output = "actions") {
    Node("Identity", {"$"})->set_output(0, output);
    cur_ = output;
    Port(g_->add_output(), output, width_);
    std::string s;
    m_.SerializeToString(&s);
    return s;
  }

  static void Port(::onnx::ValueInfoProto* v, const std::string& name, int size) {
    v->set_name(name);
    auto* tt = v->mutable_type()->mutable_tensor_type();
    tt->set_elem_type(::onnx::TensorProto::FLOAT);
    tt->mutable_shape()->add_dim()->set_dim_param("batch");
    tt->mutable_shape()->add_dim()->set_dim_value(size);
  }

 private:
  ::onnx::ModelProto m_;
  ::onnx::GraphProto* g_ = nullptr;
  std::string cur_;
  int width_;
  int count_ = 0;
  std::mt19937 rng_;
};

}  // namespace pbppo::test
