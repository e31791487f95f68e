#include "runtime/policy/reference.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "runtime/core/random.hpp"
#include "runtime/policy/blob.hpp"

namespace pbppo::policy {
namespace {

constexpr double kU = 0x1.0p-24;  // unit roundoff of float32

double Gamma(std::size_t n) {
  return static_cast<double>(n) * kU / (1.0 - static_cast<double>(n) * kU);
}

double Activate(Activation a, double alpha, double x) {
  switch (a) {
    case Activation::kIdentity: return x;
    case Activation::kTanh: return std::tanh(x);
    case Activation::kElu: return x > 0.0 ? x : std::expm1(x);
    case Activation::kRelu: return x > 0.0 ? x : 0.0;
    case Activation::kLeakyRelu: return x > 0.0 ? x : alpha * x;
  }
  return x;
}

// The float32 activation's own error at output fx = act(f), beyond the error e of its input
// (|f^ - f| <= e, carried on through |W|: every activation here is 1-Lipschitz).
// - identity, relu: exact (a copy, a max with 0).
// - tanh, elu: the kernels' approximations, within 4 kU of max(|fx|, 1).
// - leaky_relu: one float multiply, alpha * f^, where the kernel's pre-activation f^ is not
//   positive. Rounded to nearest it is off by at most u * alpha * |f^| (u = kU). With
//   0 <= alpha <= 1, alpha |f^| <= |fx| + alpha e: for f <= 0, alpha |f^| <= alpha (|f| + e) =
//   |fx| + alpha e; for f > 0 (f^ <= 0 across the sign change), |f^| <= e. So u (|fx| + alpha e)
//   bounds it rigorously, also next to 0 where f and f^ differ in sign and a bound in |fx| alone
//   (even a whole ulp of |fx|) would not. The kernels' max(x, alpha x) and masked-multiply forms
//   return this same float. Underflow is left to the final absolute slack, as in the dot products.
double ActivationRoundoff(Activation a, double alpha, double fx, double e) {
  switch (a) {
    case Activation::kIdentity:
    case Activation::kRelu: return 0.0;
    case Activation::kLeakyRelu: return kU * (std::fabs(fx) + alpha * e);
    case Activation::kTanh:
    case Activation::kElu: break;
  }
  return 4.0 * kU * std::max(std::fabs(fx), 1.0);
}

// A value and the bound on a float32 computation's deviation from it.
struct Bounded {
  double v = 0.0, e = 0.0;
};

// The product of two bounded values as a float multiply gives it: the error carried (first and
// second order) and one rounding of the computed product's magnitude.
Bounded Mul(Bounded a, Bounded b) {
  const double carried = std::fabs(a.v) * b.e + std::fabs(b.v) * a.e + a.e * b.e;
  return {a.v * b.v, carried + kU * (std::fabs(a.v) + a.e) * (std::fabs(b.v) + b.e)};
}

// The sum of two bounded values with one rounding.
Bounded Add(Bounded a, Bounded b) {
  return {a.v + b.v, a.e + b.e + kU * (std::fabs(a.v) + a.e + std::fabs(b.v) + b.e)};
}

// Row `row` of W x + b over row-major W of width n: a dot product of length n + 1 rounds within
// gamma(n + 1) * sum |w| (|x| + e) (Higham; any order, FMA or not); input errors carry through |w|.
Bounded Affine(const float* w_rows, const float* bias, std::size_t n, const std::vector<double>& x,
               const std::vector<double>& e, std::size_t row) {
  const float* w = w_rows + row * n;
  double acc = static_cast<double>(bias[row]), mag = std::fabs(static_cast<double>(bias[row])), prop = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double wi = static_cast<double>(w[i]);
    acc += wi * x[i];
    mag += std::fabs(wi) * (std::fabs(x[i]) + e[i]);
    prop += std::fabs(wi) * e[i];
  }
  return {acc, prop + Gamma(n + 1) * mag};
}

// sigmoid as the kernels compute it, 0.5 * tanh(0.5 x) + 0.5: the halvings are exact, tanh is
// within 4 kU (|tanh| <= 1), the halving of it exact and the final add one rounding of a value
// at most 1; the input error carries through sigmoid's slope, at most 1/4.
Bounded Sigmoid(Bounded x) {
  return {1.0 / (1.0 + std::exp(-x.v)), 0.25 * x.e + 3.0 * kU};
}

Bounded Tanh(Bounded x) {
  return {std::tanh(x.v), x.e + 4.0 * kU};  // 1-Lipschitz; the kernels' tanh within 4 kU of 1
}

void LstmReference(const Layer& l, const std::vector<double>& x, const std::vector<double>& ex,
                   ReferenceState::Layer& st, std::vector<double>* y, std::vector<double>* ey) {
  const std::size_t n = l.out;
  std::vector<double> h(n), eh(n), c(n), ec(n);
  for (std::size_t j = 0; j < n; ++j) {
    Bounded g[4];
    for (std::size_t k = 0; k < 4; ++k) {
      g[k] = Add(Affine(l.weight.data(), l.bias.data(), l.in, x, ex, k * n + j),
                 Affine(l.recurrent_weight.data(), l.recurrent_bias.data(), n, st.h, st.eh, k * n + j));
    }
    const Bounded i = Sigmoid(g[0]), o = Sigmoid(g[1]), f = Sigmoid(g[2]), u = Tanh(g[3]);
    const Bounded cn = Add(Mul(f, {st.c[j], st.ec[j]}), Mul(i, u));
    const Bounded hn = Mul(o, Tanh(cn));
    h[j] = hn.v;
    eh[j] = hn.e;
    c[j] = cn.v;
    ec[j] = cn.e;
  }
  st.h = h;
  st.eh = eh;
  st.c = std::move(c);
  st.ec = std::move(ec);
  *y = std::move(h);
  *ey = std::move(eh);
}

void GruReference(const Layer& l, const std::vector<double>& x, const std::vector<double>& ex,
                  ReferenceState::Layer& st, std::vector<double>* y, std::vector<double>* ey) {
  const std::size_t n = l.out;
  const float* R = l.recurrent_weight.data();
  const float* Rb = l.recurrent_bias.data();
  std::vector<Bounded> z(n), r(n);
  for (std::size_t j = 0; j < n; ++j) {
    z[j] = Sigmoid(Add(Affine(l.weight.data(), l.bias.data(), l.in, x, ex, j), Affine(R, Rb, n, st.h, st.eh, j)));
    r[j] =
        Sigmoid(Add(Affine(l.weight.data(), l.bias.data(), l.in, x, ex, n + j), Affine(R, Rb, n, st.h, st.eh, n + j)));
  }
  std::vector<double> rh(n), erh(n);  // r * h, the input of R_h without linear_before_reset
  for (std::size_t i = 0; i < n; ++i) {
    const Bounded p = Mul(r[i], {st.h[i], st.eh[i]});
    rh[i] = p.v;
    erh[i] = p.e;
  }
  std::vector<double> h(n), eh(n);
  for (std::size_t j = 0; j < n; ++j) {
    const Bounded gx = Affine(l.weight.data(), l.bias.data(), l.in, x, ex, 2 * n + j);
    const Bounded pre = l.linear_before_reset ? Add(gx, Mul(r[j], Affine(R, Rb, n, st.h, st.eh, 2 * n + j)))
                                              : Add(gx, Affine(R, Rb, n, rh, erh, 2 * n + j));
    const Bounded nn = Tanh(pre);
    const Bounded one_minus_z{1.0 - z[j].v, z[j].e + kU * (std::fabs(1.0 - z[j].v) + z[j].e)};
    const Bounded hn = Add(Mul(one_minus_z, nn), Mul(z[j], {st.h[j], st.eh[j]}));
    h[j] = hn.v;
    eh[j] = hn.e;
  }
  st.h = h;
  st.eh = eh;
  *y = std::move(h);
  *ey = std::move(eh);
}

}  // namespace

