// A dense MLP over a flat parameter vector, batched forward and hand-written backward, templated
// on the scalar: float for training, double for finite-difference gradient checks.
// Layout of the flat vector, layer by layer: weight [out x in] column-major, then bias [out].
// Batches are matrices with one sample per column.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "runtime/core/random.hpp"
#include "runtime/policy/policy_spec.hpp"

namespace pbppo::trainer {

template <typename S>
using Mat = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
template <typename S>
using Vec = Eigen::Matrix<S, Eigen::Dynamic, 1>;

using policy::Activation;

struct MlpShape {
  std::vector<int> widths;                    // input first, output last
  Activation hidden = Activation::kTanh;      // after every layer but the last
  Activation output = Activation::kIdentity;  // after the last layer
};

// y = f(z) in place, and the derivative f'(z) expressed through y (tanh: 1 - y^2, relu: y > 0,
// elu: y > 0 ? 1 : y + 1), which is all backward needs.
template <typename Derived>
void ApplyActivation(Activation a, Eigen::MatrixBase<Derived>& y) {
  using S = typename Derived::Scalar;
  switch (a) {
    case Activation::kIdentity: break;
    case Activation::kTanh: y.derived().array() = y.derived().array().tanh(); break;
    case Activation::kRelu: y.derived().array() = y.derived().array().max(S(0)); break;
    case Activation::kElu:
      // max(y, 0) + exp(min(y, 0)) - 1: the same function as the select of the two branches, in
      // packet operations throughout (Eigen's select evaluates the exponential one scalar at a time).
      y.derived().array() = y.derived().array().max(S(0)) + (y.derived().array().min(S(0)).exp() - S(1));
      break;
    case Activation::kLeakyRelu: break;  // blob and runtime only: Mlp refuses it
  }
}

template <typename DerivedD, typename DerivedY>
void MultiplyActivationDerivative(Activation a, Eigen::MatrixBase<DerivedD>& d, const Eigen::MatrixBase<DerivedY>& y) {
  using S = typename DerivedD::Scalar;
  switch (a) {
    case Activation::kIdentity: break;
    case Activation::kTanh: d.derived().array() *= S(1) - y.array().square(); break;
    case Activation::kRelu: d.derived().array() *= (y.array() > S(0)).template cast<S>(); break;
    case Activation::kElu: d.derived().array() *= (y.array() + S(1)).min(S(1)); break;  // y > 0: 1
    case Activation::kLeakyRelu: break;  // blob and runtime only: Mlp refuses it
  }
}

template <typename S>
class Mlp {
 public:
  struct Workspace {
    std::vector<Mat<S>> y;  // post-activation output of each layer
    std::vector<Mat<S>> d;  // d loss / d pre-activation of each layer
  };

  Mlp() = default;
  explicit Mlp(MlpShape shape) : shape_(std::move(shape)) {
    if (shape_.widths.size() < 2) throw std::invalid_argument("mlp: needs at least input and output widths");
    if (shape_.hidden == Activation::kLeakyRelu || shape_.output == Activation::kLeakyRelu)
      throw std::invalid_argument("mlp: leaky_relu is not trainable here (blob and runtime only)");
    std::size_t off = 0;
    for (std::size_t l = 0; l + 1 < shape_.widths.size(); ++l) {
      if (shape_.widths[l] <= 0 || shape_.widths[l + 1] <= 0)
        throw std::invalid_argument("mlp: widths must be positive");
      w_off_.push_back(off);
      off += static_cast<std::size_t>(out(l)) * static_cast<std::size_t>(in(l));
      b_off_.push_back(off);
      off += static_cast<std::size_t>(out(l));
    }
    size_ = off;
  }

  const MlpShape& shape() const noexcept { return shape_; }
  std::size_t size() const noexcept { return size_; }
  std::size_t layers() const noexcept { return w_off_.size(); }
  int in(std::size_t l) const noexcept { return shape_.widths[l]; }
  int out(std::size_t l) const noexcept { return shape_.widths[l + 1]; }
  int input_size() const noexcept { return shape_.widths.front(); }
  int output_size() const noexcept { return shape_.widths.back(); }
  Activation activation(std::size_t l) const noexcept { return l + 1 == layers() ? shape_.output : shape_.hidden; }

