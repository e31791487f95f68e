#include "policies/onnx/onnx_eval.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

namespace pbppo::onnx {
namespace {

// A value: its elements and its dimensions (a row is [1, n] or [n]).
struct Value {
  std::vector<std::int64_t> dims;
  std::vector<double> v;
};

Error EvalError(const Model& m, const Node& n, const std::string& what) {
  return MakeError(ErrorCode::kUnsupported, m.origin + ": evaluating " + n.Label() + ": " + what);
}

double AttrF(const Node& n, const char* name, double dflt) {
  const Attribute* a = n.Find(name);
  return a && a->kind == Attribute::Kind::kFloat ? a->f : dflt;
}

std::int64_t AttrI(const Node& n, const char* name, std::int64_t dflt) {
  const Attribute* a = n.Find(name);
  return a && a->kind == Attribute::Kind::kInt ? a->i : dflt;
}

// Numpy-style broadcasting of two operands of rank <= 2.
Result<Value> Broadcast(const Model& m, const Node& n, const Value& a, const Value& b, double (*op)(double, double)) {
  const std::size_t rank = std::max(a.dims.size(), b.dims.size());
  std::vector<std::int64_t> da(rank, 1), db(rank, 1), dr(rank, 1);
  std::copy(a.dims.begin(), a.dims.end(), da.begin() + static_cast<long>(rank - a.dims.size()));
  std::copy(b.dims.begin(), b.dims.end(), db.begin() + static_cast<long>(rank - b.dims.size()));
  for (std::size_t i = 0; i < rank; ++i) {
    if (da[i] != db[i] && da[i] != 1 && db[i] != 1) return EvalError(m, n, "shapes do not broadcast");
    dr[i] = std::max(da[i], db[i]);
  }
  Value r;
  r.dims = dr;
  std::size_t total = 1;
  for (auto d : dr) total *= static_cast<std::size_t>(d);
  r.v.resize(total);
  for (std::size_t k = 0; k < total; ++k) {
    std::size_t rem = k, ia = 0, ib = 0, sa = 1, sb = 1;
    for (std::size_t i = rank; i-- > 0;) {
      const auto idx = rem % static_cast<std::size_t>(dr[i]);
      rem /= static_cast<std::size_t>(dr[i]);
      ia += (da[i] == 1 ? 0 : idx) * sa;
      ib += (db[i] == 1 ? 0 : idx) * sb;
      sa *= static_cast<std::size_t>(da[i]);
      sb *= static_cast<std::size_t>(db[i]);
    }
    r.v[k] = op(a.v[ia], b.v[ib]);
  }
  return r;
}

// [rows, k] x [k, cols] with either operand transposed.
Result<Value> MatrixProduct(const Model& m, const Node& n, const Value& a, bool ta, const Value& b, bool tb) {
  auto as2 = [](const Value& x) {
    return x.dims.size() == 2 ? std::pair<std::int64_t, std::int64_t>{x.dims[0], x.dims[1]}
                              : std::pair<std::int64_t, std::int64_t>{1, x.dims.empty() ? 1 : x.dims[0]};
  };
  auto [ar, ac] = as2(a);
  auto [br, bc] = as2(b);
  if (b.dims.size() != 2) return EvalError(m, n, "the second operand is not a matrix");
  const std::int64_t rows = ta ? ac : ar, k = ta ? ar : ac, kb = tb ? bc : br, cols = tb ? br : bc;
  if (k != kb) return EvalError(m, n, "inner sizes " + std::to_string(k) + " and " + std::to_string(kb));
  Value r;
  r.dims = {rows, cols};
  r.v.assign(static_cast<std::size_t>(rows * cols), 0.0);
  for (std::int64_t i = 0; i < rows; ++i)
    for (std::int64_t j = 0; j < cols; ++j) {
      double s = 0;
      for (std::int64_t p = 0; p < k; ++p) {
        const double x = a.v[static_cast<std::size_t>(ta ? p * ac + i : i * ac + p)];
        const double y = b.v[static_cast<std::size_t>(tb ? j * bc + p : p * bc + j)];
        s += x * y;
      }
      r.v[static_cast<std::size_t>(i * cols + j)] = s;
    }
  return r;
}

std::size_t Count(const std::vector<std::int64_t>& dims) {
  std::size_t n = 1;
  for (auto d : dims) n *= static_cast<std::size_t>(d);
  return n;
}

// An axis of a value of rank `rank`, negative ones counted from the end; -1 when out of range.
std::int64_t Axis(std::int64_t a, std::size_t rank) {
  const auto r = static_cast<std::int64_t>(rank);
  if (a < 0) a += r;
  return a >= 0 && a < r ? a : -1;
}

double Sigmoid(double x) {
  return 1.0 / (1.0 + std::exp(-x));
}

// The ONNX LSTM (gates i, o, f, c) or GRU (z, r, h) operator, forward direction, default
// activations, in float64: X [seq, batch, in] -> Y [seq, 1, batch, H], Y_h [1, batch, H] (and
// Y_c [1, batch, H] for the LSTM).
Result<std::vector<Value>> Recurrent(const Model& m, const Node& n, const std::vector<std::optional<Value>>& in) {
  const bool lstm = n.op == "LSTM";
  const std::size_t gates = lstm ? 4 : 3;
  if (n.Find("activations") || n.Find("clip") || AttrI(n, "input_forget", 0) != 0 || AttrI(n, "layout", 0) != 0)
    return EvalError(m, n, "activations, clip, input_forget or layout other than the defaults");
  const Attribute* dir = n.Find("direction");
  if (dir != nullptr && dir->s != "forward") return EvalError(m, n, "direction '" + dir->s + "'");
  if (in.size() > 4 && in[4]) return EvalError(m, n, "sequence_lens");
  if (lstm && in.size() > 7 && in[7]) return EvalError(m, n, "peepholes");
  const Value& X = *in[0];
  const Value& W = *in[1];
  const Value& R = *in[2];
  if (X.dims.size() != 3 || W.dims.size() != 3 || R.dims.size() != 3) return EvalError(m, n, "X, W, R not rank 3");
  const auto seq = static_cast<std::size_t>(X.dims[0]), batch = static_cast<std::size_t>(X.dims[1]),
             nin = static_cast<std::size_t>(X.dims[2]);
  const auto H = static_cast<std::size_t>(R.dims[2]);
  if (W.dims[0] != 1 || static_cast<std::size_t>(W.dims[1]) != gates * H ||
      static_cast<std::size_t>(W.dims[2]) != nin || static_cast<std::size_t>(R.dims[1]) != gates * H)
    return EvalError(m, n, "W or R shapes do not match X and hidden_size");
  std::vector<double> B(2 * gates * H, 0.0);
  if (in.size() > 3 && in[3]) {
    if (in[3]->v.size() != B.size()) return EvalError(m, n, "B has " + std::to_string(in[3]->v.size()) + " elements");
    B = in[3]->v;
  }
  std::vector<double> h(batch * H, 0.0), c(batch * H, 0.0);
  if (in.size() > 5 && in[5]) {
    if (in[5]->v.size() != h.size()) return EvalError(m, n, "initial_h size");
    h = in[5]->v;
  }
  if (lstm && in.size() > 6 && in[6]) {
    if (in[6]->v.size() != c.size()) return EvalError(m, n, "initial_c size");
    c = in[6]->v;
  }
  const bool lbr = !lstm && AttrI(n, "linear_before_reset", 0) != 0;
  Value Y{{static_cast<std::int64_t>(seq), 1, static_cast<std::int64_t>(batch), static_cast<std::int64_t>(H)}, {}};
  Y.v.reserve(seq * batch * H);
  auto wx = [&](std::size_t row, const double* x) {
    double s = B[row];
    for (std::size_t k = 0; k < nin; ++k) s += W.v[row * nin + k] * x[k];
    return s;
  };
  auto rh = [&](std::size_t row, const double* hv) {
    double s = B[gates * H + row];
    for (std::size_t k = 0; k < H; ++k) s += R.v[row * H + k] * hv[k];
    return s;
  };
  for (std::size_t t = 0; t < seq; ++t) {
    std::vector<double> hn(batch * H), cn(batch * H);
    for (std::size_t b = 0; b < batch; ++b) {
      const double* x = X.v.data() + (t * batch + b) * nin;
      const double* hb = h.data() + b * H;
      if (lstm) {
        for (std::size_t j = 0; j < H; ++j) {
          const double i = Sigmoid(wx(j, x) + rh(j, hb)), o = Sigmoid(wx(H + j, x) + rh(H + j, hb));
          const double f = Sigmoid(wx(2 * H + j, x) + rh(2 * H + j, hb));
          const double u = std::tanh(wx(3 * H + j, x) + rh(3 * H + j, hb));
          cn[b * H + j] = f * c[b * H + j] + i * u;
          hn[b * H + j] = o * std::tanh(cn[b * H + j]);
        }
        continue;
      }
      std::vector<double> z(H), r(H), r_h(H);
      for (std::size_t j = 0; j < H; ++j) {
        z[j] = Sigmoid(wx(j, x) + rh(j, hb));
        r[j] = Sigmoid(wx(H + j, x) + rh(H + j, hb));
        r_h[j] = r[j] * hb[j];
      }
      for (std::size_t j = 0; j < H; ++j) {
        const double pre = wx(2 * H + j, x) + (lbr ? r[j] * rh(2 * H + j, hb) : rh(2 * H + j, r_h.data()));
        hn[b * H + j] = (1.0 - z[j]) * std::tanh(pre) + z[j] * hb[j];
      }
    }
    h = hn;
    if (lstm) c = cn;
    Y.v.insert(Y.v.end(), h.begin(), h.end());
  }
  std::vector<Value> out{Y, Value{{1, static_cast<std::int64_t>(batch), static_cast<std::int64_t>(H)}, h}};
  if (lstm) out.push_back(Value{{1, static_cast<std::int64_t>(batch), static_cast<std::int64_t>(H)}, c});
  return out;
}

}  // namespace

Result<std::vector<double>> Evaluate(const Model& model, std::span<const double> input) {
  Feeds feeds;
  feeds[model.input.name] = std::vector<double>(input.begin(), input.end());
  auto out = EvaluateGraph(model, feeds);
  if (!out) return std::move(out).error();
  return (*out)[model.output.name];
}

Result<Feeds> EvaluateGraph(const Model& model, const Feeds& feeds) {
  std::map<std::string, Value> values;
  for (const Port& p : model.inputs) {
    auto it = feeds.find(p.name);
    if (it == feeds.end())
      return MakeError(ErrorCode::kInvalidValue, model.origin + ": input '" + p.name + "' not fed");
    if (it->second.size() != Count(p.dims))
      return MakeError(ErrorCode::kInvalidValue, model.origin + ": input '" + p.name + "' fed " +
                                                     std::to_string(it->second.size()) + " values, it has " +
                                                     std::to_string(Count(p.dims)));
    values[p.name] = Value{p.dims, it->second};
  }
  auto get = [&](const Node& n, std::size_t k) -> Result<Value> {
    if (k >= n.inputs.size() || n.inputs[k].empty())
      return EvalError(model, n, "input " + std::to_string(k) + " missing");
    if (auto it = values.find(n.inputs[k]); it != values.end()) return it->second;
    const Tensor* t = model.Constant(n.inputs[k]);
    if (t == nullptr) return EvalError(model, n, "input '" + n.inputs[k] + "' has no value");
    if (!t->is_float32()) return EvalError(model, n, "constant '" + t->name + "' is " + DataTypeName(t->data_type));
    return Value{t->dims, t->values};
  };
  auto has = [](const Node& n, std::size_t k) { return k < n.inputs.size() && !n.inputs[k].empty(); };
  for (const Node& n : model.nodes) {
    if (n.outputs.empty()) return EvalError(model, n, "no output");
    auto x = get(n, 0);
    if (!x) return std::move(x).error();
    Value r;
    const std::string& op = n.op;
    // Integer operands of the shape operators (axes, starts, ends): an attribute before opset 13
    // (Unsqueeze, Squeeze) or 10 (Slice), an input after.
    auto ints = [&](std::size_t k, const char* attribute, std::vector<std::int64_t>* out) -> bool {
      if (const Attribute* a = n.Find(attribute); a != nullptr) {
        *out = a->ints;
        return true;
      }
      if (!has(n, k)) return false;
      const Tensor* t = model.Constant(n.inputs[k]);
      if (t == nullptr) return false;
      *out = t->ints;
      return true;
    };
    if (op == "LSTM" || op == "GRU") {
      std::vector<std::optional<Value>> in(n.inputs.size());
      for (std::size_t k = 0; k < n.inputs.size(); ++k) {
        if (!has(n, k)) continue;
        auto v = get(n, k);
        if (!v) return std::move(v).error();
        in[k] = std::move(*v);
      }
      if (in.size() < 3 || !in[1] || !in[2]) return EvalError(model, n, "W or R missing");
      auto outs = Recurrent(model, n, in);
      if (!outs) return std::move(outs).error();
      for (std::size_t k = 0; k < n.outputs.size() && k < outs->size(); ++k)
        if (!n.outputs[k].empty()) values[n.outputs[k]] = (*outs)[k];
      continue;
    }
    if (op == "Unsqueeze" || op == "Squeeze") {
      std::vector<std::int64_t> axes;
      const bool given = ints(1, "axes", &axes);
      r = std::move(*x);
      if (op == "Unsqueeze") {
        if (!given) return EvalError(model, n, "no axes");
        const std::size_t rank = r.dims.size() + axes.size();
        std::vector<bool> inserted(rank, false);
        for (auto a : axes) {
          const std::int64_t ax = Axis(a, rank);
          if (ax < 0) return EvalError(model, n, "axis " + std::to_string(a) + " out of range");
          inserted[static_cast<std::size_t>(ax)] = true;
        }
        std::vector<std::int64_t> dims;
        std::size_t from = 0;
        for (std::size_t k = 0; k < rank; ++k) dims.push_back(inserted[k] ? 1 : r.dims[from++]);
        r.dims = dims;
      } else {
        std::vector<bool> removed(r.dims.size(), !given);
        for (auto a : axes) {
          const std::int64_t ax = Axis(a, r.dims.size());
          if (ax < 0 || r.dims[static_cast<std::size_t>(ax)] != 1)
            return EvalError(model, n, "axis " + std::to_string(a) + " is not a dimension of size 1");
          removed[static_cast<std::size_t>(ax)] = true;
        }
        std::vector<std::int64_t> dims;
        for (std::size_t k = 0; k < r.dims.size(); ++k)
          if (!removed[k] || r.dims[k] != 1) dims.push_back(r.dims[k]);
        r.dims = dims;
      }
    } else if (op == "Slice") {
      std::vector<std::int64_t> starts, ends, axes, steps;
      if (!ints(1, "starts", &starts) || !ints(2, "ends", &ends)) return EvalError(model, n, "no starts or ends");
      if (!ints(3, "axes", &axes))
        for (std::size_t k = 0; k < starts.size(); ++k) axes.push_back(static_cast<std::int64_t>(k));
      if (ints(4, "steps", &steps))
        for (auto st : steps)
          if (st != 1) return EvalError(model, n, "step " + std::to_string(st));
      if (starts.size() != ends.size() || axes.size() != starts.size())
        return EvalError(model, n, "starts, ends and axes differ in length");
      r = std::move(*x);
      for (std::size_t k = 0; k < axes.size(); ++k) {
        const std::int64_t ax = Axis(axes[k], r.dims.size());
        if (ax < 0) return EvalError(model, n, "axis out of range");
        const std::int64_t d = r.dims[static_cast<std::size_t>(ax)];
        auto clamp = [d](std::int64_t v) { return std::clamp<std::int64_t>(v < 0 ? v + d : v, 0, d); };
        const std::int64_t b = clamp(starts[k]), e = std::max(b, clamp(ends[k]));
        std::size_t outer = 1, inner = 1;
        for (std::int64_t q = 0; q < ax; ++q) outer *= static_cast<std::size_t>(r.dims[static_cast<std::size_t>(q)]);
        for (std::size_t q = static_cast<std::size_t>(ax) + 1; q < r.dims.size(); ++q)
          inner *= static_cast<std::size_t>(r.dims[q]);
        std::vector<double> v;
        for (std::size_t o = 0; o < outer; ++o)
          for (std::int64_t i = b; i < e; ++i)
            for (std::size_t q = 0; q < inner; ++q)
              v.push_back(r.v[(o * static_cast<std::size_t>(d) + static_cast<std::size_t>(i)) * inner + q]);
        r.v = std::move(v);
        r.dims[static_cast<std::size_t>(ax)] = e - b;
      }
    } else if (op == "Concat") {
      std::vector<Value> parts{std::move(*x)};
      for (std::size_t k = 1; k < n.inputs.size(); ++k) {
        auto v = get(n, k);
        if (!v) return std::move(v).error();
        parts.push_back(std::move(*v));
      }
      const std::int64_t ax = Axis(AttrI(n, "axis", 0), parts[0].dims.size());
      if (ax < 0) return EvalError(model, n, "axis out of range");
      std::size_t outer = 1;
      for (std::int64_t q = 0; q < ax; ++q)
        outer *= static_cast<std::size_t>(parts[0].dims[static_cast<std::size_t>(q)]);
      r.dims = parts[0].dims;
      r.dims[static_cast<std::size_t>(ax)] = 0;
      for (const Value& p : parts) {
        if (p.dims.size() != r.dims.size()) return EvalError(model, n, "inputs of different ranks");
        r.dims[static_cast<std::size_t>(ax)] += p.dims[static_cast<std::size_t>(ax)];
      }
      for (std::size_t o = 0; o < outer; ++o)
        for (const Value& p : parts) {
          const std::size_t chunk = p.v.size() / outer;
          r.v.insert(r.v.end(), p.v.begin() + static_cast<long>(o * chunk),
                     p.v.begin() + static_cast<long>((o + 1) * chunk));
        }
    } else if (op == "Gemm" || op == "MatMul") {
      auto b = get(n, 1);
      if (!b) return std::move(b).error();
      const bool gemm = op == "Gemm";
      auto p = MatrixProduct(model, n, *x, gemm && AttrI(n, "transA", 0) != 0, *b, gemm && AttrI(n, "transB", 0) != 0);
      if (!p) return std::move(p).error();
      r = std::move(*p);
      if (gemm) {
        const double alpha = AttrF(n, "alpha", 1.0), beta = AttrF(n, "beta", 1.0);
        for (double& e : r.v) e *= alpha;
        if (has(n, 2)) {
          auto c = get(n, 2);
          if (!c) return std::move(c).error();
          for (double& e : c->v) e *= beta;
          auto s = Broadcast(model, n, r, *c, [](double u, double w) { return u + w; });
          if (!s) return std::move(s).error();
          r = std::move(*s);
        }
      }
    } else if (op == "Add" || op == "Sub" || op == "Mul" || op == "Div") {
      auto b = get(n, 1);
      if (!b) return std::move(b).error();
      double (*f)(double, double) = op == "Add"   ? [](double u, double w) { return u + w; }
                                    : op == "Sub" ? [](double u, double w) { return u - w; }
                                    : op == "Mul" ? [](double u, double w) { return u * w; }
                                                  : [](double u, double w) { return u / w; };
      auto s = Broadcast(model, n, *x, *b, f);
      if (!s) return std::move(s).error();
      r = std::move(*s);
    } else if (op == "Clip") {
      double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
      if (model.opset < 11) {
        lo = AttrF(n, "min", lo);
        hi = AttrF(n, "max", hi);
      } else {
        for (std::size_t k : {std::size_t{1}, std::size_t{2}}) {
          if (!has(n, k)) continue;
          auto c = get(n, k);
          if (!c) return std::move(c).error();
          if (c->v.size() != 1) return EvalError(model, n, "bound is not a scalar");
          (k == 1 ? lo : hi) = c->v[0];
        }
      }
      r = std::move(*x);
      for (double& e : r.v) e = std::min(std::max(e, lo), hi);
    } else if (op == "Relu" || op == "Tanh" || op == "Elu" || op == "LeakyRelu" || op == "Identity" ||
               op == "Flatten") {
      r = std::move(*x);
      const double elu = AttrF(n, "alpha", 1.0), leak = AttrF(n, "alpha", 0.01);
      for (double& e : r.v) {
        if (op == "Relu") e = e > 0 ? e : 0.0;
        if (op == "Tanh") e = std::tanh(e);
        if (op == "Elu") e = e > 0 ? e : elu * std::expm1(e);
        if (op == "LeakyRelu") e = e >= 0 ? e : leak * e;
      }
      if (op == "Flatten") r.dims = {1, static_cast<std::int64_t>(r.v.size())};
    } else {
      return EvalError(model, n, "operator not evaluated");
    }
    values[n.outputs[0]] = std::move(r);
  }
  Feeds out;
  for (const Port& p : model.outputs) {
    auto it = values.find(p.name);
    if (it == values.end())
      return MakeError(ErrorCode::kFormat, model.origin + ": output '" + p.name + "' is computed by no node");
    if (it->second.v.size() != Count(p.dims))
      return MakeError(ErrorCode::kMismatch, model.origin + ": output '" + p.name + "' has " +
                                                 std::to_string(it->second.v.size()) + " elements, its declared size " +
                                                 std::to_string(Count(p.dims)));
    out[p.name] = it->second.v;
  }
  return out;
}

}  // namespace pbppo::onnx
