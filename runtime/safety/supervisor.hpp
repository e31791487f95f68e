// The safety supervisor: one small, latching decision per tick for every robot, with the last
// word on what is sent. It knows nothing about CAN, DDS, motors or vehicles: a model gives the
// commands (limits, rate limits, what safe-stop sends), the input streams (how stale is too
// stale), the supervised signals and the transports; each tick it gets the command source's
// command, the sample check's findings, the streams' ages, the transports' health, the deadline
// misses, the inference status and an e-stop request. Pure: no OS header, no allocation after the
// state is made, noexcept; fuzzed for "the command is always finite and within its limits".
//
//   cause               condition                                          asks for
//   command limit       a command outside its limits (clamped)             nominal (counted) or degraded
//   rate limit          a change beyond a command's rate limit (limited)   nominal (counted)
//   non-finite command  a NaN or Inf in the source's command               safe-stop (the previous command held)
//   inference failed    the policy's Forward did not return ok             safe-stop (the previous command held)
//   invalid sample      a field outside its bounds (the one sample check)  degraded; safe-stop after
//                                                                          invalid_safe_stop in a row
//   stale sample        a stream older than stale_degraded / safe_stop    degraded / safe-stop
//   lost peer           a stream older than lost, or a transport that      e-stop
//                       reports its peer gone
//   transport degraded  frames dropped, error-passive, ...                 degraded
//   transport fault     bus-off, socket error                              safe-stop
//   deadline overrun    consecutive misses >= overrun_degraded / _safe_stop degraded / safe-stop
//   signal limit        a supervised signal (body tilt) out of range       safe-stop
//   e-stop request      operator, shutdown                                 e-stop
//
// Modes latch upward (nominal -> degraded -> safe-stop -> e-stop); only Reset, while disarmed,
// brings the mode back down. What each mode sends, per command:
//   nominal    the source's command, clamped, rate limited from the previous one
//   degraded   the same inside the degraded limits (half speed, ...)
//   safe-stop  ramp to zero at the stop rate, a fixed value (zero stiffness, damping), or the
//              measured value of an input (a joint's position)
//   e-stop     zero (inside the limits); the caller also switches actuators off
// Counters are indexed by cause (by name, CauseCounts), and every decision names its subject.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"

