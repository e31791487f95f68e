#include "policies/trainer/clip_schedule.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "runtime/core/enum_name.hpp"

namespace pbppo::trainer {
namespace {

constexpr double kCountEps = 1e-6;

std::string Num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

Result<double> ParseUnit(const std::string& field, const std::string& s) {
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end == s.c_str() || *end != '\0' || !std::isfinite(v)) {
    return MakeError(ErrorCode::kInvalidValue, field + ": '" + s + "' is not a number");
  }
  if (v < 0.0 || v > 1.0) {
    return MakeError(ErrorCode::kInvalidValue, field + ": clip bound " + s + " is outside [0, 1]");
  }
  return v;
}

int ArgMax(const std::vector<double>& score) {
  int best = 0;
  for (std::size_t i = 1; i < score.size(); ++i)
    if (score[i] > score[static_cast<std::size_t>(best)]) best = static_cast<int>(i);
  return best;
}

class Fixed final : public ClipSchedule {
 public:
  explicit Fixed(double eps) { arms_.push_back({eps, 0, 0, 0}); }
  int Choose() override {
    arms_[0].count += 1;
    return 0;
  }
  void Update(int, double, double) override {}
  bool uses_feedback() const noexcept override { return false; }
};

// The paper's rule and the released script's rule share the discounted-sum state.
class DiscountedSum final : public ClipSchedule {
 public:
  DiscountedSum(const ScheduleConfig& c, bool reference)
      : reference_(reference), advantage_(c.advantage), lambda_(c.lambda), gamma_(c.gamma) {
    for (double e : c.arms) arms_.push_back({e, 0, 0, 0});
    e_.assign(arms_.size(), 0.0);
  }

  int Choose() override {
    const std::size_t n = arms_.size();
    std::vector<double> u = e_;
    // The script divides first; wi-ad then shifts what it divided (the paper: the sums themselves).
    if (reference_) {
      const double denom = *std::max_element(u.begin(), u.end()) + 0.001;
      bool finite = denom != 0.0;
      for (std::size_t i = 0; i < n && finite; ++i) finite = std::isfinite(u[i] / denom);
      for (std::size_t i = 0; i < n; ++i) u[i] = finite ? u[i] / denom : 0.0;
    }
    if (advantage_) {
      double mean = 0;
      for (double v : u) mean += v;
      mean /= static_cast<double>(n);
      for (double& v : u) v -= mean;
    }
    std::vector<double> score(n);
    for (std::size_t i = 0; i < n; ++i) {
      arms_[i].value = u[i];
      arms_[i].bonus = lambda_ * std::sqrt(total_ / (arms_[i].count + kCountEps));
      score[i] = arms_[i].value + arms_[i].bonus;
    }
    return ArgMax(score);
  }

  void Update(int arm, double return_after, double) override {
    const auto a = static_cast<std::size_t>(arm);
    e_[a] = gamma_ * e_[a] + return_after;
    arms_[a].count += 1;
    total_ += 1;
  }

 private:
  bool reference_, advantage_;
  double lambda_, gamma_;
  std::vector<double> e_;
  double total_ = 0;
};

class DiscountedUcb final : public ClipSchedule {
 public:
  explicit DiscountedUcb(const ScheduleConfig& c) : lambda_(c.lambda), gamma_(c.gamma) {
    for (double e : c.arms) arms_.push_back({e, 0, 0, 0});
    sum_.assign(arms_.size(), 0.0);
    pulled_.assign(arms_.size(), false);
  }

  int Choose() override {
    const std::size_t n = arms_.size();
    double total = 0;
    for (const auto& a : arms_) total += a.count;
    int first_unpulled = -1;
    std::vector<double> score(n);
    for (std::size_t i = 0; i < n; ++i) {
      if (!pulled_[i]) {
        arms_[i].value = 0;
        arms_[i].bonus = std::numeric_limits<double>::infinity();
        if (first_unpulled < 0) first_unpulled = static_cast<int>(i);
        continue;
      }
      arms_[i].value = sum_[i] / arms_[i].count;
      arms_[i].bonus = lambda_ * std::sqrt(std::max(std::log(total), 0.0) / arms_[i].count);
      score[i] = arms_[i].value + arms_[i].bonus;
    }
    return first_unpulled >= 0 ? first_unpulled : ArgMax(score);
  }

  void Update(int arm, double return_after, double return_before) override {
    const double delta = return_after - return_before;
    if (!std::isfinite(delta)) return;
    scale_ = seen_ ? gamma_ * scale_ + (1 - gamma_) * std::fabs(delta) : std::fabs(delta);
    seen_ = true;
    const double x = scale_ > 0 ? std::clamp(delta / scale_, -1.0, 1.0) : 0.0;
    for (std::size_t i = 0; i < arms_.size(); ++i) {
      arms_[i].count *= gamma_;
      sum_[i] *= gamma_;
    }
    const auto a = static_cast<std::size_t>(arm);
    arms_[a].count += 1;
    sum_[a] += x;
    pulled_[a] = true;
  }

  double scale() const noexcept { return scale_; }

 private:
  double lambda_, gamma_;
  std::vector<double> sum_;
  std::vector<bool> pulled_;
  double scale_ = 0;
  bool seen_ = false;
};

}  // namespace

const char* ToString(ScheduleMode m) noexcept {
  return EnumName(m, {"fixed", "pbppo-paper", "pbppo-reference", "pbppo"});
}

