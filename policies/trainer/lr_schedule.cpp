#include "policies/trainer/lr_schedule.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace pbppo::trainer {

std::string LrSchedule::Describe() const {
  switch (kind) {
    case Kind::kConstant: return "constant";
    case Kind::kAnneal: return "anneal";
    case Kind::kAdaptive: {
      char buf[48];
      std::snprintf(buf, sizeof buf, "adaptive:%g", desired_kl);
      return buf;
    }
  }
  return "constant";
}

double LrSchedule::AtIteration(double lr, int it, int iterations) const {
  return kind == Kind::kAnneal ? lr * (1.0 - static_cast<double>(it) / iterations) : lr;
}

double LrSchedule::Adapt(double lr, double kl) const {
  if (kl > desired_kl * 2.0) return std::max(kMinAdaptive, lr / kFactor);
  if (kl < desired_kl / 2.0 && kl > 0.0) return std::min(kMaxAdaptive, lr * kFactor);
  return lr;
}

Result<LrSchedule> ParseLrSchedule(const std::string& text) {
  LrSchedule s;
  if (text == "constant") return s;
  if (text == "anneal") {
    s.kind = LrSchedule::Kind::kAnneal;
    return s;
  }
  if (text == "adaptive" || text.rfind("adaptive:", 0) == 0) {
    s.kind = LrSchedule::Kind::kAdaptive;
    if (text != "adaptive") {
      const std::string kl = text.substr(9);
      char* end = nullptr;
      s.desired_kl = std::strtod(kl.c_str(), &end);
      if (kl.empty() || *end != '\0' || !(s.desired_kl > 0 && s.desired_kl <= 1))
        return MakeError(ErrorCode::kInvalidValue,
                         "--lr-schedule: '" + text + "': desired KL '" + kl + "' is not a number in (0, 1]");
    }
    return s;
  }
  return MakeError(ErrorCode::kInvalidValue,
                   "--lr-schedule: '" + text + "' unknown (constant, anneal, adaptive or adaptive:KL)");
}

}  // namespace pbppo::trainer
