// A robot's observation and action layout, as data (models/<robot>/io_layout.yaml): how each
// policy input is built from a named signal and how each policy output maps to a command.
// The trainer's environments and the controller read the same file; its hash goes into every
// blob, so a policy only runs on the layout it was trained for. Set-up time only.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/policy/policy_spec.hpp"

namespace pbppo::robot {

// observation = clamp((signal - offset) * scale, -clip, clip); with history h > 1 the element
// occupies h consecutive inputs: now, one tick ago, ..., h-1 ticks ago.
struct ObservationElement {
  std::string name;
  std::string signal;
  std::string unit;
  double scale = 1.0;
  double offset = 0.0;
  double clip = 1e6;
  std::uint32_t history = 1;
};

// command = clamp(action * scale + offset, low, high)
struct ActionElement {
  std::string name;
  std::string command;
  std::string unit;
  double scale = 1.0;
  double offset = 0.0;
  double low = -1.0;
  double high = 1.0;
};

struct IoLayout {
  std::string robot;
  std::vector<ObservationElement> observations;
  std::vector<ActionElement> actions;

  // Policy input count (history expanded) and output count.
  std::uint32_t observation_size() const noexcept;
  std::uint32_t action_size() const noexcept;
  // Input names with history expanded ("yaw", "yaw@-1", ...), and output names.
  std::vector<std::string> ObservationNames() const;
  std::vector<std::string> ActionNames() const;
  // FNV-1a 64 over a canonical text of every field (names, signals, units, numbers to 9
  // significant digits, history): independent of YAML formatting and comments.
  std::uint64_t Hash() const;
  std::string CanonicalText() const;
};

// Parses and validates a layout file. Errors name the file, the element and the field.
Result<IoLayout> LoadIoLayout(const std::string& path);
Result<IoLayout> ParseIoLayout(const std::string& yaml_text, const std::string& origin);

// Copies names, hash and the action map (scale, offset, low, high) into a policy spec.
void ApplyLayoutToSpec(const IoLayout& layout, policy::PolicySpec& spec);

// The policy units of the commands a blob gives (its action map applied): per action,
// (command - offset) / scale with the layout's own scale and offset: what an environment's Step()
// and the last_action observations take. (An imported blob's action map may fold the model's own
// output scale into the layout's, so its scale is not the one to divide by.)
void ToPolicyUnits(const IoLayout& layout, std::span<const float> commands, std::span<float> actions);

// Refuses a policy trained for another layout, naming the first difference.
Status CheckPolicyMatchesLayout(const policy::PolicySpec& policy, const IoLayout& layout);

}  // namespace pbppo::robot
