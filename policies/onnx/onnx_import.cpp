#include "policies/onnx/onnx_import.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "policies/onnx/onnx_eval.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::onnx {
namespace {

using robot::YamlFields;

constexpr double kInf = std::numeric_limits<double>::infinity();

// One recognised piece of the chain.
struct Piece {
  enum class Kind : std::uint8_t { kAffine, kClip, kLinear, kActivation, kRecurrent } kind;
  const Node* node = nullptr;
  std::vector<double> a, b;       // affine: x -> a x + b per element
  double lo = -kInf, hi = kInf;   // clip
  std::uint32_t in = 0, out = 0;  // linear; recurrent: out is the hidden size
  std::vector<double> w, bias;    // linear: row-major [out][in]; recurrent: [gates * out][in], Wb
  policy::Activation activation = policy::Activation::kIdentity;
  double alpha = 0;  // LeakyRelu
  // recurrent: LSTM or GRU, R [gates * out][out] and Rb, GRU's linear_before_reset
  policy::LayerKind recurrent = policy::LayerKind::kDense;
  std::vector<double> rw, rbias;
  bool linear_before_reset = false;
  std::string state_note;  // "h_in[0] -> h_out[0], c_in[0] -> c_out[0]"

  std::uint32_t rows() const { return out * policy::GateCount(recurrent); }
};

// Where a recurrent node's state comes from or goes to: a graph input or output and the layer
// index along its first dimension (a Slice or a Concat input of a stacked export; 0 otherwise).
struct StateSlot {
  std::string port;
  std::int64_t slot = 0;
};

class Importer {
 public:
  Importer(const Model& m, const Mapping& map, const robot::IoLayout& layout) : m_(m), map_(map), layout_(layout) {}

  Result<Imported> Run(const ImportOptions& options);

 private:
  Error Refuse(const Node& n, const std::string& what) const {
    return MakeError(ErrorCode::kUnsupported, m_.origin + ": " + n.Label() + ": " + what);
  }
  Error Refuse(const std::string& what) const { return MakeError(ErrorCode::kUnsupported, m_.origin + ": " + what); }
  Status SelectPorts();
  Status Walk();
  Status Recurrent(const Node& n, std::uint32_t width, Piece* p);
  Result<StateSlot> StateSource(const Node& n, std::size_t k) const;
  Result<StateSlot> StateDestination(const Node& n, std::size_t k) const;
  Status CheckStateWiring(const Node& n, const char* what, const StateSlot& from, const StateSlot& to);
  Result<std::vector<std::int64_t>> IntsOf(const Node& n, std::size_t k, const char* attribute) const;
  Result<const Tensor*> ConstantInput(const Node& n, std::size_t k) const;
  Result<std::vector<double>> PerElement(const Node& n, const Tensor& t, std::uint32_t width) const;
  Status Assemble(policy::PolicySpec& s, std::vector<std::string>& notes, bool* graph_normaliser);

