// The controller's phases (runtime/loop/loop.hpp says what happens in each), here so that a robot
// file can name them: operator.from narrows the phases an operator's request is taken in.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string_view>

namespace pbppo::robot {

enum class Phase : std::uint8_t {
  kDisarmed,
  kArming,
  kStandUp,
  kHold,
  kRun,
  kDamping,
  kMotorOff,
  kDone,
  kFailed,
  kSitDown,
  kPassive
};
inline constexpr std::size_t kPhaseCount = 11;
// "disarmed", "stand-up", "sit-down" ...
const char* ToString(Phase phase) noexcept;
// The phase of that name; -1 when none.
int PhaseIndex(std::string_view name) noexcept;

// A set of phases: bit (1 << phase).
using PhaseSet = std::uint16_t;
inline constexpr PhaseSet Phases(std::initializer_list<Phase> phases) noexcept {
  PhaseSet s = 0;
  for (const Phase p : phases) s = static_cast<PhaseSet>(s | (1u << static_cast<unsigned>(p)));
  return s;
}
inline constexpr PhaseSet kAllPhases = (1u << kPhaseCount) - 1;
inline constexpr bool InPhases(PhaseSet set, Phase phase) noexcept {
  return ((static_cast<unsigned>(set) >> static_cast<unsigned>(phase)) & 1u) != 0;
}

// The phases the controller takes each narrowable request in (loop.hpp: Operator requests).
inline constexpr PhaseSet kArmPhases = Phases({Phase::kDisarmed, Phase::kPassive});
inline constexpr PhaseSet kSitPhases = Phases({Phase::kStandUp, Phase::kHold, Phase::kRun});
inline constexpr PhaseSet kSwitchPhases = Phases({Phase::kHold, Phase::kRun});

}  // namespace pbppo::robot