ReferenceState MakeReferenceState(const PolicySpec& s) {
  ReferenceState st;
  st.layers.resize(s.layers.size());
  for (std::size_t i = 0; i < s.layers.size(); ++i) {
    const Layer& l = s.layers[i];
    if (l.kind == LayerKind::kDense) continue;
    ReferenceState::Layer& ls = st.layers[i];
    ls.h.assign(l.out, 0.0);
    ls.eh.assign(l.out, 0.0);
    if (l.kind == LayerKind::kLstm) {
      ls.c.assign(l.out, 0.0);
      ls.ec.assign(l.out, 0.0);
    }
  }
  return st;
}

ReferenceOutput ReferenceForward(const PolicySpec& s, const float* obs) {
  ReferenceState st = MakeReferenceState(s);
  return ReferenceForward(s, obs, &st);
}

ReferenceOutput ReferenceForward(const PolicySpec& s, const float* obs, ReferenceState* state) {
  std::vector<double> x(s.input_size), e(s.input_size);
  const double clip = static_cast<double>(s.obs_clip);
  for (std::size_t i = 0; i < s.input_size; ++i) {
    const double v =
        (static_cast<double>(obs[i]) - static_cast<double>(s.obs_mean[i])) * static_cast<double>(s.obs_inv_std[i]);
    x[i] = std::clamp(v, -clip, clip);
    e[i] = 2.0 * kU * std::fabs(v) * 1.0000001;
  }
  for (std::size_t li = 0; li < s.layers.size(); ++li) {
    const Layer& l = s.layers[li];
    std::vector<double> y(l.out), ey(l.out);
    if (l.kind == LayerKind::kLstm) {
      LstmReference(l, x, e, state->layers[li], &y, &ey);
    } else if (l.kind == LayerKind::kGru) {
      GruReference(l, x, e, state->layers[li], &y, &ey);
    } else {
      const auto alpha = static_cast<double>(l.alpha);
      for (std::size_t j = 0; j < l.out; ++j) {
        const Bounded pre = Affine(l.weight.data(), l.bias.data(), l.in, x, e, j);
        y[j] = Activate(l.activation, alpha, pre.v);
        ey[j] = pre.e + ActivationRoundoff(l.activation, alpha, y[j], pre.e);
      }
    }
    x = std::move(y);
    e = std::move(ey);
  }
  ReferenceOutput out;
  out.action.resize(s.output_size);
  out.error_bound.resize(s.output_size);
  for (std::size_t j = 0; j < s.output_size; ++j) {
    double a = x[j], ea = e[j];
    if (s.action_head == ActionHead::kTanh) {
      a = std::tanh(a);
      ea += ActivationRoundoff(Activation::kTanh, 0.0, a, ea);
    }
    const double sc = static_cast<double>(s.action_scale[j]), off = static_cast<double>(s.action_offset[j]);
    const double scaled = a * sc + off;
    out.action[j] = std::clamp(scaled, static_cast<double>(s.action_low[j]), static_cast<double>(s.action_high[j]));
    out.error_bound[j] = ea * std::fabs(sc) + 2.0 * kU * (std::fabs(a * sc) + std::fabs(scaled)) + 1e-30;
  }
  return out;
}

