// Running mean/variance (parallel-update form, as stable-baselines3's RunningMeanStd) for
// observation normalisation and reward scaling.
#pragma once

#include <cmath>
#include <vector>

#include "policies/trainer/state_io.hpp"

namespace pbppo::trainer {

class RunningMeanStd {
 public:
  explicit RunningMeanStd(int n = 0)
      : mean_(static_cast<std::size_t>(n), 0.0), var_(static_cast<std::size_t>(n), 1.0) {}

  // Adds a batch of `count` samples (sample-major, n values each).
  void Update(const float* x, long count) {
    if (count <= 0) return;
    const std::size_t n = mean_.size();
    std::vector<double> bm(n, 0.0), bv(n, 0.0);
    for (long s = 0; s < count; ++s)
      for (std::size_t j = 0; j < n; ++j) bm[j] += x[static_cast<std::size_t>(s) * n + j];
    for (auto& m : bm) m /= static_cast<double>(count);
    for (long s = 0; s < count; ++s)
      for (std::size_t j = 0; j < n; ++j) {
        const double d = x[static_cast<std::size_t>(s) * n + j] - bm[j];
        bv[j] += d * d;
      }
    for (auto& v : bv) v /= static_cast<double>(count);
    const double c = static_cast<double>(count);
    const double total = count_ + c;
    for (std::size_t j = 0; j < n; ++j) {
      const double delta = bm[j] - mean_[j];
      const double m2 = var_[j] * count_ + bv[j] * c + delta * delta * count_ * c / total;
      mean_[j] += delta * c / total;
      var_[j] = m2 / total;
    }
    count_ = total;
  }

  const std::vector<double>& mean() const noexcept { return mean_; }
  const std::vector<double>& var() const noexcept { return var_; }
  double count() const noexcept { return count_; }

  void Save(ByteWriter& w) const {
    w.PutVector(mean_);
    w.PutVector(var_);
    w.Put(count_);
  }
  void Load(ByteReader& r) {
    r.GetVector(mean_, "running mean", static_cast<std::int64_t>(mean_.size()));
    r.GetVector(var_, "running variance", static_cast<std::int64_t>(var_.size()));
    count_ = r.Get<double>("running count");
  }

 private:
  std::vector<double> mean_, var_;
  double count_ = 1e-4;
};

}  // namespace pbppo::trainer
