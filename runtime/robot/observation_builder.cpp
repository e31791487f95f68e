#include "runtime/robot/observation_builder.hpp"

#include <algorithm>
#include <cmath>

namespace pbppo::robot {

Result<ObservationBuilder> ObservationBuilder::Create(const IoLayout& layout,
                                                      const std::vector<std::string>& signal_names) {
  ObservationBuilder b;
  b.signal_count_ = static_cast<std::uint32_t>(signal_names.size());
  std::uint32_t input = 0;
  for (std::size_t e = 0; e < layout.observations.size(); ++e) {
    const ObservationElement& o = layout.observations[e];
    const auto it = std::find(signal_names.begin(), signal_names.end(), o.signal);
    if (it == signal_names.end()) {
      std::string known;
      for (const auto& n : signal_names) known += (known.empty() ? "" : ", ") + n;
      return MakeError(ErrorCode::kMismatch, "io layout '" + layout.robot + "': observations[" + std::to_string(e) +
                                                 "] '" + o.name + "': signal '" + o.signal +
                                                 "' is not provided (known: " + known + ")");
    }
    if (o.history < 1) {
      return MakeError(ErrorCode::kInvalidValue, "io layout '" + layout.robot + "': observations[" + std::to_string(e) +
                                                     "] '" + o.name + "': history 0 (must be >= 1)");
    }
    const auto signal = static_cast<std::uint32_t>(it - signal_names.begin());
    b.elements_.push_back(Element{o.scale, o.offset, o.clip, signal, o.history, input});
    b.signal_.push_back(signal);
    input += o.history;
  }
  b.history_.assign(input, 0.0f);
  return b;
}

void ObservationBuilder::Build(const double* signals, bool first, float* obs) noexcept {
  float* last = history_.data();
  for (const Element& e : elements_) {
    const double v = (signals[e.signal] - e.offset) * e.scale;
    const auto now = static_cast<float>(std::clamp(v, -e.clip, e.clip));
    float* slot = last + e.first_input;
    for (std::uint32_t j = e.history - 1; j >= 1; --j) slot[j] = first ? now : slot[j - 1];
    slot[0] = now;
  }
  std::copy(history_.begin(), history_.end(), obs);
}

ActionMapper ActionMapper::Create(const IoLayout& layout) {
  ActionMapper m;
  for (const ActionElement& a : layout.actions) m.map_.push_back(Element{a.scale, a.offset, a.low, a.high});
  return m;
}

std::uint32_t ActionMapper::Map(const float* action, double* command) const noexcept {
  std::uint32_t nonfinite = 0;
  for (std::size_t i = 0; i < map_.size(); ++i) {
    const Element& a = map_[i];
    double x = static_cast<double>(action[i]);
    if (!std::isfinite(x)) {
      x = 0.0;
      if (i < 32) nonfinite |= 1u << i;
    }
    command[i] = std::clamp(x * a.scale + a.offset, a.low, a.high);
  }
  return nonfinite;
}

}  // namespace pbppo::robot