namespace pbppo::safety {

enum class Mode : std::uint8_t { kNominal = 0, kDegraded = 1, kSafeStop = 2, kEStop = 3 };
inline constexpr std::size_t kModeCount = 4;

enum class Cause : std::uint8_t {
  kCommandLimit,
  kRateLimit,
  kNonFiniteCommand,
  kInferenceFailed,
  kInvalidSample,
  kStaleSample,
  kLostPeer,
  kTransportDegraded,
  kTransportFault,
  kDeadlineOverrun,
  kSignalLimit,
  kEStopRequest,
};
inline constexpr std::size_t kCauseCount = 12;

const char* ToString(Mode mode) noexcept;
const char* ToString(Cause cause) noexcept;

// One counter per cause, indexed by the cause.
struct CauseCounts {
  std::array<std::uint64_t, kCauseCount> n{};
  std::uint64_t& operator[](Cause c) noexcept { return n[static_cast<std::size_t>(c)]; }
  std::uint64_t operator[](Cause c) const noexcept { return n[static_cast<std::size_t>(c)]; }
};

// What safe-stop sends for a command.
enum class StopKind : std::uint8_t { kRamp, kValue, kHoldInput };

struct CommandLimit {
  std::string name;
  double min = 0, max = 0;
  double degraded_min = 0, degraded_max = 0;
  double rate = HUGE_VAL;  // largest change per tick (inf: none)
  StopKind stop = StopKind::kValue;
  double stop_rate = 0;          // kRamp: per tick, towards zero
  double stop_value = 0;         // kValue
  std::int32_t hold_input = -1;  // kHoldInput: the input held (clamped into [min, max])
};

struct StreamLimit {
  std::string name;
  std::uint32_t stale_degraded_ticks = 1, stale_safe_stop_ticks = 2, lost_ticks = 20;  // "older than"
  std::uint32_t invalid_safe_stop = 1;
  bool required = true;  // false: no fault before the first sample
  // false: a command source whose silence is no fault (its values read 0 after a while: the
  // loop's business); the stale and lost limits are not used.
  bool silence_faults = true;
};

struct SignalLimit {
  std::string name;
  std::uint32_t signal = 0;  // index into SupervisorInput::signals
  std::uint32_t stream = 0;  // checked once this stream has been seen
  double min = 0, max = 0;
};

struct SupervisorModel {
  std::vector<CommandLimit> commands;
  std::vector<StreamLimit> streams;
  std::vector<std::string> input_names;  // the fields of the sample check (for reasons)
  std::vector<std::string> transport_names;
  std::vector<SignalLimit> signal_limits;
  bool command_limit_degrades = false;
  std::uint32_t overrun_degraded = 2, overrun_safe_stop = 5;
  // E-stop's commands: false, every command 0 (the loop switches the motors off); true, safe-stop's
  // (each command's stop: for a legged robot the damping values), the motors left on.
  bool estop_damps = false;
};

// Checks every limit: finite, ordered, magnitudes <= 1000 where the command is rate limited or
// ramps (beyond, a unit error; and the ramp arithmetic stays exact), zero inside a ramping
// command's limits, stop rates >= rate limits, increasing stale limits. Names the field and value.
Status ValidateSupervisorModel(const SupervisorModel& model);

// One stream this tick: whether it was ever seen, its age in ticks (0: a new sample this tick) and
// the sample check's first finding on its current values (-1: valid).
struct StreamState {
  bool seen = false;
  std::uint32_t age_ticks = 0;
  std::int32_t invalid_input = -1;
  double invalid_value = 0;
};

struct TransportHealth {
  bool degraded = false;  // frames dropped, error-passive, a full queue
  bool fault = false;     // bus-off, socket error
  bool lost = false;      // the transport reports its peer gone
};

struct SupervisorInput {
  std::span<const double> command;  // the command source's, one per model command
  std::span<const double> inputs;   // the robot's inputs (kHoldInput)
  std::span<const StreamState> streams;
  std::span<const double> signals;  // supervised signals (SignalLimit::signal)
  std::span<const TransportHealth> transports;
  std::uint32_t consecutive_deadline_misses = 0;
  bool inference_failed = false;
  const char* inference_status = "";  // its name, for the reason
  bool estop_request = false;
};

struct Decision {
  Mode mode = Mode::kNominal;          // the mode from this tick on
  bool any = false;                    // a finding this tick
  Cause cause = Cause::kEStopRequest;  // the finding asking for the highest mode (when any)
  Mode cause_mode = Mode::kNominal;    // the mode it asks for
  std::int32_t subject = -1;           // its command, stream, transport or signal limit
  std::int32_t input = -1;             // kInvalidSample: the input
  double value = 0, limit = 0;
  const char* detail = "";   // kInferenceFailed: the inference status (a static string)
  std::uint32_t causes = 0;  // bit (1 << cause) of every cause found this tick
  bool transition = false;   // the mode rose this tick
};

struct SupervisorState {
  Mode mode = Mode::kNominal;
  std::vector<double> previous;            // the command sent last tick
  std::vector<std::uint32_t> invalid_run;  // per stream: consecutive invalid checks
  std::uint64_t ticks = 0, transitions = 0;
  CauseCounts counts;  // ticks on which each cause was found
  std::array<std::uint64_t, kModeCount> ticks_in_mode{};
  std::array<Decision, kModeCount> entered{};  // the decision that entered each mode
  std::array<std::uint64_t, kModeCount> entered_tick{};
  Decision last;
};

// The state for a model (the only allocation): nominal, the previous command zero (inside the limits).
SupervisorState MakeSupervisorState(const SupervisorModel& model);

// The decision of one tick: writes the command to send into `out` (one per model command) and
// updates the state. Inputs of the wrong size count as a non-finite command (a caller's bug never
// passes as nominal).
Decision Supervise(const SupervisorModel& model, const SupervisorInput& in, std::uint64_t tick, SupervisorState& state,
                   std::span<double> out) noexcept;

// Back to nominal with the previous command zero; refused (false) while armed.
bool Reset(SupervisorState& state, bool armed) noexcept;

// "safe-stop: stale sample: LF_KFE: age 3 ticks > 2" into buf (snprintf, no allocation).
std::size_t Describe(const SupervisorModel& model, const Decision& d, char* buf, std::size_t size) noexcept;
std::string Describe(const SupervisorModel& model, const Decision& d);

}  // namespace pbppo::safety
