// Observation normalisation as the blob carries it: out = clamp((raw - mean) * inv_std, -clip, clip).
// Learning (--normalize-obs): a running mean/variance over every rollout's raw observations, frozen
// into mean and inv_std before each rollout, clip 10. Otherwise the identity (no clip), or what an
// --init blob brought.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "policies/trainer/running_stats.hpp"

namespace pbppo::trainer {

class ObservationNormalizer {
 public:
  ObservationNormalizer() = default;
  ObservationNormalizer(int size, bool learn)
      : learn_(learn),
        rms_(size),
        mean_(static_cast<std::size_t>(size), 0.f),
        inv_std_(static_cast<std::size_t>(size), 1.f),
        clip_(learn ? 10.f : std::numeric_limits<float>::max()) {}

  int size() const noexcept { return static_cast<int>(mean_.size()); }

  void Normalize(const float* raw, float* out) const {
    for (std::size_t j = 0; j < mean_.size(); ++j)
      out[j] = std::clamp((raw[j] - mean_[j]) * inv_std_[j], -clip_, clip_);
  }
  // Adds `count` raw observations (sample-major) to the running statistics (when learning).
  void Update(const float* raw, long count) {
    if (learn_) rms_.Update(raw, count);
  }
  // Makes the running statistics the normaliser in use (when learning).
  void Freeze() {
    if (!learn_) return;
    for (std::size_t j = 0; j < mean_.size(); ++j) {
      mean_[j] = static_cast<float>(rms_.mean()[j]);
      inv_std_[j] = static_cast<float>(1.0 / std::sqrt(rms_.var()[j] + 1e-8));
    }
  }
  // A frozen normaliser (an --init blob's).
  void Load(std::vector<float> mean, std::vector<float> inv_std, float clip) {
    mean_ = std::move(mean);
    inv_std_ = std::move(inv_std);
    clip_ = clip;
  }

  const std::vector<float>& mean() const noexcept { return mean_; }
  const std::vector<float>& inv_std() const noexcept { return inv_std_; }
  float clip() const noexcept { return clip_; }

  // Its running statistics and the normaliser in use (a resumed run's).
  void Save(ByteWriter& w) const {
    rms_.Save(w);
    w.PutVector(mean_);
    w.PutVector(inv_std_);
    w.Put(clip_);
  }
  void Load(ByteReader& r) {
    rms_.Load(r);
    r.GetVector(mean_, "normaliser mean", static_cast<std::int64_t>(mean_.size()));
    r.GetVector(inv_std_, "normaliser inverse std", static_cast<std::int64_t>(inv_std_.size()));
    clip_ = r.Get<float>("normaliser clip");
  }

 private:
  bool learn_ = false;
  RunningMeanStd rms_;
  std::vector<float> mean_, inv_std_;
  float clip_ = std::numeric_limits<float>::max();
};

}  // namespace pbppo::trainer
