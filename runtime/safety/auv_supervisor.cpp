#include "runtime/safety/auv_supervisor.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <iterator>

namespace pbppo::safety {
namespace {

std::size_t CauseIndex(std::uint32_t bit) noexcept {
  return static_cast<std::size_t>(std::countr_zero(bit));
}

// A finding: the cause, the mode it asks for, the field, the value and the limit it crossed.
struct Finding {
  std::uint32_t cause = 0;
  AuvMode mode = AuvMode::kNominal;
  const char* field = "";
  double value = 0, limit = 0;
};

struct Findings {
  std::uint32_t causes = 0;
  Finding worst;
  void Add(std::uint32_t cause, AuvMode mode, const char* field, double value, double limit) noexcept {
    causes |= cause;
    if (worst.cause == 0 || mode > worst.mode) worst = Finding{cause, mode, field, value, limit};
  }
};

// value outside [lo, hi] (or non-finite): records it and returns true.
bool OutOfRange(double v, double lo, double hi, const char* name, const char** field, double* value,
                double* limit) noexcept {
  if (std::isfinite(v) && v >= lo && v <= hi) return false;
  *field = name;
  *value = v;
  if (limit != nullptr) *limit = std::isfinite(v) && v < lo ? lo : hi;
  return true;
}

double Sane(double v, double lo, double hi) noexcept {
  return std::isfinite(v) ? std::clamp(v, lo, hi) : 0.0;
}

// One rate-limited step from `from` towards `to`. The result always lies between the two (so
// inside any limits both respect) and is `to` itself once within reach: `from + (to - from)`
// can round past `to` (from -7.97 towards 0.1 it gives 0.10000000000000053).
double Toward(double from, double to, double step) noexcept {
  if (to > from) return std::min(to, from + step);
  if (to < from) return std::max(to, from - step);
  return to;
}

bool Finite(double v) noexcept {
  return std::isfinite(v);
}

}  // namespace

const char* ToString(AuvMode mode) noexcept {
  switch (mode) {
    case AuvMode::kNominal: return "nominal";
    case AuvMode::kDegraded: return "degraded";
    case AuvMode::kSafeStop: return "safe-stop";
    case AuvMode::kEStop: return "e-stop";
  }
  return "unknown";
}

const char* AuvCauseName(std::uint32_t cause) noexcept {
  switch (cause) {
    case 0: return "none";
    case kAuvCauseCommandLimit: return "command limit";
    case kAuvCauseRateLimit: return "rate limit";
    case kAuvCauseNonFiniteAction: return "non-finite action";
    case kAuvCauseInvalidSample: return "invalid sensor sample";
    case kAuvCauseStaleSample: return "stale sensor sample";
    case kAuvCauseLostPeer: return "lost peer";
    case kAuvCauseDeadlineOverrun: return "deadline overrun";
    case kAuvCauseEStopRequest: return "e-stop request";
    default: return "several";
  }
}

bool ValidateAuvSupervisorConfig(const AuvSupervisorConfig& c, char* why, std::size_t size) noexcept {
  auto fail = [&](const char* field, double v, const char* rule) {
    if (size > 0) std::snprintf(why, size, "supervisor: %s = %g: %s", field, v, rule);
    return false;
  };
  // Every number must be finite. The first eight (command limits and rates) are physical
  // quantities of an AUV: a magnitude beyond kAuvLimitBound is a unit or typing error, and such
  // magnitudes would also make the rate limits inexact in doubles.
  const struct {
    const char* name;
    double v;
  } numbers[] = {{"v_min_mps", c.v_min_mps},           {"v_max_mps", c.v_max_mps},
                 {"w_max_radps", c.w_max_radps},       {"degraded_v_max_mps", c.degraded_v_max_mps},
                 {"dv_max_mps", c.dv_max_mps},         {"dw_max_radps", c.dw_max_radps},
                 {"stop_dv_mps", c.stop_dv_mps},       {"stop_dw_radps", c.stop_dw_radps},
                 {"sonar_max_m", c.sonar_max_m},       {"speed_max_mps", c.speed_max_mps},
                 {"rate_max_radps", c.rate_max_radps}, {"position_max_m", c.position_max_m},
                 {"depth_min_m", c.depth_min_m},       {"depth_max_m", c.depth_max_m}};
  constexpr std::size_t kBounded = 8;
  for (std::size_t i = 0; i < std::size(numbers); ++i) {
    const auto& f = numbers[i];
    if (!Finite(f.v)) return fail(f.name, f.v, "not finite");
    if (i < kBounded && std::abs(f.v) > kAuvLimitBound) return fail(f.name, f.v, "magnitude must be <= 1000");
  }
  if (c.v_min_mps > 0.0) return fail("v_min_mps", c.v_min_mps, "must be <= 0 (stopping must be allowed)");
  if (c.v_max_mps < 0.0 || c.v_max_mps <= c.v_min_mps)
    return fail("v_max_mps", c.v_max_mps, "must be >= 0 and > v_min");
  if (c.w_max_radps < 0.0) return fail("w_max_radps", c.w_max_radps, "must be >= 0");
  if (c.degraded_v_max_mps < 0.0 || c.degraded_v_max_mps > c.v_max_mps)
    return fail("degraded_v_max_mps", c.degraded_v_max_mps, "must be in [0, v_max]");
  if (c.dv_max_mps <= 0.0) return fail("dv_max_mps", c.dv_max_mps, "must be > 0");
  if (c.dw_max_radps <= 0.0) return fail("dw_max_radps", c.dw_max_radps, "must be > 0");
  if (c.stop_dv_mps < c.dv_max_mps) return fail("stop_dv_mps", c.stop_dv_mps, "must be >= dv_max_mps");
  if (c.stop_dw_radps < c.dw_max_radps) return fail("stop_dw_radps", c.stop_dw_radps, "must be >= dw_max_radps");
  if (c.stale_safe_stop_ticks <= c.stale_degraded_ticks)
    return fail("stale_safe_stop_ticks", c.stale_safe_stop_ticks, "must be > stale_degraded_ticks");
  if (c.lost_peer_ticks <= c.stale_safe_stop_ticks)
    return fail("lost_peer_ticks", c.lost_peer_ticks, "must be > stale_safe_stop_ticks");
  if (c.invalid_safe_stop < 1) return fail("invalid_safe_stop", c.invalid_safe_stop, "must be >= 1");
  if (c.overrun_degraded < 1) return fail("overrun_degraded", c.overrun_degraded, "must be >= 1");
  if (c.overrun_safe_stop <= c.overrun_degraded)
    return fail("overrun_safe_stop", c.overrun_safe_stop, "must be > overrun_degraded");
  if (c.sonar_beams < 1 || c.sonar_beams > robot::kAuvMaxSonarBeams)
    return fail("sonar_beams", c.sonar_beams, "must be in [1, 32]");
  if (c.sonar_max_m <= 0.0) return fail("sonar_max_m", c.sonar_max_m, "must be > 0");
  if (c.depth_max_m <= c.depth_min_m) return fail("depth_max_m", c.depth_max_m, "must be > depth_min_m");
  return true;
}

std::uint32_t CheckAuvSample(const AuvSupervisorConfig& c, const robot::AuvSensorSample& s, const char** field,
                             double* value) noexcept {
  double limit = 0;
  const double sp = c.speed_max_mps, rt = c.rate_max_radps, pos = c.position_max_m;
  if (s.sonar_beams != c.sonar_beams) {
    *field = "sonar_beams";
    *value = s.sonar_beams;
    return kAuvCauseInvalidSample;
  }
  const struct {
    const char* name;
    double v, lo, hi;
  } fields[] = {{"x_m", s.x_m, -pos, pos},
                {"y_m", s.y_m, -pos, pos},
                {"depth_m", s.depth_m, c.depth_min_m, c.depth_max_m},
                {"roll_rad", s.roll_rad, -7.0, 7.0},
                {"pitch_rad", s.pitch_rad, -7.0, 7.0},
                {"yaw_rad", s.yaw_rad, -7.0, 7.0},
                {"surge_mps", s.surge_mps, -sp, sp},
                {"sway_mps", s.sway_mps, -sp, sp},
                {"heave_mps", s.heave_mps, -sp, sp},
                {"roll_rate_radps", s.roll_rate_radps, -rt, rt},
                {"pitch_rate_radps", s.pitch_rate_radps, -rt, rt},
                {"yaw_rate_radps", s.yaw_rate_radps, -rt, rt},
                {"target_x_m", s.target_x_m, -pos, pos},
                {"target_y_m", s.target_y_m, -pos, pos},
                {"target_distance_m", s.target_distance_m, 0.0, 4.0 * pos},
                {"target_bearing_rad", s.target_bearing_rad, -7.0, 7.0},
                {"route_bearing_rad", s.route_bearing_rad, -7.0, 7.0},
                {"clearance_m", s.clearance_m, -4.0 * pos, 4.0 * pos},
                {"target_index", static_cast<double>(s.target_index), 0.0, 1e6}};
  for (const auto& f : fields) {
    if (OutOfRange(f.v, f.lo, f.hi, f.name, field, value, &limit)) return kAuvCauseInvalidSample;
  }
  for (std::uint32_t i = 0; i < c.sonar_beams && i < robot::kAuvMaxSonarBeams; ++i) {
    if (OutOfRange(static_cast<double>(s.sonar_m[i]), 0.0, c.sonar_max_m, "sonar_m", field, value, &limit))
      return kAuvCauseInvalidSample;
  }
  return 0;
}

AuvDecision SuperviseAuv(const AuvSupervisorConfig& c, const AuvSupervisorInput& in,
                         const AuvSupervisorState& previous) noexcept {
  AuvDecision d;
  d.state = previous;
  AuvSupervisorState& st = d.state;
  if (static_cast<std::uint8_t>(st.mode) > static_cast<std::uint8_t>(AuvMode::kEStop)) st.mode = AuvMode::kEStop;
  // The previous command as sent (anything else cannot have been sent: treat it as zero or clamp).
  const double v_prev = Sane(previous.v_mps, c.v_min_mps, c.v_max_mps);
  const double w_prev = Sane(previous.w_radps, -c.w_max_radps, c.w_max_radps);
  Findings f;

  // The policy's command.
  double v = in.v_mps, w = in.w_radps;
  if (!Finite(v) || !Finite(w)) {
    const bool bad_v = !Finite(v);
    f.Add(kAuvCauseNonFiniteAction, AuvMode::kSafeStop, bad_v ? "v" : "omega", bad_v ? v : w, 0.0);
    v = v_prev;
    w = w_prev;
  }
  if (v < c.v_min_mps || v > c.v_max_mps) {
    f.Add(kAuvCauseCommandLimit, AuvMode::kNominal, "v", v, v < c.v_min_mps ? c.v_min_mps : c.v_max_mps);
    v = std::clamp(v, c.v_min_mps, c.v_max_mps);
  }
  if (w < -c.w_max_radps || w > c.w_max_radps) {
    f.Add(kAuvCauseCommandLimit, AuvMode::kNominal, "omega", w, w < 0 ? -c.w_max_radps : c.w_max_radps);
    w = std::clamp(w, -c.w_max_radps, c.w_max_radps);
  }

  // The sample.
  if (in.sample == nullptr) {
    if (in.sample_age_ticks > c.lost_peer_ticks)
      f.Add(kAuvCauseLostPeer, AuvMode::kEStop, "sample age", in.sample_age_ticks, c.lost_peer_ticks);
  } else {
    const char* field = "";
    double value = 0;
    if (CheckAuvSample(c, *in.sample, &field, &value) != 0) {
      st.invalid_run = st.invalid_run < 0xffffffffu ? st.invalid_run + 1 : st.invalid_run;
      f.Add(kAuvCauseInvalidSample, st.invalid_run >= c.invalid_safe_stop ? AuvMode::kSafeStop : AuvMode::kDegraded,
            field, value, st.invalid_run);
    } else if (in.sample_age_ticks == 0) {
      st.invalid_run = 0;
    }
    if (in.sample_age_ticks > c.lost_peer_ticks)
      f.Add(kAuvCauseLostPeer, AuvMode::kEStop, "sample age", in.sample_age_ticks, c.lost_peer_ticks);
    else if (in.sample_age_ticks > c.stale_safe_stop_ticks)
      f.Add(kAuvCauseStaleSample, AuvMode::kSafeStop, "sample age", in.sample_age_ticks, c.stale_safe_stop_ticks);
    else if (in.sample_age_ticks > c.stale_degraded_ticks)
      f.Add(kAuvCauseStaleSample, AuvMode::kDegraded, "sample age", in.sample_age_ticks, c.stale_degraded_ticks);
  }
  if (in.peer_lost) f.Add(kAuvCauseLostPeer, AuvMode::kEStop, "peer", 1.0, 0.0);
  if (in.consecutive_deadline_misses >= c.overrun_safe_stop)
    f.Add(kAuvCauseDeadlineOverrun, AuvMode::kSafeStop, "deadline misses", in.consecutive_deadline_misses,
          c.overrun_safe_stop);
  else if (in.consecutive_deadline_misses >= c.overrun_degraded)
    f.Add(kAuvCauseDeadlineOverrun, AuvMode::kDegraded, "deadline misses", in.consecutive_deadline_misses,
          c.overrun_degraded);
  if (in.estop_request) f.Add(kAuvCauseEStopRequest, AuvMode::kEStop, "request", 1.0, 0.0);

  // Latch upward.
  if (f.worst.mode > st.mode) {
    st.mode = f.worst.mode;
    ++st.transitions;
    st.latched_cause = f.worst.cause;
    st.latched_field = f.worst.field;
    st.latched_value = f.worst.value;
    st.latched_limit = f.worst.limit;
    d.transition = true;
  }

  // The command of the mode.
  switch (st.mode) {
    case AuvMode::kNominal:
    case AuvMode::kDegraded: {
      if (st.mode == AuvMode::kDegraded) v = std::min(v, c.degraded_v_max_mps);
      const double v_out = Toward(v_prev, v, c.dv_max_mps);
      const double w_out = Toward(w_prev, w, c.dw_max_radps);
      if (v_out != v || w_out != w) {
        const bool on_v = v_out != v;
        f.Add(kAuvCauseRateLimit, AuvMode::kNominal, on_v ? "v" : "omega", on_v ? v - v_prev : w - w_prev,
              on_v ? c.dv_max_mps : c.dw_max_radps);
      }
      d.v_mps = v_out;
      d.w_radps = w_out;
      break;
    }
    case AuvMode::kSafeStop:
      d.v_mps = Toward(v_prev, 0.0, c.stop_dv_mps);
      d.w_radps = Toward(w_prev, 0.0, c.stop_dw_radps);
      break;
    case AuvMode::kEStop:
      d.v_mps = 0.0;
      d.w_radps = 0.0;
      break;
  }
  st.v_mps = d.v_mps;
  st.w_radps = d.w_radps;
  ++st.ticks;
  for (std::uint32_t bits = f.causes; bits != 0; bits &= bits - 1) ++st.cause_ticks[CauseIndex(bits & (~bits + 1))];
  d.causes = f.causes;
  d.worst = f.worst.cause;
  d.worst_mode = f.worst.mode;
  d.field = f.worst.field;
  d.value = f.worst.value;
  d.limit = f.worst.limit;
  return d;
}

bool ResetAuvSupervisor(AuvSupervisorState& state, bool armed) noexcept {
  if (armed) return false;
  state.mode = AuvMode::kNominal;
  state.v_mps = state.w_radps = 0.0;
  state.invalid_run = 0;
  state.latched_cause = 0;
  state.latched_field = "";
  state.latched_value = state.latched_limit = 0.0;
  return true;
}

std::size_t DescribeAuv(const AuvDecision& d, char* buf, std::size_t size) noexcept {
  if (size == 0) return 0;
  const char* mode = ToString(d.state.mode);
  const char* cause = AuvCauseName(d.worst);
  int n = 0;
  switch (d.worst) {
    case 0: n = std::snprintf(buf, size, "%s: all clear", mode); break;
    case kAuvCauseStaleSample:
      n = std::snprintf(buf, size, "%s: %s: age %.0f ticks > %.0f", mode, cause, d.value, d.limit);
      break;
    case kAuvCauseLostPeer:
      if (d.value == 1.0 && d.limit == 0.0)
        n = std::snprintf(buf, size, "%s: %s: the transport reports the vehicle gone", mode, cause);
      else
        n = std::snprintf(buf, size, "%s: %s: no sample for %.0f ticks > %.0f", mode, cause, d.value, d.limit);
      break;
    case kAuvCauseDeadlineOverrun:
      n = std::snprintf(buf, size, "%s: %s: %.0f consecutive misses >= %.0f", mode, cause, d.value, d.limit);
      break;
    case kAuvCauseInvalidSample:
      n = std::snprintf(buf, size, "%s: %s: %s = %g (%.0f in a row)", mode, cause, d.field, d.value, d.limit);
      break;
    case kAuvCauseNonFiniteAction:
      n = std::snprintf(buf, size, "%s: %s: %s = %g", mode, cause, d.field, d.value);
      break;
    case kAuvCauseEStopRequest: n = std::snprintf(buf, size, "%s: %s", mode, cause); break;
    default: n = std::snprintf(buf, size, "%s: %s: %s = %g (limit %g)", mode, cause, d.field, d.value, d.limit); break;
  }
  return n < 0 ? 0 : std::min(static_cast<std::size_t>(n), size - 1);
}

}  // namespace pbppo::safety
