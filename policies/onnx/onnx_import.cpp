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
  enum class Kind : std::uint8_t { kAffine, kClip, kLinear, kActivation } kind;
  const Node* node = nullptr;
  std::vector<double> a, b;       // affine: x -> a x + b per element
  double lo = -kInf, hi = kInf;   // clip
  std::uint32_t in = 0, out = 0;  // linear
  std::vector<double> w, bias;    // linear: row-major [out][in]
  policy::Activation activation = policy::Activation::kIdentity;
  double alpha = 0;  // LeakyRelu
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
  Status Walk();
  Result<const Tensor*> ConstantInput(const Node& n, std::size_t k) const;
  Result<std::vector<double>> PerElement(const Node& n, const Tensor& t, std::uint32_t width) const;
  Status Assemble(policy::PolicySpec& s, std::vector<std::string>& notes);

  const Model& m_;
  const Mapping& map_;
  const robot::IoLayout& layout_;
  std::vector<Piece> pieces_;
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
  std::map<std::string, std::vector<const Node*>> users;
  for (const Node& n : m_.nodes)
    for (const std::string& v : n.inputs)
      if (!v.empty() && !m_.Constant(v)) users[v].push_back(&n);
  std::string cur = m_.input.name;
  std::uint32_t width = m_.input.size;
  while (true) {
    const auto& u = users[cur];
    if (cur == m_.output.name) {
      if (!u.empty()) return Refuse(*u[0], "reads the graph output '" + cur + "': the engine runs a chain of layers");
      break;
    }
    if (u.empty())
      return Refuse("value '" + cur + "' reaches no node and is not the graph output '" + m_.output.name + "'");
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
      const bool is_int = a.name == "transA" || a.name == "transB" || a.name == "axis";
      if ((is_float && a.kind != Attribute::Kind::kFloat) || (is_int && a.kind != Attribute::Kind::kInt))
        return Refuse(n, "attribute '" + a.name + "' is not " + (is_float ? "a float" : "an integer"));
    }
    if (n.outputs.size() != 1 || n.outputs[0].empty())
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
      }
      cur = n.outputs[0];
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
                    "LeakyRelu, Elu, Tanh, Identity, Flatten)");
    }
    pieces_.push_back(std::move(p));
    cur = n.outputs[0];
  }
  if (width != m_.output.size)
    return Refuse("the chain gives " + std::to_string(width) + " values, the output '" + m_.output.name +
                  "' declares " + std::to_string(m_.output.size));
  return {};
}

std::string Names(const std::vector<const Node*>& nodes) {
  std::string s;
  for (const Node* n : nodes) s += (s.empty() ? "" : ", ") + n->op + " '" + n->name + "'";
  return s;
}

Status Importer::Assemble(policy::PolicySpec& s, std::vector<std::string>& notes) {
  const std::uint32_t n_in = m_.input.size;
  std::size_t i = 0;
  // Input normaliser: x -> clamp(a x + b, lo, hi).
  std::vector<double> a(n_in, 1.0), b(n_in, 0.0);
  const Piece* clip = nullptr;
  std::vector<const Node*> norm_nodes;
  for (; i < pieces_.size() && pieces_[i].kind != Piece::Kind::kLinear; ++i) {
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
  if (i == pieces_.size()) return Refuse("no Gemm or MatMul: nothing the engine could run as a layer");

  // Layers; an affine map right after a linear one (MatMul then Add) folds into it.
  struct Layer {
    Piece lin;
    bool closed = false;
    std::vector<const Node*> nodes;
  };
  std::vector<Layer> layers;
  for (; i < pieces_.size(); ++i) {
    const Piece& p = pieces_[i];
    if (p.kind == Piece::Kind::kLinear) {
      if (!layers.empty()) layers.back().closed = true;
      layers.push_back({p, false, {p.node}});
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
  const std::uint32_t n_out = m_.output.size;
  std::vector<double> sy(n_out, 1.0), oy(n_out, 0.0), ylo(n_out, -kInf), yhi(n_out, kInf);
  std::vector<const Node*> out_nodes;
  for (; i < pieces_.size(); ++i) {
    const Piece& p = pieces_[i];
    if (p.kind == Piece::Kind::kLinear || p.kind == Piece::Kind::kActivation)
      return Refuse(*p.node, "follows the output map (" + Names(out_nodes) +
                                 "): elementwise ops and clips between layers are not supported");
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

  // The mapping against the model.
  if (map_.input_name != m_.input.name || map_.input_size != m_.input.size)
    return MakeError(ErrorCode::kMismatch, map_.origin + ": input: '" + map_.input_name + "' of " +
                                               std::to_string(map_.input_size) + " elements, but " + m_.origin +
                                               " takes '" + m_.input.name + "' of " + std::to_string(m_.input.size));
  if (map_.output_name != m_.output.name || map_.output_size != m_.output.size)
    return MakeError(ErrorCode::kMismatch, map_.origin + ": output: '" + map_.output_name + "' of " +
                                               std::to_string(map_.output_size) + " elements, but " + m_.origin +
                                               " gives '" + m_.output.name + "' of " + std::to_string(m_.output.size));

  // First layer: constant inputs into the bias; the normaliser into the blob's, or into the
  // weights when it has no clip and an element's scale is not positive.
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
    for (std::uint32_t o = 0; o < first.out; ++o) bias[o] += first.w[o * n_in + j] * add;
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
    d.activation = p.activation;
    d.alpha = static_cast<float>(p.alpha);
    d.in = l == 0 ? n_obs : p.in;
    d.out = l + 1 == layers.size() ? s.output_size : p.out;
    d.weight.resize(static_cast<std::size_t>(d.in) * d.out);
    d.bias.resize(d.out);
    for (std::uint32_t o = 0; o < d.out; ++o) {
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
    s.action_low[k] = static_cast<float>(low);
    s.action_high[k] = static_cast<float>(high);
  }

  // What was recognised.
  std::string norm = norm_nodes.empty() ? "none" : Names(norm_nodes);
  if (clip) norm += ", clip at " + YamlFields::Num(clip->hi);
  notes.push_back("normaliser:  " + norm +
                  (fold                 ? " (folded into the first layer: a scale is not positive)"
                   : norm_nodes.empty() ? ""
                                        : " -> the blob's"));
  for (std::size_t l = 0; l < layers.size(); ++l)
    notes.push_back("layer " + std::to_string(l) + ":     " + std::to_string(layers[l].lin.in) + " -> " +
                    std::to_string(layers[l].lin.out) + " " + policy::ToString(layers[l].lin.activation) + "  (" +
                    Names(layers[l].nodes) + ")");
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

Result<Imported> Importer::Run(const ImportOptions& options) {
  if (auto st = Walk(); !st) return st.error();
  Imported out;
  if (auto st = Assemble(out.spec, out.notes); !st) return st.error();
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

  // The check: the blob's float64 reference against the graph's own evaluation.
  out.golden = policy::MakeGoldenVectors(out.spec, options.golden_rows, options.golden_seed);
  for (std::size_t r = 0; r < out.golden.observations.size(); ++r) {
    auto y = Evaluate(m_, InputRow(map_, out.golden.observations[r]));
    if (!y) return std::move(y).error();
    const std::vector<double> cmd = CommandsOf(map_, layout_, *y);
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

}  // namespace pbppo::onnx