GoldenVectors MakeGoldenVectors(const PolicySpec& s, std::size_t rows, std::uint64_t seed) {
  Rng rng(seed);
  ReferenceState state = MakeReferenceState(s);  // a recurrent policy's rows are one sequence
  GoldenVectors g;
  g.input_size = s.input_size;
  g.output_size = s.output_size;
  for (std::size_t r = 0; r < rows; ++r) {
    std::vector<float> obs(s.input_size);
    // Spread grows with the row: small rows probe the linear region, large ones the clip.
    const double spread = 0.25 + 3.0 * static_cast<double>(r) / static_cast<double>(std::max<std::size_t>(rows, 2) - 1);
    for (std::size_t i = 0; i < s.input_size; ++i) {
      const double sd = 1.0 / static_cast<double>(s.obs_inv_std[i]);
      obs[i] = static_cast<float>(static_cast<double>(s.obs_mean[i]) + sd * spread * rng.Normal());
    }
    g.expected.push_back(ReferenceForward(s, obs.data(), &state));
    g.observations.push_back(std::move(obs));
  }
  return g;
}

namespace {

// The golden file's text.
std::string GoldenText(const GoldenVectors& g) {
  std::string text;
  text += "# pbppo golden vectors: observation (float32) | reference action (float64 forward over the\n";
  text += "# blob's float32 parameters) | per-element bound on a float32 forward's deviation\n";
  char buf[64];
  std::snprintf(buf, sizeof buf, "pbppo-golden 1 %u %u %zu\n", g.input_size, g.output_size, g.observations.size());
  text += buf;
  for (std::size_t r = 0; r < g.observations.size(); ++r) {
    for (float v : g.observations[r]) {
      std::snprintf(buf, sizeof buf, "%.9g ", static_cast<double>(v));
      text += buf;
    }
    text += "|";
    for (double v : g.expected[r].action) {
      std::snprintf(buf, sizeof buf, " %.17g", v);
      text += buf;
    }
    text += " |";
    for (double v : g.expected[r].error_bound) {
      std::snprintf(buf, sizeof buf, " %.3e", v);
      text += buf;
    }
    text += "\n";
  }
  return text;
}

std::span<const std::uint8_t> Bytes(const std::string& text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

}  // namespace

Status WriteGoldenFile(const std::string& path, const GoldenVectors& g) {
  return WriteFileAtomic(path, Bytes(GoldenText(g)));
}

Result<GoldenVectors> ReadGoldenFile(const std::string& path) {
  std::ifstream f(path);
  if (!f) return MakeError(ErrorCode::kIo, path + ": cannot open");
  std::string line;
  GoldenVectors g;
  std::size_t rows = 0, lineno = 0;
  bool header = false;
  while (std::getline(f, line)) {
    ++lineno;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    const std::string where = path + ":" + std::to_string(lineno) + ": ";
    if (!header) {
      std::string magic;
      int version = 0;
      if (!(in >> magic >> version >> g.input_size >> g.output_size >> rows) || magic != "pbppo-golden" ||
          version != 1) {
        return MakeError(ErrorCode::kFormat, where + "expected 'pbppo-golden 1 INPUT OUTPUT ROWS'");
      }
      header = true;
      continue;
    }
    std::vector<float> obs(g.input_size);
    ReferenceOutput out;
    out.action.resize(g.output_size);
    out.error_bound.resize(g.output_size);
    std::string bar1, bar2;
    for (auto& v : obs) in >> v;
    in >> bar1;
    for (auto& v : out.action) in >> v;
    in >> bar2;
    for (auto& v : out.error_bound) in >> v;
    if (!in || bar1 != "|" || bar2 != "|") {
      return MakeError(ErrorCode::kFormat, where + "expected " + std::to_string(g.input_size) + " observations | " +
                                               std::to_string(g.output_size) + " actions | " +
                                               std::to_string(g.output_size) + " bounds");
    }
    g.observations.push_back(std::move(obs));
    g.expected.push_back(std::move(out));
  }
  if (!header) return MakeError(ErrorCode::kFormat, path + ": no 'pbppo-golden' header");
  if (g.observations.size() != rows) {
    return MakeError(ErrorCode::kFormat, path + ": header says " + std::to_string(rows) + " rows, file has " +
                                             std::to_string(g.observations.size()));
  }
  return g;
}

std::string GoldenPathFor(const std::string& blob_path) {
  return PathBeside(blob_path, ".golden");
}

Status WritePolicyFiles(const std::string& blob_path, const PolicySpec& spec, const GoldenVectors& golden) {
  auto blob = EncodeBlob(spec);
  if (!blob) return blob.error();
  const std::string golden_path = GoldenPathFor(blob_path);
  if (golden.input_size != spec.input_size || golden.output_size != spec.output_size)
    return MakeError(ErrorCode::kInvalidValue,
                     golden_path + ": golden vectors of " + std::to_string(golden.input_size) + " observations and " +
                         std::to_string(golden.output_size) + " actions for a policy of " +
                         std::to_string(spec.input_size) + " and " + std::to_string(spec.output_size));
  const std::string text = GoldenText(golden);
  const FileBytes files[] = {{golden_path, Bytes(text)}, {blob_path, *blob}};
  return WriteFilesAtomic(files);
}

}  // namespace pbppo::policy
