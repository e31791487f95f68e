#include "runtime/robot/signals.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pbppo::robot {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr const char* kLastAction = "last_action_";

}  // namespace

double WrapAngleRad(double a) noexcept {
  a = std::remainder(a, 2.0 * kPi);  // [-pi, pi]
  return a <= -kPi ? a + 2.0 * kPi : a;
}

std::vector<std::string> SignalNames(const RobotModel& m) {
  std::vector<std::string> names;
  for (const SignalSpec& s : m.signals) names.push_back(s.name);
  for (const FieldSpec& f : m.fields) names.push_back(f.name);
  if (m.io)
    for (const ActionElement& a : m.io->actions) names.push_back(kLastAction + a.name);
  return names;
}

Result<SignalProgram> SignalProgram::Create(const RobotModel& m, const std::vector<std::string>& names) {
  SignalProgram p;
  for (const std::string& name : names) {
    Step step;
    std::int32_t stream = -1;
    const auto declared =
        std::find_if(m.signals.begin(), m.signals.end(), [&](const auto& s) { return s.name == name; });
    const int field = m.FieldIndex(name);
    if (declared != m.signals.end()) {
      using SOp = SignalSpec::Op;
      const SignalSpec& s = *declared;
      step.a = s.fields[0];
      step.value = s.value;
      switch (s.op) {
        case SOp::kField: step.op = Op::kField; break;
        case SOp::kWrap: step.op = Op::kWrap; break;
        case SOp::kCos: step.op = Op::kCos; break;
        case SOp::kSin: step.op = Op::kSin; break;
        case SOp::kMinus: step.op = Op::kMinus; break;
        case SOp::kMin:
        case SOp::kGravityX:
        case SOp::kGravityY:
        case SOp::kGravityZ:
          step.op = s.op == SOp::kMin        ? Op::kMin
                    : s.op == SOp::kGravityX ? Op::kGravityX
                    : s.op == SOp::kGravityY ? Op::kGravityY
                                             : Op::kGravityZ;
          step.a = static_cast<std::uint32_t>(p.fields_.size());
          step.n = static_cast<std::uint32_t>(s.fields.size());
          p.fields_.insert(p.fields_.end(), s.fields.begin(), s.fields.end());
          break;
      }
      stream = static_cast<std::int32_t>(m.fields[s.fields[0]].stream);
    } else if (field >= 0) {
      step.op = Op::kField;
      step.a = static_cast<std::uint32_t>(field);
      stream = static_cast<std::int32_t>(m.fields[static_cast<std::size_t>(field)].stream);
    } else {
      int action = -1;
      if (m.io && name.rfind(kLastAction, 0) == 0) {
        const std::string a = name.substr(std::char_traits<char>::length(kLastAction));
        for (std::size_t i = 0; i < m.io->actions.size(); ++i)
          if (m.io->actions[i].name == a) action = static_cast<int>(i);
      }
      if (action < 0) {
        std::string known;
        for (const auto& n : SignalNames(m)) known += (known.empty() ? "" : ", ") + n;
        return MakeError(ErrorCode::kMismatch,
                         m.path + ": signal '" + name + "' is not provided (known: " + known + ")");
      }
      step.op = Op::kAction;
      step.a = static_cast<std::uint32_t>(action);
    }
    p.steps_.push_back(step);
    p.names_.push_back(name);
    p.stream_.push_back(stream);
  }
  return p;
}

Result<SignalProgram> SignalProgram::ForLayout(const RobotModel& m, const IoLayout& layout) {
  std::vector<std::string> names;
  for (std::size_t e = 0; e < layout.observations.size(); ++e) {
    const ObservationElement& o = layout.observations[e];
    if (std::find(names.begin(), names.end(), o.signal) != names.end()) continue;
    auto one = Create(m, {o.signal});
    if (!one) {
      std::string known;
      for (const auto& n : SignalNames(m)) known += (known.empty() ? "" : ", ") + n;
      return MakeError(ErrorCode::kMismatch, "io layout '" + layout.robot + "': observations[" + std::to_string(e) +
                                                 "] '" + o.name + "': signal '" + o.signal +
                                                 "' is not provided (known: " + known + ")");
    }
    names.push_back(o.signal);
  }
  return Create(m, names);
}

void SignalProgram::Compute(std::span<const double> f, std::span<const float> last_action, double* out) const noexcept {
  for (std::size_t i = 0; i < steps_.size(); ++i) {
    const Step& s = steps_[i];
    double v = 0;
    switch (s.op) {
      case Op::kField: v = f[s.a]; break;
      case Op::kWrap: v = WrapAngleRad(f[s.a]); break;
      case Op::kCos: v = std::cos(f[s.a]); break;
      case Op::kSin: v = std::sin(f[s.a]); break;
      case Op::kMinus: v = f[s.a] - s.value; break;
      case Op::kMin:
        v = std::numeric_limits<double>::infinity();
        for (std::uint32_t k = 0; k < s.n; ++k) v = std::min(v, f[fields_[s.a + k]]);
        break;
      case Op::kGravityX:
      case Op::kGravityY:
      case Op::kGravityZ: {
        // The world's unit gravity (0, 0, -1) in the frame of an orientation (w, x, y, z), body to
        // world: minus the third row of its rotation matrix.
        double w = f[fields_[s.a]], x = f[fields_[s.a + 1]], y = f[fields_[s.a + 2]], z = f[fields_[s.a + 3]];
        const double norm = std::sqrt(w * w + x * x + y * y + z * z);
        if (norm > 0) {
          w /= norm;
          x /= norm;
          y /= norm;
          z /= norm;
        }
        v = s.op == Op::kGravityX   ? 2.0 * (w * y - x * z)
            : s.op == Op::kGravityY ? -2.0 * (y * z + w * x)
                                    : 2.0 * (x * x + y * y) - 1.0;
        break;
      }
      case Op::kAction: v = s.a < last_action.size() ? static_cast<double>(last_action[s.a]) : 0.0; break;
    }
    out[i] = v;
  }
}

}  // namespace pbppo::robot
