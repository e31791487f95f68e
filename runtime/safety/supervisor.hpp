// The safety supervisor: a small, pure, latching decision on every tick. It knows nothing about
// CAN, motors or the robot: a model gives channels (actuators) with command fields and feedback
// fields and their limits, and transports; the data gives this tick's commands, feedback, the
// age of each channel's feedback in ticks and each transport's health. The quadruped's joints
// (command q, dq, kp, kd, tau; feedback q, dq) and an AUV's thrusters (command thrust; feedback
// rpm) fit the same model. No OS header, no allocation after the model is built.
//
// Modes latch upward only: nominal -> degraded -> safe-stop (the caller damps) -> e-stop (the
// caller cuts the actuators). What moves the mode:
//
//   degraded   a command outside its limits (the caller sends LimitCommand's clamped value),
//              feedback older than stale_degraded_ticks, a transport reporting trouble
//   safe-stop  feedback older than stale_safe_stop_ticks, a non-finite command or feedback,
//              feedback outside its limits, a transport fault (bus-off, socket error)
//   e-stop     feedback older than stale_estop_ticks, an e-stop request
//
// Every decision says which channel, field or transport caused it.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"

namespace pbppo::safety {

enum class Mode : std::uint8_t { kNominal = 0, kDegraded = 1, kSafeStop = 2, kEStop = 3 };
inline constexpr std::size_t kModeCount = 4;

enum class Fault : std::uint8_t {
  kNone = 0,
  kCommandLimit,       // channel, field
  kStaleFeedback,      // channel
  kNonFiniteCommand,   // channel, field
  kNonFiniteFeedback,  // channel, field
  kFeedbackLimit,      // channel, field
  kTransportDegraded,  // transport
  kTransportFault,     // transport
  kEStopRequest,
};
inline constexpr std::size_t kFaultCount = 9;

const char* ToString(Mode mode) noexcept;
const char* ToString(Fault fault) noexcept;

struct SupervisorModel {
  std::uint32_t channels = 0;
  std::uint32_t command_fields = 0;
  std::uint32_t feedback_fields = 0;
  std::uint32_t transports = 0;
  std::vector<double> command_min, command_max;    // [channel * command_fields + field]
  std::vector<double> feedback_min, feedback_max;  // [channel * feedback_fields + field]
  std::vector<std::string> channel_names;          // for reports ("LF_KFE")
  std::vector<std::string> command_field_names;    // ("q_rad", ...)
  std::vector<std::string> feedback_field_names;
  std::vector<std::string> transport_names;  // ("vcan0")
  std::uint32_t stale_degraded_ticks = 2;    // feedback this old: degraded (one tick missed)
  std::uint32_t stale_safe_stop_ticks = 3;   // this old: safe-stop
  std::uint32_t stale_estop_ticks = 500;     // this old: e-stop (cannot even damp it)
};

// Checks sizes, names and that every min < max and the stale thresholds increase.
Status ValidateSupervisorModel(const SupervisorModel& model);

struct TransportHealth {
  bool degraded = false;  // error-passive, frames dropped this tick, ...
  bool fault = false;     // bus-off, socket error
};

struct SupervisorInput {
  std::span<const double> command;                    // channels * command_fields
  std::span<const double> feedback;                   // channels * feedback_fields
  std::span<const std::uint32_t> feedback_age_ticks;  // per channel: 0 = fresh this tick
  std::span<const TransportHealth> transports;        // per transport
  bool estop_request = false;
};

struct Decision {
  Mode mode = Mode::kNominal;        // the mode from this tick on
  Fault fault = Fault::kNone;        // the cause of the worst finding this tick (kNone: all clear)
  Mode fault_mode = Mode::kNominal;  // the mode that finding asks for
  std::int32_t channel = -1, field = -1, transport = -1;
  bool transition = false;  // mode rose this tick
};

// The pure function: this tick's worst finding and the latched mode. Inputs of the wrong size
// count as non-finite data of channel 0 (the caller's bug must not pass as nominal).
Decision Supervise(const SupervisorModel& model, const SupervisorInput& in, Mode previous) noexcept;

// Puts every command field into its limits; non-finite values become the value in [min, max]
// nearest zero. Returns how many fields were changed.
std::uint32_t LimitCommand(const SupervisorModel& model, std::span<double> command) noexcept;

// Counters kept across ticks.
struct SupervisorData {
  Mode mode = Mode::kNominal;
  std::uint64_t decisions = 0;
  std::uint64_t ticks_in_mode[kModeCount] = {};
  std::uint64_t findings[kFaultCount] = {};  // ticks whose worst finding was this fault
  std::uint64_t transitions = 0;
  Decision entered[kModeCount] = {};  // the decision that entered each mode
  std::uint64_t entered_tick[kModeCount] = {};
};

// Supervise + counters: the tick calls this.
Decision Step(const SupervisorModel& model, const SupervisorInput& in, std::uint64_t tick,
              SupervisorData& data) noexcept;

// "safe-stop at tick 1234: stale feedback, channel 'LF_KFE'" (set-up or report time; allocates).
std::string Describe(const SupervisorModel& model, const Decision& d);

}  // namespace pbppo::safety