  Eigen::Map<const Mat<S>> W(const S* p, std::size_t l) const { return {p + w_off_[l], out(l), in(l)}; }
  Eigen::Map<Mat<S>> W(S* p, std::size_t l) const { return {p + w_off_[l], out(l), in(l)}; }
  Eigen::Map<const Vec<S>> b(const S* p, std::size_t l) const { return {p + b_off_[l], out(l)}; }
  Eigen::Map<Vec<S>> b(S* p, std::size_t l) const { return {p + b_off_[l], out(l)}; }

  // Orthogonal weights (gain `hidden_gain` on hidden layers, `output_gain` on the last), zero
  // biases.
  void InitOrthogonal(S* p, Rng& rng, double hidden_gain, double output_gain) const;

  // Output is ws.y.back() (out x batch).
  template <typename DerivedX>
  const Mat<S>& Forward(const S* p, const Eigen::MatrixBase<DerivedX>& x, Workspace& ws) const {
    ws.y.resize(layers());
    for (std::size_t l = 0; l < layers(); ++l) {
      Mat<S>& y = ws.y[l];
      y.resize(out(l), x.cols());
      if (l == 0) {
        y.noalias() = W(p, l) * x;
      } else {
        y.noalias() = W(p, l) * ws.y[l - 1];
      }
      y.colwise() += b(p, l);
      ApplyActivation(activation(l), y);
    }
    return ws.y.back();
  }

  // Given d loss / d output (out x batch) for the batch of the last Forward(), writes d loss /
  // d parameters into grad (overwriting). If dx is not null it receives d loss / d input.
  template <typename DerivedX, typename DerivedDY>
  void Backward(const S* p, const Eigen::MatrixBase<DerivedX>& x, Workspace& ws, const Eigen::MatrixBase<DerivedDY>& dy,
                S* grad, Mat<S>* dx = nullptr) const {
    ws.d.resize(layers());
    const std::size_t last = layers() - 1;
    ws.d[last] = dy;
    MultiplyActivationDerivative(activation(last), ws.d[last], ws.y[last]);
    for (std::size_t l = last + 1; l-- > 0;) {
      const Mat<S>& d = ws.d[l];
      if (l == 0) {
        W(grad, l).noalias() = d * x.transpose();
      } else {
        W(grad, l).noalias() = d * ws.y[l - 1].transpose();
      }
      b(grad, l) = d.rowwise().sum();
      if (l > 0) {
        Mat<S>& dp = ws.d[l - 1];
        dp.resize(in(l), d.cols());
        dp.noalias() = W(p, l).transpose() * d;
        MultiplyActivationDerivative(activation(l - 1), dp, ws.y[l - 1]);
      } else if (dx != nullptr) {
        dx->resize(in(0), d.cols());
        dx->noalias() = W(p, 0).transpose() * d;
      }
    }
  }

 private:
  MlpShape shape_;
  std::vector<std::size_t> w_off_, b_off_;
  std::size_t size_ = 0;
};

// torch.nn.init.orthogonal_ in our own terms: a Gaussian matrix from `rng`, made orthonormal by
// modified Gram-Schmidt (the QR factor with a positive diagonal), transposed when wider than tall.
inline void FillOrthogonal(double* out_colmajor, int rows, int cols, double gain, Rng& rng) {
  const bool wide = rows < cols;
  const int m = wide ? cols : rows;  // tall: m >= n
  const int n = wide ? rows : cols;
  Eigen::MatrixXd a(m, n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < m; ++i) a(i, j) = rng.Normal();
  for (int j = 0; j < n; ++j) {
    for (int pass = 0; pass < 2; ++pass) {  // re-orthogonalise once for accuracy
      for (int k = 0; k < j; ++k) a.col(j) -= a.col(k).dot(a.col(j)) * a.col(k);
    }
    const double norm = a.col(j).norm();
    a.col(j) /= norm;
  }
  Eigen::Map<Eigen::MatrixXd> w(out_colmajor, rows, cols);
  if (wide) {
    w = gain * a.transpose();
  } else {
    w = gain * a;
  }
}

template <typename S>
void Mlp<S>::InitOrthogonal(S* p, Rng& rng, double hidden_gain, double output_gain) const {
  for (std::size_t l = 0; l < layers(); ++l) {
    Eigen::MatrixXd w(out(l), in(l));
    FillOrthogonal(w.data(), out(l), in(l), l + 1 == layers() ? output_gain : hidden_gain, rng);
    W(p, l) = w.cast<S>();
    b(p, l).setZero();
  }
}

}  // namespace pbppo::trainer
