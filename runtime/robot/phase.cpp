#include "runtime/robot/phase.hpp"

namespace pbppo::robot {

const char* ToString(Phase phase) noexcept {
  switch (phase) {
    case Phase::kDisarmed: return "disarmed";
    case Phase::kArming: return "arming";
    case Phase::kStandUp: return "stand-up";
    case Phase::kHold: return "hold";
    case Phase::kRun: return "run";
    case Phase::kDamping: return "damping";
    case Phase::kMotorOff: return "motor-off";
    case Phase::kDone: return "done";
    case Phase::kFailed: return "failed";
    case Phase::kSitDown: return "sit-down";
    case Phase::kPassive: return "passive";
  }
  return "?";
}

int PhaseIndex(std::string_view name) noexcept {
  for (std::size_t k = 0; k < kPhaseCount; ++k)
    if (name == ToString(static_cast<Phase>(k))) return static_cast<int>(k);
  return -1;
}

}  // namespace pbppo::robot
