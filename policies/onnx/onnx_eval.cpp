#include "policies/onnx/onnx_eval.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

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

}  // namespace

Result<std::vector<double>> Evaluate(const Model& model, std::span<const double> input) {
  std::map<std::string, Value> values;
  values[model.input.name] = Value{model.input.has_batch ? std::vector<std::int64_t>{1, model.input.size}
                                                         : std::vector<std::int64_t>{model.input.size},
                                   std::vector<double>(input.begin(), input.end())};
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
    if (op == "Gemm" || op == "MatMul") {
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
  auto it = values.find(model.output.name);
  if (it == values.end())
    return MakeError(ErrorCode::kFormat, model.origin + ": output '" + model.output.name + "' is computed by no node");
  if (it->second.v.size() != model.output.size)
    return MakeError(ErrorCode::kMismatch, model.origin + ": output '" + model.output.name + "' has " +
                                               std::to_string(it->second.v.size()) + " elements, its declared size " +
                                               std::to_string(model.output.size));
  return it->second.v;
}

}  // namespace pbppo::onnx