const char* ToString(FeedbackSource f) noexcept {
  return f == FeedbackSource::kEval ? "eval" : "rollout";
}

std::string ScheduleConfig::Describe() const {
  std::ostringstream s;
  if (mode == ScheduleMode::kFixed) {
    s << "fixed:" << Num(arms.empty() ? 0.0 : arms[0]);
    return s.str();
  }
  s << ToString(mode);
  if (mode != ScheduleMode::kDucb) s << (advantage ? ":wi-ad" : ":wo-ad");
  s << " arms=" << Num(arms.front()) << ".." << Num(arms.back()) << "/" << arms.size() << " lambda=" << Num(lambda)
    << " gamma_b=" << Num(gamma) << " feedback=" << ToString(feedback);
  if (feedback == FeedbackSource::kEval) s << " k=" << eval_episodes;
  return s.str();
}

Result<std::vector<double>> ParseArms(const std::string& text) {
  std::vector<double> out;
  if (text.find(':') != std::string::npos) {
    const auto a = text.find(':'), b = text.find(':', a + 1);
    if (b == std::string::npos || text.find(':', b + 1) != std::string::npos) {
      return MakeError(ErrorCode::kInvalidValue, "--arms: '" + text + "' is not MIN:MAX:N");
    }
    auto lo = ParseUnit("--arms", text.substr(0, a));
    if (!lo) return std::move(lo).error();
    auto hi = ParseUnit("--arms", text.substr(a + 1, b - a - 1));
    if (!hi) return std::move(hi).error();
    const std::string ns = text.substr(b + 1);
    char* end = nullptr;
    const long n = std::strtol(ns.c_str(), &end, 10);
    if (ns.empty() || *end != '\0' || n < 1 || n > 1000) {
      return MakeError(ErrorCode::kInvalidValue, "--arms: count '" + ns + "' is not an integer in [1, 1000]");
    }
    if (*hi < *lo) {
      return MakeError(ErrorCode::kInvalidValue, "--arms: max " + Num(*hi) + " is below min " + Num(*lo));
    }
    for (long i = 0; i < n; ++i) {
      out.push_back(n == 1 ? *lo : *lo + (*hi - *lo) * static_cast<double>(i) / static_cast<double>(n - 1));
    }
    return out;
  }
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    auto v = ParseUnit("--arms", item);
    if (!v) return std::move(v).error();
    out.push_back(*v);
  }
  if (out.empty()) return MakeError(ErrorCode::kInvalidValue, "--arms: '" + text + "' lists no clip bound");
  return out;
}

Result<ScheduleConfig> ParseSchedule(const std::string& schedule, const std::vector<double>& arms) {
  ScheduleConfig c;
  const auto colon = schedule.find(':');
  const std::string head = schedule.substr(0, colon);
  const std::string tail = colon == std::string::npos ? std::string() : schedule.substr(colon + 1);
  if (head == "fixed") {
    auto e = ParseUnit("--schedule fixed", tail);
    if (!e) return std::move(e).error();
    c.mode = ScheduleMode::kFixed;
    c.arms = {*e};
    return c;
  }
  if (head == "pbppo-paper" || head == "pbppo-reference") {
    c.mode = head == "pbppo-paper" ? ScheduleMode::kPaper : ScheduleMode::kReference;
    // Without a variant: the paper's wi-ad, and the released script's default, wo-ad.
    if (colon == std::string::npos) {
      c.advantage = c.mode == ScheduleMode::kPaper;
    } else if (tail == "wi-ad") {
      c.advantage = true;
    } else if (tail == "wo-ad") {
      c.advantage = false;
    } else {
      return MakeError(ErrorCode::kInvalidValue,
                       "--schedule: '" + schedule + "': variant '" + tail + "' unknown (wi-ad or wo-ad)");
    }
    c.lambda = 5.0;
    c.gamma = 0.99;
  } else if (head == "pbppo" && colon == std::string::npos) {
    c.mode = ScheduleMode::kDucb;
    c.lambda = 1.0;
    c.gamma = 0.95;
  } else {
    return MakeError(ErrorCode::kInvalidValue, "--schedule: '" + schedule +
                                                   "' unknown (fixed:EPS, pbppo-paper[:wi-ad|:wo-ad], "
                                                   "pbppo-reference[:wi-ad|:wo-ad], pbppo)");
  }
  if (arms.empty()) return MakeError(ErrorCode::kInvalidValue, "--arms: a bandit schedule needs at least one arm");
  for (double a : arms) {
    if (!(a >= 0.0 && a <= 1.0)) {
      return MakeError(ErrorCode::kInvalidValue, "--arms: clip bound " + Num(a) + " is outside [0, 1]");
    }
  }
  c.arms = arms;
  return c;
}

std::unique_ptr<ClipSchedule> MakeClipSchedule(const ScheduleConfig& c) {
  switch (c.mode) {
    case ScheduleMode::kFixed: return std::make_unique<Fixed>(c.arms.at(0));
    case ScheduleMode::kPaper: return std::make_unique<DiscountedSum>(c, false);
    case ScheduleMode::kReference: return std::make_unique<DiscountedSum>(c, true);
    case ScheduleMode::kDucb: return std::make_unique<DiscountedUcb>(c);
  }
  return nullptr;
}

}  // namespace pbppo::trainer
