// The AUV's safety supervisor (v1): a pure function of (configuration, this tick's inputs, the
// previous state) -> (command, new state). It has the last word on the speed set-points the
// controller sends. No OS header, no allocation, noexcept.
//
// Every tick the policy's command is put into its limits (v in [v_min, v_max], omega in
// [-w_max, w_max]) and its rate limits (change per tick), and the inputs are checked:
//
//   cause                 condition                                   asks for
//   command limit         policy command outside its limits           (counted; clamped)
//   rate limit            change larger than the rate limit            (counted; limited)
//   non-finite action     a NaN or Inf in the policy's command         safe-stop
//   invalid sample        a non-finite or out-of-range sample field    degraded; safe-stop after
//                                                                      invalid_safe_stop consecutive
//   stale sample          sample age > stale_degraded_ticks            degraded
//                         sample age > stale_safe_stop_ticks           safe-stop
//   lost peer             no sample for > lost_peer_ticks, or the      e-stop
//                         transport reports the peer gone
//   deadline overrun      consecutive deadline misses >= k_degraded    degraded
//                         ... >= k_safe_stop                            safe-stop
//   e-stop request        operator / shutdown                           e-stop
//
// Modes latch upward: nominal -> degraded -> safe-stop -> e-stop; only ResetAuvSupervisor, while
// disarmed, brings the mode back down. What each mode sends:
//
//   nominal    the limited policy command
//   degraded   the same with v also at most degraded_v_max
//   safe-stop  v and omega ramp to zero (stop_dv / stop_dw per tick): stop, hold heading
//   e-stop     v = 0, omega = 0 at once
//
// Invariant (fuzzed): the command is finite, inside its limits, and within the rate limits of the
// previous command, except that safe-stop moves towards zero by at most the stop rates and
// e-stop sends zero.
#pragma once

#include <cstddef>
#include <cstdint>

#include "runtime/robot/auv_messages.hpp"

namespace pbppo::safety {

enum class AuvMode : std::uint8_t { kNominal = 0, kDegraded = 1, kSafeStop = 2, kEStop = 3 };

// Cause bits (AuvDecision::causes, AuvControllerStatus::cause).
enum AuvCause : std::uint32_t {
  kAuvCauseCommandLimit = 1u << 0,
  kAuvCauseRateLimit = 1u << 1,
  kAuvCauseNonFiniteAction = 1u << 2,
  kAuvCauseInvalidSample = 1u << 3,
  kAuvCauseStaleSample = 1u << 4,
  kAuvCauseLostPeer = 1u << 5,
  kAuvCauseDeadlineOverrun = 1u << 6,
  kAuvCauseEStopRequest = 1u << 7,
};
inline constexpr std::size_t kAuvCauseCount = 8;
// The largest magnitude a command limit or rate in AuvSupervisorConfig may have (m/s, rad/s).
inline constexpr double kAuvLimitBound = 1000.0;

const char* ToString(AuvMode mode) noexcept;
// The name of one cause bit ("stale sensor sample"); "none" for 0, "several" for more bits.
const char* AuvCauseName(std::uint32_t cause_bit) noexcept;

struct AuvSupervisorConfig {
  // Command limits.
  double v_min_mps = 0.0, v_max_mps = 1.5;
  double w_max_radps = 0.5;
  double degraded_v_max_mps = 0.75;
  // Rate limits: largest change per tick; safe-stop ramps to zero at the stop rates (>= these).
  double dv_max_mps = 0.1, dw_max_radps = 0.25;
  double stop_dv_mps = 0.3, stop_dw_radps = 0.5;
  // Sample age (ticks since the latest sample arrived new).
  std::uint32_t stale_degraded_ticks = 1;
  std::uint32_t stale_safe_stop_ticks = 3;
  std::uint32_t lost_peer_ticks = 20;
  std::uint32_t invalid_safe_stop = 3;  // consecutive invalid samples
  // Consecutive deadline misses.
  std::uint32_t overrun_degraded = 2;
  std::uint32_t overrun_safe_stop = 5;
  // Plausible sample ranges.
  std::uint32_t sonar_beams = 16;
  double sonar_max_m = 15.0;
  double speed_max_mps = 5.0;   // |surge|, |sway|, |heave|
  double rate_max_radps = 5.0;  // |roll|, |pitch|, |yaw| rates
  double position_max_m = 1e5;  // |x|, |y|
  double depth_min_m = -5.0, depth_max_m = 1000.0;
};

// Checks every limit (finite, ordered, zero inside [v_min, v_max], stop rates >= rate limits,
// thresholds increasing). Writes a message naming the field and the value into `why` on failure.
bool ValidateAuvSupervisorConfig(const AuvSupervisorConfig& c, char* why, std::size_t why_size) noexcept;

struct AuvSupervisorInput {
  double v_mps = 0, w_radps = 0;                   // the policy's command (command units)
  const robot::AuvSensorSample* sample = nullptr;  // latest sample (null: none yet)
  std::uint32_t sample_age_ticks = 0;              // ticks since it arrived new (0: this tick)
  bool peer_lost = false;                          // the transport says the vehicle is gone
  std::uint32_t consecutive_deadline_misses = 0;
  bool estop_request = false;
};

struct AuvSupervisorState {
  AuvMode mode = AuvMode::kNominal;
  double v_mps = 0, w_radps = 0;  // the command sent last tick
  std::uint32_t invalid_run = 0;  // consecutive invalid samples
  std::uint64_t ticks = 0;
  std::uint64_t cause_ticks[kAuvCauseCount] = {};  // ticks on which each cause was found
  std::uint64_t transitions = 0;
  std::uint32_t latched_cause = 0;  // cause bit of the latest mode rise
  double latched_value = 0, latched_limit = 0;
  const char* latched_field = "";  // static string
};

struct AuvDecision {
  double v_mps = 0, w_radps = 0;  // the command to send
  AuvSupervisorState state;       // the state from this tick on
  std::uint32_t causes = 0;       // every cause found this tick
  std::uint32_t worst = 0;        // the cause asking for the highest mode (0: none)
  AuvMode worst_mode = AuvMode::kNominal;
  double value = 0, limit = 0;  // the worst cause's value and the limit it crossed
  const char* field = "";       // which field (sample field, "v", "omega", ...)
  bool transition = false;      // mode rose this tick
};

// The pure function.
AuvDecision SuperviseAuv(const AuvSupervisorConfig& c, const AuvSupervisorInput& in,
                         const AuvSupervisorState& previous) noexcept;

// Checks one sample's fields: 0 if valid, else kAuvCauseInvalidSample with the field and value.
std::uint32_t CheckAuvSample(const AuvSupervisorConfig& c, const robot::AuvSensorSample& s, const char** field,
                             double* value) noexcept;

// Back to nominal with zero command; refused (false) while armed.
bool ResetAuvSupervisor(AuvSupervisorState& state, bool armed) noexcept;

// "safe-stop: stale sensor sample: age 4 ticks > 3" into buf (snprintf, no allocation).
std::size_t DescribeAuv(const AuvDecision& d, char* buf, std::size_t size) noexcept;

}  // namespace pbppo::safety
