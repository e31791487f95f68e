// Observation and action through an IO layout, the one code path of training and deployment.
//
//   ObservationBuilder  signals (a table of named doubles) -> policy inputs:
//                       clamp((signal - offset) * scale, -clip, clip), an element with history
//                       h occupying h consecutive inputs (now, one tick ago, ...)
//   ActionMapper        policy outputs -> commands: clamp(action * scale + offset, low, high)
//
// Made once at set-up (allocates, errors name the element); Build and Map are noexcept and
// allocate nothing.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/io_layout.hpp"

namespace pbppo::robot {

class ObservationBuilder {
 public:
  // Maps each observation element to its signal's index in `signal_names`. An unknown signal
  // is refused naming the element, its signal and the known names.
  static Result<ObservationBuilder> Create(const IoLayout& layout, const std::vector<std::string>& signal_names);

  // Writes observation_size() inputs. `signals` holds signal_count() values. With `first` every
  // history slot takes the current value (the start of an episode, or the first tick after arming).
  void Build(const double* signals, bool first, float* obs) noexcept;

  std::uint32_t observation_size() const noexcept { return static_cast<std::uint32_t>(history_.size()); }
  std::uint32_t signal_count() const noexcept { return signal_count_; }
  // The signal index each element reads.
  const std::vector<std::uint32_t>& signal_of_element() const noexcept { return signal_; }
  // The previous observation, which the history slots shift through (a log's snapshot saves and
  // restores it).
  std::span<float> history() noexcept { return history_; }
  std::span<const float> history() const noexcept { return history_; }

 private:
  struct Element {
    double scale, offset, clip;
    std::uint32_t signal, history, first_input;
  };
  std::vector<Element> elements_;
  std::vector<std::uint32_t> signal_;
  std::vector<float> history_;  // the previous observation (the history slots shift through it)
  std::uint32_t signal_count_ = 0;
};

class ActionMapper {
 public:
  static ActionMapper Create(const IoLayout& layout);

  // command[i] = clamp(action[i] * scale + offset, low, high); a non-finite action element is
  // taken as 0 (policy units) and its bit (1 << i, elements < 32) set in the returned mask.
  std::uint32_t Map(const float* action, double* command) const noexcept;

  std::uint32_t action_size() const noexcept { return static_cast<std::uint32_t>(map_.size()); }

 private:
  struct Element {
    double scale, offset, low, high;
  };
  std::vector<Element> map_;
};

}  // namespace pbppo::robot
