// Clip schedules: what sets PPO's clip bound each iteration. A fixed bound, or a bandit over a
// set of candidate bounds (arms) fed by task return (Pb-PPO; see PBPPO.md).
//
//   fixed:EPS           plain PPO.
//   pbppo-paper[:wi-ad|:wo-ad]
//                       the paper's equations: UCB_i = U_i + lambda sqrt(N / (N_i + 1e-6)),
//                       E_i <- gamma_b E_i + R for the pulled arm, U = E (wo-ad) or E - mean(E)
//                       (wi-ad, the default: a uniform shift that never changes the argmax).
//                       Defaults lambda 5, gamma_b 0.99.
//   pbppo-reference[:wi-ad|:wo-ad]
//                       the released script's rule, wo-ad by default as the script runs:
//                       score_i = U_i + lambda sqrt(N / (N_i + 1e-6)) with the same discounted-sum
//                       E and U_i = E_i / (max_j E_j + 0.001); wi-ad, as the script computes it,
//                       subtracts the mean of those ratios from each (after dividing), so it
//                       chooses exactly as wo-ad and only the logged values differ. Quirks kept:
//                       the exploitation term is tiny beside the bonus (near round-robin, an
//                       index-order sweep at the start), the discounted sum favours often-pulled
//                       arms, and with negative returns a negative denominator flips the ranking.
//                       Where the script would divide by zero (max_j E_j = -0.001) or produce a
//                       non-finite ratio, the exploitation term is 0 for every arm (the bonus
//                       alone decides) instead of crashing.
//   pbppo               ours: discounted UCB (Garivier & Moulines 2011). The arm reward is the
//                       return improvement its update caused, (R_after - R_before) / s clamped to
//                       [-1, 1], with s a discounted mean of |R_after - R_before| (the running
//                       return scale). Discounted counts N_i and sums S_i (all arms decay by
//                       gamma_b on every update); score_i = S_i / N_i + lambda sqrt(log(sum_j N_j)
//                       / N_i); arms never pulled go first, in index order. Defaults lambda 1,
//                       gamma_b 0.95.
// Ties always go to the lowest index.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"

namespace pbppo::trainer {

enum class ScheduleMode { kFixed, kPaper, kReference, kDucb };
enum class FeedbackSource { kEval, kRollout };

const char* ToString(ScheduleMode m) noexcept;
const char* ToString(FeedbackSource f) noexcept;

struct ScheduleConfig {
  ScheduleMode mode = ScheduleMode::kDucb;
  std::vector<double> arms;  // candidate clip bounds, each in [0, 1]
  bool advantage = true;     // wi-ad (paper/reference modes)
  double lambda = 1.0;       // exploration weight
  double gamma = 0.95;       // bandit discount gamma_b
  FeedbackSource feedback = FeedbackSource::kEval;
  int eval_episodes = 2;  // k
  std::string Describe() const;
};

// "0.05:0.4:6" (linspace, n >= 1) or "0.1,0.2,0.3"; every value in [0, 1].
Result<std::vector<double>> ParseArms(const std::string& text);

// Parses --schedule and applies the mode's defaults for lambda and gamma_b (the paper's for the
// paper and reference modes). `arms` is used by the bandit modes.
Result<ScheduleConfig> ParseSchedule(const std::string& schedule, const std::vector<double>& arms);

struct ArmState {
  double epsilon = 0;
  double value = 0;  // the exploitation term of the last score
  double bonus = 0;  // the exploration term of the last score
  double count = 0;  // pulls (discounted for pbppo)
};

class ClipSchedule {
 public:
  virtual ~ClipSchedule() = default;
  // Picks the arm for the next update (and refreshes arms()' value and bonus).
  virtual int Choose() = 0;
  // Feedback for the update made with `arm`: the return after it and the return before it.
  virtual void Update(int arm, double return_after, double return_before) = 0;
  virtual bool uses_feedback() const noexcept { return true; }
  const std::vector<ArmState>& arms() const noexcept { return arms_; }
  double epsilon(int arm) const { return arms_[static_cast<std::size_t>(arm)].epsilon; }

 protected:
  std::vector<ArmState> arms_;
};

std::unique_ptr<ClipSchedule> MakeClipSchedule(const ScheduleConfig& config);

}  // namespace pbppo::trainer