  const Model& m_;
  const Mapping& map_;
  const robot::IoLayout& layout_;
  const Port* in_ = nullptr;  // the mapping's input and output ports
  const Port* out_ = nullptr;
  std::vector<Piece> pieces_;
  std::map<std::string, const Node*> producer_;            // value -> the node giving it
  std::map<std::string, std::vector<const Node*>> users_;  // value -> the nodes reading it
  std::map<std::string, std::vector<bool>> slots_used_;    // state input -> per layer slot
};

std::string Printable(const std::string& s, std::size_t max) {
  std::string out;
  for (char c : s.substr(0, max)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
  return out;
}

Result<const Tensor*> Importer::ConstantInput(const Node& n, std::size_t k) const {
  if (k >= n.inputs.size() || n.inputs[k].empty()) return Refuse(n, "input " + std::to_string(k) + " is missing");
  const Tensor* t = m_.Constant(n.inputs[k]);
  if (t == nullptr)
    return Refuse(n, "input " + std::to_string(k) + " '" + n.inputs[k] +
                         "' is not a constant (weights, biases and bounds must be initializers)");
  if (!t->is_float32())
    return Refuse(n, "constant '" + t->name + "' is " + DataTypeName(t->data_type) +
                         ": the engine runs float32 weights only (export the model in float32)");
  return t;
}

// A constant of an elementwise op as one value per element: a scalar, [width] or [1, width].
Result<std::vector<double>> Importer::PerElement(const Node& n, const Tensor& t, std::uint32_t width) const {
  if (t.values.size() == 1) return std::vector<double>(width, t.values[0]);
  const bool row =
      (t.dims.size() == 1 && t.dims[0] == width) || (t.dims.size() == 2 && t.dims[0] == 1 && t.dims[1] == width);
  if (!row)
    return Refuse(n, "constant '" + t.name + "' of shape " + t.Shape() + " does not apply elementwise to " +
                         std::to_string(width) + " elements");
  return t.values;
}

Status Importer::Walk() {
  std::map<std::string, std::vector<const Node*>>& users = users_;
  for (const Node& n : m_.nodes) {
    for (const std::string& v : n.inputs)
      if (!v.empty() && !m_.Constant(v)) users[v].push_back(&n);
    for (const std::string& v : n.outputs)
      if (!v.empty()) producer_[v] = &n;
  }
  std::string cur = in_->name;
  std::uint32_t width = in_->size;
  std::size_t rank = in_->dims.size();  // where the features are: always the last dimension
  while (true) {
    const auto& u = users[cur];
    if (cur == out_->name) {
      if (!u.empty()) return Refuse(*u[0], "reads the graph output '" + cur + "': the engine runs a chain of layers");
      break;
    }
    if (u.empty())
      return Refuse("value '" + cur + "' reaches no node and is not the graph output '" + out_->name + "'");
    if (u.size() > 1) {
      std::string list;
      for (const Node* n : u) list += (list.empty() ? "" : ", ") + n->Label();
      return Refuse(*u[1], "value '" + cur + "' feeds " + std::to_string(u.size()) + " nodes (" + list +
                               "): the engine runs a chain of layers, not a graph with branches");
    }
    const Node& n = *u[0];
    if (!n.domain.empty() && n.domain != "ai.onnx")
      return Refuse(n, "an operator of domain '" + n.domain + "': only the default ONNX operator set is read");
    for (const Attribute& a : n.attributes) {  // the attributes read below, of the type ONNX gives them
      const bool is_float = a.name == "alpha" || a.name == "beta" || a.name == "min" || a.name == "max";
      const bool is_int = a.name == "transA" || a.name == "transB" || a.name == "axis" || a.name == "hidden_size" ||
                          a.name == "linear_before_reset" || a.name == "input_forget" || a.name == "layout";
      const bool is_ints = a.name == "axes" || a.name == "starts" || a.name == "ends";
      if ((is_float && a.kind != Attribute::Kind::kFloat) || (is_int && a.kind != Attribute::Kind::kInt) ||
          (is_ints && a.kind != Attribute::Kind::kInts))
        return Refuse(n, "attribute '" + a.name + "' is not " +
                             (is_float ? "a float"
                              : is_int ? "an integer"
                                       : "a list of integers"));
    }
    const bool recurrent = n.op == "LSTM" || n.op == "GRU";
    if (!recurrent && (n.outputs.size() != 1 || n.outputs[0].empty()))
      return Refuse(n, std::to_string(n.outputs.size()) + " outputs: the engine's operators have one");
    std::size_t chain_at = n.inputs.size();
    for (std::size_t k = 0; k < n.inputs.size(); ++k) {
      if (n.inputs[k] != cur) continue;
      if (chain_at != n.inputs.size()) return Refuse(n, "takes '" + cur + "' twice");
      chain_at = k;
    }
    const std::string& op = n.op;
    Piece p;
    p.node = &n;
    if (op == "Identity" || op == "Flatten") {
      if (op == "Flatten") {
        const Attribute* a = n.Find("axis");
        if (a != nullptr && a->i != 1) return Refuse(n, "axis " + std::to_string(a->i) + " (only 1 keeps a row a row)");
        rank = 2;
      }
      cur = n.outputs[0];
      continue;
    }
    if (op == "Unsqueeze" || op == "Squeeze") {
      // Only dimensions of size 1 before the features: the row stays the same numbers.
      if (chain_at != 0) return Refuse(n, "the value is its input " + std::to_string(chain_at) + ", not 0");
      auto axes = IntsOf(n, 1, "axes");
      if (!axes) return std::move(axes).error();
      if (axes->empty()) return Refuse(n, "no axes: the engine needs to know which dimensions of size 1 it removes");
      const std::size_t to = op == "Unsqueeze" ? rank + axes->size() : rank;
      for (std::int64_t a : *axes) {
        const std::int64_t ax = a < 0 ? a + static_cast<std::int64_t>(to) : a;
        if (ax < 0 || ax >= static_cast<std::int64_t>(to))
          return Refuse(n, "axis " + std::to_string(a) + " outside a value of rank " + std::to_string(to));
        if (ax == static_cast<std::int64_t>(to) - 1)
          return Refuse(n, "axis " + std::to_string(a) + " is the features' dimension (the last)");
      }
      if (op == "Squeeze" && axes->size() >= rank)
        return Refuse(n, std::to_string(axes->size()) + " axes of a value of rank " + std::to_string(rank));
      rank = op == "Unsqueeze" ? to : rank - axes->size();
      cur = n.outputs[0];
      continue;
    }
    if (recurrent) {
      if (chain_at != 0) return Refuse(n, "the value is its input " + std::to_string(chain_at) + ", not X (0)");
      if (rank != 3)
        return Refuse(n, "X has rank " + std::to_string(rank) +
                             ": an exported single step is [1, batch, features] (an Unsqueeze before the node)");
      if (auto st = Recurrent(n, width, &p); !st) return st;
      width = p.out;
      // The chain goes on from Y [1, 1, batch, hidden] or, where Y is not used, from Y_h.
      const bool y_used = !n.outputs.empty() && !n.outputs[0].empty() && !users[n.outputs[0]].empty();
      cur = y_used ? n.outputs[0] : n.outputs[1];
      rank = y_used ? 4 : 3;
      pieces_.push_back(std::move(p));
      continue;
    }
    if (op == "Gemm" || op == "MatMul") {
      if (chain_at != 0) return Refuse(n, "the observation is its input " + std::to_string(chain_at) + ", not 0");
      const Attribute* ta = n.Find("transA");
      if (op == "Gemm" && ta != nullptr && ta->i != 0) return Refuse(n, "transA 1: the engine multiplies W x");
      auto B = ConstantInput(n, 1);
      if (!B) return std::move(B).error();
      const Tensor& w = **B;
      const Attribute* tb = n.Find("transB");
      const bool trans = op == "Gemm" && tb != nullptr && tb->i != 0;
      if (w.dims.size() != 2) return Refuse(n, "weight '" + w.name + "' has shape " + w.Shape() + ", not a matrix");
      const std::int64_t k_in = trans ? w.dims[1] : w.dims[0], k_out = trans ? w.dims[0] : w.dims[1];
      if (k_in != width)
        return Refuse(n, "weight '" + w.name + "' " + w.Shape() + (trans ? " (transposed)" : "") + " takes " +
                             std::to_string(k_in) + " inputs, the value before it has " + std::to_string(width));
      if (k_out < 1 || k_out > 65536) return Refuse(n, "weight '" + w.name + "' " + w.Shape() + " gives no outputs");
      p.kind = Piece::Kind::kLinear;
      p.in = width;
      p.out = static_cast<std::uint32_t>(k_out);
      const double alpha = op == "Gemm" && n.Find("alpha") ? n.Find("alpha")->f : 1.0;
      const double beta = op == "Gemm" && n.Find("beta") ? n.Find("beta")->f : 1.0;
      p.w.resize(static_cast<std::size_t>(p.in) * p.out);
      for (std::uint32_t o = 0; o < p.out; ++o)
        for (std::uint32_t i = 0; i < p.in; ++i)
          p.w[o * p.in + i] = alpha * (trans ? w.values[o * p.in + i] : w.values[i * p.out + o]);
      p.bias.assign(p.out, 0.0);
      if (op == "Gemm" && n.inputs.size() > 2 && !n.inputs[2].empty()) {
        auto C = ConstantInput(n, 2);
        if (!C) return std::move(C).error();
        auto c = PerElement(n, **C, p.out);
        if (!c) return std::move(c).error();
        for (std::uint32_t o = 0; o < p.out; ++o) p.bias[o] = beta * (*c)[o];
      }
      width = p.out;
    } else if (op == "Add" || op == "Sub" || op == "Mul" || op == "Div") {
      if (n.inputs.size() != 2) return Refuse(n, "needs two inputs");
      auto c = ConstantInput(n, 1 - chain_at);
      if (!c) return std::move(c).error();
      auto v = PerElement(n, **c, width);
      if (!v) return std::move(v).error();
      p.kind = Piece::Kind::kAffine;
      p.a.assign(width, 1.0);
      p.b.assign(width, 0.0);
      for (std::uint32_t j = 0; j < width; ++j) {
        const double cj = (*v)[j];
        if (op == "Add") p.b[j] = cj;
        if (op == "Sub" && chain_at == 0) p.b[j] = -cj;
        if (op == "Sub" && chain_at == 1) {
          p.a[j] = -1.0;
          p.b[j] = cj;
        }
        if (op == "Mul") p.a[j] = cj;
        if (op == "Div") {
          if (chain_at != 0) return Refuse(n, "divides a constant by the value: not an affine map");
          if (cj == 0.0) return Refuse(n, "divides element " + std::to_string(j) + " by 0");
          p.a[j] = 1.0 / cj;
        }
      }
    } else if (op == "Clip") {
      if (chain_at != 0) return Refuse(n, "clips a constant");
      p.kind = Piece::Kind::kClip;
      if (m_.opset < 11) {
        if (const Attribute* a = n.Find("min")) p.lo = a->f;
        if (const Attribute* a = n.Find("max")) p.hi = a->f;
      } else {
        for (std::size_t k : {std::size_t{1}, std::size_t{2}}) {
          if (k >= n.inputs.size() || n.inputs[k].empty()) continue;
          auto c = ConstantInput(n, k);
          if (!c) return std::move(c).error();
          if ((*c)->values.size() != 1) return Refuse(n, "bound '" + (*c)->name + "' is not a scalar");
          (k == 1 ? p.lo : p.hi) = (*c)->values[0];
        }
      }
      if (!(p.lo <= p.hi))
        return Refuse(n, "bounds [" + YamlFields::Num(p.lo) + ", " + YamlFields::Num(p.hi) + "] are empty");
    } else if (op == "Relu" || op == "Tanh" || op == "Elu" || op == "LeakyRelu") {
      p.kind = Piece::Kind::kActivation;
      if (op == "Relu") p.activation = policy::Activation::kRelu;
      if (op == "Tanh") p.activation = policy::Activation::kTanh;
      if (op == "Elu") {
        const Attribute* a = n.Find("alpha");
        if (a != nullptr && a->f != 1.0)
          return Refuse(n, "alpha " + YamlFields::Num(a->f) + ": the engine's ELU has alpha 1 (never approximated)");
        p.activation = policy::Activation::kElu;
      }
      if (op == "LeakyRelu") {
        const Attribute* a = n.Find("alpha");
        p.alpha = a != nullptr ? a->f : static_cast<double>(0.01f);
        if (!(p.alpha >= 0.0 && p.alpha <= 1.0))
          return Refuse(n, "alpha " + YamlFields::Num(p.alpha) + " outside [0, 1]");
        p.activation = policy::Activation::kLeakyRelu;
      }
    } else {
      return Refuse(n,
                    "operator not supported by the engine (it runs Gemm, MatMul, Add, Sub, Mul, Div, Clip, Relu, "
                    "LeakyRelu, Elu, Tanh, LSTM, GRU, Identity, Flatten, Unsqueeze, Squeeze)");
    }
    pieces_.push_back(std::move(p));
    cur = n.outputs[0];
  }
  if (width != out_->size)
    return Refuse("the chain gives " + std::to_string(width) + " values, the output '" + out_->name + "' declares " +
                  std::to_string(out_->size));
  for (const auto& [port, used] : slots_used_)
    for (std::size_t k = 0; k < used.size(); ++k)
      if (!used[k])
        return Refuse("state input '" + port + "'" + (used.size() > 1 ? " layer " + std::to_string(k) : "") +
                      " feeds no LSTM or GRU node on the chain from '" + in_->name + "'");
  return {};
}

Result<std::vector<std::int64_t>> Importer::IntsOf(const Node& n, std::size_t k, const char* attribute) const {
  if (const Attribute* a = n.Find(attribute); a != nullptr) return a->ints;
  if (k >= n.inputs.size() || n.inputs[k].empty()) return std::vector<std::int64_t>{};
  const Tensor* t = m_.Constant(n.inputs[k]);
  if (t == nullptr || (t->data_type != 7 && t->data_type != 6))
    return Refuse(n, "input " + std::to_string(k) + " '" + n.inputs[k] + "' is not a constant integer list");
  return t->ints;
}

Result<StateSlot> Importer::StateSource(const Node& n, std::size_t k) const {
  const char* what = k == 5 ? "initial_h" : "initial_c";
  std::string v = n.inputs[k];
  std::int64_t slot = 0;
  bool sliced = false;
  for (int hops = 0; hops < 16; ++hops) {
    if (const Port* p = m_.FindInput(v)) {
      if (p->dims.size() != 3)
        return Refuse(n, std::string(what) + " is graph input '" + v + "' of rank " + std::to_string(p->dims.size()) +
                             ": a state is [layers, batch, hidden]");
      if (slot >= p->dims[0])
        return Refuse(n, std::string(what) + " reads layer " + std::to_string(slot) + " of '" + v + "', which has " +
                             std::to_string(p->dims[0]));
      return StateSlot{v, slot};
    }
    auto it = producer_.find(v);
    if (it == producer_.end())
      return Refuse(n, std::string(what) + " '" + v +
                           "' is a constant: the state would start from it at every step (export it as a graph input "
                           "and name it in the mapping's state)");
    const Node& q = *it->second;
    if (q.op == "Identity") {
      v = q.inputs.empty() ? "" : q.inputs[0];
      continue;
    }
    if (q.op == "Slice" && !sliced) {
      auto starts = IntsOf(q, 1, "starts"), ends = IntsOf(q, 2, "ends"), axes = IntsOf(q, 3, "axes"),
           steps = IntsOf(q, 4, "steps");
      if (!starts) return std::move(starts).error();
      if (!ends) return std::move(ends).error();
      if (!axes) return std::move(axes).error();
      if (!steps) return std::move(steps).error();
      const bool one_layer = starts->size() == 1 && ends->size() == 1 && (*ends)[0] == (*starts)[0] + 1 &&
                             (*starts)[0] >= 0 && (axes->empty() || *axes == std::vector<std::int64_t>{0}) &&
                             (steps->empty() || *steps == std::vector<std::int64_t>{1});
      if (!one_layer)
        return Refuse(q, "slices the state for " + n.Label() + " other than one layer of its first dimension");
      slot = (*starts)[0];
      sliced = true;
      v = q.inputs[0];
      continue;
    }
    return Refuse(n, std::string(what) + " comes from " + q.Label() +
                         ": a state must be a graph input, directly or as a Slice of one layer of it");
  }
  return Refuse(n, std::string(what) + ": too many Identity nodes before it");
}

Result<StateSlot> Importer::StateDestination(const Node& n, std::size_t k) const {
  const char* what = k == 1 ? "Y_h" : "Y_c";
  if (k >= n.outputs.size() || n.outputs[k].empty())
    return Refuse(n, std::string("gives no ") + what +
                         ": its next state would be lost (export it as a graph output and name it in the mapping's "
                         "state)");
  std::string v = n.outputs[k];
  std::int64_t slot = 0;
  bool concatenated = false;
  for (int hops = 0; hops < 16; ++hops) {
    if (m_.FindOutput(v) != nullptr) return StateSlot{v, slot};
    const Node* next = nullptr;
    auto it = users_.find(v);
    if (it != users_.end())
      for (const Node* u : it->second)
        if (u->op == "Identity" || (u->op == "Concat" && !concatenated)) next = u;
    if (next == nullptr)
      return Refuse(n, std::string(what) + " '" + n.outputs[k] +
                           "' reaches no graph output: the state is not wired back to the next step");
    if (next->op == "Concat") {
      const Attribute* axis = next->Find("axis");
      if (axis == nullptr || axis->i != 0)
        return Refuse(*next, "concatenates states along an axis other than 0 (their layers)");
      slot = std::find(next->inputs.begin(), next->inputs.end(), v) - next->inputs.begin();
      concatenated = true;
    }
    v = next->outputs.empty() ? "" : next->outputs[0];
  }
  return Refuse(n, std::string(what) + ": too many Identity nodes after it");
}

Status Importer::CheckStateWiring(const Node& n, const char* what, const StateSlot& from, const StateSlot& to) {
  const StatePair* pair = nullptr;
  std::string named;
  for (const StatePair& q : map_.state) {
    named += (named.empty() ? "" : ", ") + q.input + " -> " + q.output;
    if (q.input == from.port) pair = &q;
  }
  if (pair == nullptr)
    return Refuse(n, std::string(what) + " is read from '" + from.port + "', which " + map_.origin +
                         " does not name as a state input (state: " + (named.empty() ? "none" : named) + ")");
  if (pair->output != to.port)
    return Refuse(n, std::string(what) + " is read from '" + from.port + "' but the node's next state goes to '" +
                         to.port + "', and " + map_.origin + " feeds '" + from.port + "' from '" + pair->output +
                         "': the state output is not wired back to its input");
  if (from.slot != to.slot)
    return Refuse(n, std::string(what) + " reads layer " + std::to_string(from.slot) + " of '" + from.port +
                         "' but writes layer " + std::to_string(to.slot) + " of '" + to.port + "'");
  const Port* in = m_.FindInput(from.port);
  std::vector<bool>& used = slots_used_[from.port];
  used.resize(static_cast<std::size_t>(in->dims[0]), false);
  if (used[static_cast<std::size_t>(from.slot)])
    return Refuse(n, std::string(what) + ": layer " + std::to_string(from.slot) + " of '" + from.port +
                         "' is already the state of another node");
  used[static_cast<std::size_t>(from.slot)] = true;
  return {};
}

Status Importer::Recurrent(const Node& n, std::uint32_t width, Piece* p) {
  const bool lstm = n.op == "LSTM";
  const std::uint32_t gates = lstm ? 4 : 3;
  const Attribute* hs = n.Find("hidden_size");
  if (hs == nullptr || hs->i < 1 || hs->i > 4096)
    return Refuse(n, hs == nullptr ? std::string("no hidden_size") : "hidden_size " + std::to_string(hs->i));
  const auto H = static_cast<std::uint32_t>(hs->i);
  if (const Attribute* d = n.Find("direction"); d != nullptr && d->s != "forward")
    return Refuse(n,
                  "direction '" + d->s + "': the engine runs one forward direction (a policy steps forward in time)");
  if (n.Find("activations") != nullptr)
    return Refuse(n, "activations given: the engine runs the default sigmoid and tanh only");
  if (n.Find("clip") != nullptr) return Refuse(n, "clip given: the engine's cell is not clipped");
  if (const Attribute* a = n.Find("input_forget"); a != nullptr && a->i != 0)
    return Refuse(n, "input_forget 1: the engine's LSTM has separate input and forget gates");
  if (const Attribute* a = n.Find("layout"); a != nullptr && a->i != 0)
    return Refuse(n, "layout 1 (batch first): the engine reads the default layout 0");
  if (n.inputs.size() > 4 && !n.inputs[4].empty())
    return Refuse(n, "sequence_lens given: the engine runs one step at a time");
  if (lstm && n.inputs.size() > 7 && !n.inputs[7].empty())
    return Refuse(n, "peepholes (input P): the engine's LSTM has none");
  auto W = ConstantInput(n, 1);
  if (!W) return std::move(W).error();
  auto R = ConstantInput(n, 2);
  if (!R) return std::move(R).error();
  const std::vector<std::int64_t> w_dims{1, gates * H, width}, r_dims{1, gates * H, H};
  if ((*W)->dims != w_dims)
    return Refuse(n, "W '" + (*W)->name + "' has shape " + (*W)->Shape() + ", expected [1, " +
                         std::to_string(gates * H) + ", " + std::to_string(width) + "] (" + std::to_string(gates) +
                         " gates of hidden_size " + std::to_string(H) + " over " + std::to_string(width) + " inputs)");
  if ((*R)->dims != r_dims)
    return Refuse(n, "R '" + (*R)->name + "' has shape " + (*R)->Shape() + ", expected [1, " +
                         std::to_string(gates * H) + ", " + std::to_string(H) + "]");
  std::vector<double> B(2u * gates * H, 0.0);
  if (n.inputs.size() > 3 && !n.inputs[3].empty()) {
    auto b = ConstantInput(n, 3);
    if (!b) return std::move(b).error();
    if ((*b)->values.size() != B.size())
      return Refuse(
          n, "B '" + (*b)->name + "' has shape " + (*b)->Shape() + ", expected [1, " + std::to_string(B.size()) + "]");
    B = (*b)->values;
  }
  const std::size_t state_inputs = lstm ? 2 : 1;
  for (std::size_t s = 0; s < state_inputs; ++s) {
    const std::size_t k = 5 + s;
    const char* what = s == 0 ? "initial_h" : "initial_c";
    if (k >= n.inputs.size() || n.inputs[k].empty())
      return Refuse(n, std::string("no ") + what +
                           ": the state would start from zero at every step (export it as a graph input and name it "
                           "in the mapping's state)");
    auto from = StateSource(n, k);
    if (!from) return std::move(from).error();
    auto to = StateDestination(n, 1 + s);
    if (!to) return std::move(to).error();
    for (const Port* port : {m_.FindInput(from->port), m_.FindOutput(to->port)})
      if (port->size != H)
        return Refuse(n, std::string(what) + ": state '" + port->name + "' has size " + std::to_string(port->size) +
                             ", the node's hidden_size is " + std::to_string(H));
    if (auto st = CheckStateWiring(n, what, *from, *to); !st) return st;
    p->state_note += (p->state_note.empty() ? "" : ", ") + from->port + "[" + std::to_string(from->slot) + "] -> " +
                     to->port + "[" + std::to_string(to->slot) + "]";
  }
  p->kind = Piece::Kind::kRecurrent;
  p->recurrent = lstm ? policy::LayerKind::kLstm : policy::LayerKind::kGru;
  p->in = width;
  p->out = H;
  p->w = (*W)->values;
  p->bias.assign(B.begin(), B.begin() + gates * H);
  p->rw = (*R)->values;
  p->rbias.assign(B.begin() + gates * H, B.end());
  const Attribute* lbr = n.Find("linear_before_reset");
  p->linear_before_reset = !lstm && lbr != nullptr && lbr->i != 0;
  return {};
}

std::string Names(const std::vector<const Node*>& nodes) {
  std::string s;
  for (const Node* n : nodes) s += (s.empty() ? "" : ", ") + n->op + " '" + n->name + "'";
  return s;
}

Status Importer::Assemble(policy::PolicySpec& s, std::vector<std::string>& notes, bool* graph_normaliser) {
  const std::uint32_t n_in = in_->size;
  std::size_t i = 0;
  // Input normaliser: x -> clamp(a x + b, lo, hi).
  std::vector<double> a(n_in, 1.0), b(n_in, 0.0);
  const Piece* clip = nullptr;
  std::vector<const Node*> norm_nodes;
  auto is_layer = [](const Piece& p) { return p.kind == Piece::Kind::kLinear || p.kind == Piece::Kind::kRecurrent; };
  for (; i < pieces_.size() && !is_layer(pieces_[i]); ++i) {
    const Piece& p = pieces_[i];
    if (p.kind == Piece::Kind::kActivation) return Refuse(*p.node, "an activation before the first layer");
    if (clip != nullptr)
      return Refuse(*p.node, "follows the normaliser's clip (" + clip->node->Label() +
                                 "): the blob's normaliser is an affine map, then one clip");
    if (p.kind == Piece::Kind::kClip) {
      if (!(p.hi > 0 && p.lo == -p.hi))
        return Refuse(*p.node, "bounds [" + YamlFields::Num(p.lo) + ", " + YamlFields::Num(p.hi) +
                                   "]: the blob's normaliser clips symmetrically about 0");
      clip = &p;
    } else {
      for (std::uint32_t j = 0; j < n_in; ++j) {
        a[j] = p.a[j] * a[j];
        b[j] = p.a[j] * b[j] + p.b[j];
      }
    }
    norm_nodes.push_back(p.node);
  }
  if (i == pieces_.size()) return Refuse("no Gemm, MatMul, LSTM or GRU: nothing the engine could run as a layer");

  // Layers; an affine map right after a linear one (MatMul then Add) folds into it.
  struct Layer {
    Piece lin;
    bool closed = false;
    std::vector<const Node*> nodes;
  };
  std::vector<Layer> layers;
  for (; i < pieces_.size(); ++i) {
    const Piece& p = pieces_[i];
    if (is_layer(p)) {
      if (!layers.empty()) layers.back().closed = true;
      // A recurrent layer's output is its h: nothing folds into it or follows it but a layer.
      layers.push_back({p, p.kind == Piece::Kind::kRecurrent, {p.node}});
      continue;
    }
    Layer& L = layers.back();
    if (p.kind == Piece::Kind::kAffine && !L.closed) {
      for (std::uint32_t o = 0; o < L.lin.out; ++o) {
        for (std::uint32_t k = 0; k < L.lin.in; ++k) L.lin.w[o * L.lin.in + k] *= p.a[o];
        L.lin.bias[o] = p.a[o] * L.lin.bias[o] + p.b[o];
      }
      L.nodes.push_back(p.node);
      continue;
    }
    if (p.kind == Piece::Kind::kActivation) {
      if (L.closed)
        return Refuse(*p.node, "an activation after " + L.nodes.back()->Label() + ": one activation per layer");
      L.lin.activation = p.activation;
      L.lin.alpha = p.alpha;
      L.closed = true;
      L.nodes.push_back(p.node);
      continue;
    }
    break;  // the output map
  }
  // Output map: y -> clamp(sy y + oy, ylo, yhi) per output element.
  const std::uint32_t n_out = out_->size;
  std::vector<double> sy(n_out, 1.0), oy(n_out, 0.0), ylo(n_out, -kInf), yhi(n_out, kInf);
  std::vector<const Node*> out_nodes;
  for (; i < pieces_.size(); ++i) {
    const Piece& p = pieces_[i];
    if (is_layer(p) || p.kind == Piece::Kind::kActivation)
      return Refuse(*p.node, "follows the output map (" + Names(out_nodes) +
                                 "): elementwise ops and clips between layers (and after an LSTM or GRU) are not "
                                 "supported");
    if (p.kind == Piece::Kind::kClip) {
      for (std::uint32_t j = 0; j < n_out; ++j) {
        ylo[j] = std::max(ylo[j], p.lo);
        yhi[j] = std::min(yhi[j], p.hi);
        if (ylo[j] > yhi[j]) return Refuse(*p.node, "leaves no value for output element " + std::to_string(j));
      }
    } else {
      for (std::uint32_t j = 0; j < n_out; ++j) {
        if (p.a[j] == 0.0) return Refuse(*p.node, "multiplies output element " + std::to_string(j) + " by 0");
        const double l = p.a[j] * ylo[j] + p.b[j], h = p.a[j] * yhi[j] + p.b[j];
        ylo[j] = std::min(l, h);
        yhi[j] = std::max(l, h);
        sy[j] *= p.a[j];
        oy[j] = p.a[j] * oy[j] + p.b[j];
      }
    }
    out_nodes.push_back(p.node);
  }

  // First layer: constant inputs into the bias; the normaliser into the blob's, or into the
  // weights when it has no clip and an element's scale is not positive.
  // The mapping against the model.
  if (in_->name != map_.input_name || in_->size != map_.input_size)
    return MakeError(ErrorCode::kMismatch, map_.origin + ": input: '" + map_.input_name + "' of " +
                                               std::to_string(map_.input_size) + " elements, but " + m_.origin +
                                               " takes '" + in_->name + "' of " + std::to_string(in_->size));
  if (out_->name != map_.output_name || out_->size != map_.output_size)
    return MakeError(ErrorCode::kMismatch, map_.origin + ": output: '" + map_.output_name + "' of " +
                                               std::to_string(map_.output_size) + " elements, but " + m_.origin +
                                               " gives '" + out_->name + "' of " + std::to_string(out_->size));
  if (layers.back().lin.kind == Piece::Kind::kRecurrent)
    return Refuse(*layers.back().lin.node, "the last layer: the action comes from a Gemm or MatMul after it");
  Piece& first = layers.front().lin;
  const double c_lo = clip ? clip->lo : -kInf, c_hi = clip ? clip->hi : kInf;
  bool fold = false;
  for (std::uint32_t j = 0; j < n_in; ++j)
    if (map_.input_source[j] >= 0 && !(a[j] > 0)) {
      if (clip != nullptr)
        return Refuse(*clip->node, "input element " + std::to_string(j) + " is scaled by " + YamlFields::Num(a[j]) +
                                       " before this clip: the blob's normaliser needs a positive scale");
      fold = true;
    }
  std::vector<double> bias = first.bias;
  std::uint32_t constants = 0;
  for (std::uint32_t j = 0; j < n_in; ++j) {
    double add = 0;
    if (map_.input_source[j] < 0) {
      add = std::clamp(a[j] * map_.input_constant[j] + b[j], c_lo, c_hi);
      ++constants;
    } else if (fold) {
      add = b[j];
    } else {
      continue;
    }
    for (std::uint32_t o = 0; o < first.rows(); ++o) bias[o] += first.w[o * n_in + j] * add;
  }
  const std::uint32_t n_obs = layout_.observation_size();
  std::vector<std::uint32_t> element_of_obs(n_obs, 0);
  for (std::uint32_t j = 0; j < n_in; ++j)
    if (map_.input_source[j] >= 0) element_of_obs[static_cast<std::uint32_t>(map_.input_source[j])] = j;
  s.input_size = n_obs;
  s.output_size = static_cast<std::uint32_t>(layout_.actions.size());
  s.obs_mean.assign(n_obs, 0.0f);
  s.obs_inv_std.assign(n_obs, 1.0f);
  s.obs_clip = clip ? static_cast<float>(clip->hi) : std::numeric_limits<float>::max();
  for (std::uint32_t i_obs = 0; i_obs < n_obs; ++i_obs) {
    const std::uint32_t j = element_of_obs[i_obs];
    if (fold) continue;
    s.obs_mean[i_obs] = static_cast<float>(-b[j] / a[j]);
    s.obs_inv_std[i_obs] = static_cast<float>(a[j]);
  }
  for (std::size_t l = 0; l < layers.size(); ++l) {
    const Piece& p = layers[l].lin;
    policy::Layer d;
    d.kind = p.recurrent;
    d.activation = p.activation;
    d.alpha = static_cast<float>(p.alpha);
    d.in = l == 0 ? n_obs : p.in;
    d.out = l + 1 == layers.size() ? s.output_size : p.out;
    const std::uint32_t rows = d.out * d.gates();
    d.weight.resize(static_cast<std::size_t>(d.in) * rows);
    d.bias.resize(rows);
    if (p.kind == Piece::Kind::kRecurrent) {
      d.linear_before_reset = p.linear_before_reset;
      for (double v : p.rw) d.recurrent_weight.push_back(static_cast<float>(v));
      for (double v : p.rbias) d.recurrent_bias.push_back(static_cast<float>(v));
    }
    for (std::uint32_t o = 0; o < rows; ++o) {
      const std::uint32_t row = l + 1 == layers.size() ? map_.output_of_action[o] : o;
      d.bias[o] = static_cast<float>(l == 0 ? bias[row] : p.bias[row]);
      for (std::uint32_t k = 0; k < d.in; ++k) {
        const std::uint32_t col = l == 0 ? element_of_obs[k] : k;
        const double scale = l == 0 && fold ? a[col] : 1.0;
        d.weight[o * d.in + k] = static_cast<float>(p.w[row * p.in + col] * scale);
      }
    }
    s.layers.push_back(std::move(d));
  }
  // The action map: the layout's, composed with the model's output map.
  robot::ApplyLayoutToSpec(layout_, s);
  s.action_head = policy::ActionHead::kLinear;
  for (std::uint32_t k = 0; k < s.output_size; ++k) {
    const robot::ActionElement& L = layout_.actions[k];
    const std::uint32_t j = map_.output_of_action[k];
    const double c1 = L.scale * ylo[j] + L.offset, c2 = L.scale * yhi[j] + L.offset;
    const double low = std::max(L.low, std::min(c1, c2)), high = std::min(L.high, std::max(c1, c2));
    if (!(low <= high))
      return Refuse(*out_nodes.back(), "output element " + std::to_string(j) + " ('" + L.name + "') is held in [" +
                                           YamlFields::Num(ylo[j]) + ", " + YamlFields::Num(yhi[j]) + "], commands [" +
                                           YamlFields::Num(std::min(c1, c2)) + ", " +
                                           YamlFields::Num(std::max(c1, c2)) + "], outside the layout's limits [" +
                                           YamlFields::Num(L.low) + ", " + YamlFields::Num(L.high) + "]");
    s.action_scale[k] = static_cast<float>(L.scale * sy[j]);
    s.action_offset[k] = static_cast<float>(L.scale * oy[j] + L.offset);
    s.action_low[k] = policy::FloatNotBelow(low);
    s.action_high[k] = policy::FloatNotAbove(high);
  }

  // What was recognised.
  std::string norm = norm_nodes.empty() ? "none" : Names(norm_nodes);
  *graph_normaliser = !norm_nodes.empty();
  if (clip) norm += ", clip at " + YamlFields::Num(clip->hi);
  notes.push_back("normaliser:  " + norm +
                  (fold                 ? " (folded into the first layer: a scale is not positive)"
                   : norm_nodes.empty() ? ""
                                        : " -> the blob's"));
  for (std::size_t l = 0; l < layers.size(); ++l) {
    const Piece& p = layers[l].lin;
    const bool rec = p.kind == Piece::Kind::kRecurrent;
    notes.push_back("layer " + std::to_string(l) + ":     " + std::to_string(p.in) + " -> " + std::to_string(p.out) +
                    " " + (rec ? policy::ToString(p.recurrent) : policy::ToString(p.activation)) +
                    (rec && p.linear_before_reset ? " (linear_before_reset)" : "") + "  (" + Names(layers[l].nodes) +
                    ")" + (rec ? "  state " + p.state_note : ""));
  }
  notes.push_back("output map:  " +
                  (out_nodes.empty() ? std::string("none") : Names(out_nodes) + " -> the action map"));
  notes.push_back(
      "inputs:      " + std::to_string(n_in - constants) + " layout observations" +
      (constants ? ", " + std::to_string(constants) + " constants folded into the first layer's bias" : ""));
  if (map_.stacked)
    notes.push_back("history:     " + std::to_string(map_.history_length) + " frames, " +
                    (map_.frame_major ? "frame-major" : "term-major") + ", oldest " +
                    (map_.oldest_first ? "first" : "last"));
  return {};
}

// The mapping's input and output among the graph's, and its state inputs and outputs: every other
// graph input or output is refused, naming it.
Status Importer::SelectPorts() {
  auto is_state_input = [&](const std::string& name) {
    for (const StatePair& q : map_.state)
      if (q.input == name) return true;
    return false;
  };
  auto is_state_output = [&](const std::string& name) {
    for (const StatePair& q : map_.state)
      if (q.output == name) return true;
    return false;
  };
  const std::string state_note = map_.state.empty() ? "" : " and the mapping's state";
  bool stray_input = false, stray_output = false;
  for (const Port& p : m_.inputs) stray_input |= p.name != map_.input_name && !is_state_input(p.name);
  for (const Port& p : m_.outputs) stray_output |= p.name != map_.output_name && !is_state_output(p.name);
  if (stray_input && m_.inputs.size() > 1) {
    std::string list;
    for (const Port& p : m_.inputs) list += (list.empty() ? "" : "; ") + ("'" + p.name + "' used by ") + p.users;
    return Refuse(std::to_string(m_.inputs.size()) + " graph inputs (" + list +
                  "): the engine takes one observation vector" + state_note +
                  ", and weights must be initializers (a recurrent model's state inputs are named in the mapping's "
                  "state)");
  }
  if (stray_output && m_.outputs.size() > 1) {
    std::string list;
    for (const Port& p : m_.outputs) list += (list.empty() ? "" : ", ") + ("'" + p.name + "'");
    return Refuse(std::to_string(m_.outputs.size()) + " graph outputs (" + list +
                  "): the engine gives one action vector" + state_note);
  }
  // By the mapping's names; a model of one input and output is walked whatever they are called, so
  // that what the graph cannot run is said before how the mapping differs (CheckPorts).
  in_ = m_.FindInput(map_.input_name);
  out_ = m_.FindOutput(map_.output_name);
  if (in_ == nullptr) in_ = &m_.inputs.front();
  if (out_ == nullptr) out_ = &m_.outputs.front();
  for (const Port* p : {in_, out_})
    if (!p->problem.empty()) return MakeError(ErrorCode::kUnsupported, p->problem);
  if (in_->dims.size() > 2)
    return Refuse("input '" + in_->name + "' has rank 3: the observation is [batch, size] or [size]");
  for (std::size_t i = 0; i < map_.state.size(); ++i) {
    const StatePair& q = map_.state[i];
    const std::string where = map_.origin + ": state[" + std::to_string(i) + "]";
    const Port* a = m_.FindInput(q.input);
    const Port* b = m_.FindOutput(q.output);
    if (a == nullptr)
      return MakeError(ErrorCode::kMismatch, where + ".input: '" + q.input + "' is not a graph input of " + m_.origin);
    if (b == nullptr)
      return MakeError(ErrorCode::kMismatch,
                       where + ".output: '" + q.output + "' is not a graph output of " + m_.origin);
    for (const Port* port : {a, b})
      if (!port->problem.empty()) return MakeError(ErrorCode::kUnsupported, port->problem);
    if (a->dims != b->dims)
      return MakeError(ErrorCode::kMismatch, where + ": '" + q.input + "' and '" + q.output +
                                                 "' differ in shape: the output cannot be fed back to the input");
  }
  return {};
}

Result<Imported> Importer::Run(const ImportOptions& options) {
  if (auto st = SelectPorts(); !st) return st.error();
  if (auto st = Walk(); !st) return st.error();

  Imported out;
  if (auto st = Assemble(out.spec, out.notes, &out.graph_normaliser); !st) return st.error();
  policy::Provenance& p = out.spec.provenance;
  p.trainer_version = Printable((m_.producer_name.empty() ? "unknown producer" : m_.producer_name) +
                                    (m_.producer_version.empty() ? "" : " " + m_.producer_version) + " via ONNX",
                                200);
  p.git_revision = Printable(options.importer, 200);
  p.environment = Printable("onnx " + options.source_name.substr(0, 100) + " sha256 " + options.source_sha256 +
                                " opset " + std::to_string(m_.opset) + " ir " + std::to_string(m_.ir_version),
                            256);
  p.clip_schedule = "imported (not trained by pbppo)";
  if (auto st = policy::ValidateSpec(out.spec); !st)
    return MakeError(st.error().code, m_.origin + ": the imported policy: " + st.error().message);

  // The check: the blob's float64 reference against the graph's own evaluation (a recurrent
  // policy's golden rows are one sequence: the graph runs them in order with its state fed back).
  out.golden = policy::MakeGoldenVectors(out.spec, options.golden_rows, options.golden_seed);
  auto graph = GraphCommands(m_, map_, layout_, out.golden.observations);
  if (!graph) return std::move(graph).error();
  for (std::size_t r = 0; r < out.golden.observations.size(); ++r) {
    const std::vector<double>& cmd = (*graph)[r];
    const policy::ReferenceOutput& ref = out.golden.expected[r];
    for (std::size_t k = 0; k < cmd.size(); ++k) {
      const double d = std::fabs(cmd[k] - ref.action[k]);
      const double ratio = d / CheckTolerance(ref.error_bound[k], ref.action[k]);
      out.check_max_abs = std::max(out.check_max_abs, d);
      out.check_max_ratio = std::max(out.check_max_ratio, std::isnan(ratio) ? kInf : ratio);
      if (!(ratio <= 1.0))
        return MakeError(ErrorCode::kMismatch,
                         m_.origin + ": the imported policy does not act as the graph: golden row " +
                             std::to_string(r) + ", action '" + layout_.actions[k].name +
                             "': " + YamlFields::Num(ref.action[k]) + " from the blob, " + YamlFields::Num(cmd[k]) +
                             " from the graph (tolerance " +
                             YamlFields::Num(CheckTolerance(ref.error_bound[k], ref.action[k])) + ")");
    }
  }
  return out;
}

}  // namespace

double CheckTolerance(double bound, double value) noexcept {
  return 2.0 * bound + 1e-5 * std::max(1.0, std::fabs(value));
}

Result<Imported> Import(const Model& model, const Mapping& mapping, const robot::IoLayout& layout,
                        const ImportOptions& options) {
  Importer im(model, mapping, layout);
  return im.Run(options);
}

std::vector<double> InputRow(const Mapping& mapping, std::span<const float> obs) {
  std::vector<double> row(mapping.input_size);
  for (std::size_t j = 0; j < row.size(); ++j) {
    const std::int32_t src = mapping.input_source[j];
    row[j] = src < 0 ? mapping.input_constant[j] : static_cast<double>(obs[static_cast<std::size_t>(src)]);
  }
  return row;
}

std::vector<double> CommandsOf(const Mapping& mapping, const robot::IoLayout& layout, std::span<const double> y) {
  std::vector<double> cmd(layout.actions.size());
  for (std::size_t k = 0; k < cmd.size(); ++k) {
    const robot::ActionElement& L = layout.actions[k];
    cmd[k] = std::clamp(L.scale * y[mapping.output_of_action[k]] + L.offset, L.low, L.high);
  }
  return cmd;
}

Result<std::vector<std::vector<double>>> GraphCommands(const Model& model, const Mapping& mapping,
                                                       const robot::IoLayout& layout,
                                                       const std::vector<std::vector<float>>& observations) {
  Feeds feeds;
  for (const StatePair& q : mapping.state) {
    const Port* p = model.FindInput(q.input);
    if (p == nullptr) return MakeError(ErrorCode::kMismatch, model.origin + ": no state input '" + q.input + "'");
    std::size_t n = 1;
    for (auto d : p->dims) n *= static_cast<std::size_t>(d);
    feeds[q.input].assign(n, 0.0);
  }
  std::vector<std::vector<double>> out;
  for (const auto& row : observations) {
    feeds[mapping.input_name] = InputRow(mapping, row);
    auto y = EvaluateGraph(model, feeds);
    if (!y) return std::move(y).error();
    out.push_back(CommandsOf(mapping, layout, (*y)[mapping.output_name]));
    for (const StatePair& q : mapping.state) feeds[q.input] = (*y)[q.output];
  }
  return out;
}

}  // namespace pbppo::onnx
