#include "runtime/safety/supervisor.hpp"

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <string>
#include <type_traits>

#include "runtime/core/enum_name.hpp"

namespace pbppo::safety {
namespace {

constexpr double kLimitBound = 1000.0;  // largest magnitude of a rate-limited or ramping command's limits

struct Findings {
  std::uint32_t causes = 0;
  Decision worst;
  // Keeps the first finding of the most severe mode.
  void Add(Cause c, Mode m, std::int32_t subject, std::int32_t input, double value, double limit) noexcept {
    causes |= 1u << static_cast<unsigned>(c);
    if (worst.any && m <= worst.cause_mode) return;
    worst.any = true;
    worst.cause = c;
    worst.cause_mode = m;
    worst.subject = subject;
    worst.input = input;
    worst.value = value;
    worst.limit = limit;
  }
};

std::int32_t I32(std::size_t v) noexcept {
  return static_cast<std::int32_t>(v);
}

// A value as it can have been sent: finite, inside [lo, hi] (anything else becomes zero, clamped).
double Sane(double v, double lo, double hi) noexcept {
  return std::clamp(std::isfinite(v) ? v : 0.0, lo, hi);
}

// One rate-limited step from `from` towards `to`. The result always lies between the two (so
// inside any limits both respect) and is `to` itself once within reach: `from + (to - from)` can
// round past `to` (from -7.97 towards 0.1 it gives 0.10000000000000053).
double Toward(double from, double to, double step) noexcept {
  if (to > from) return std::min(to, from + step);
  if (to < from) return std::max(to, from - step);
  return to;
}

Error Invalid(const std::string& what) {
  return MakeError(ErrorCode::kInvalidValue, "supervisor: " + what);
}

std::string Num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

void CheckStreams(const SupervisorModel& m, const SupervisorInput& in, SupervisorState& st, Findings& f) noexcept {
  for (std::size_t s = 0; s < m.streams.size() && s < in.streams.size(); ++s) {
    const StreamLimit& l = m.streams[s];
    const StreamState& x = in.streams[s];
    const double age = x.age_ticks;
    if (x.seen) {
      std::uint32_t& run = st.invalid_run[s];
      if (x.invalid_input >= 0) {
        run = run < 0xffffffffu ? run + 1 : run;
        f.Add(Cause::kInvalidSample, run >= l.invalid_safe_stop ? Mode::kSafeStop : Mode::kDegraded, I32(s),
              x.invalid_input, x.invalid_value, run);
      } else if (x.age_ticks == 0) {
        run = 0;
      }
    }
    if (!l.silence_faults || (!x.seen && !l.required)) continue;
    if (x.age_ticks > l.lost_ticks) {
      f.Add(Cause::kLostPeer, Mode::kEStop, I32(s), -1, age, l.lost_ticks);
    } else if (!x.seen) {
      continue;  // nothing yet: only a silence past the lost limit counts
    } else if (x.age_ticks > l.stale_safe_stop_ticks) {
      f.Add(Cause::kStaleSample, Mode::kSafeStop, I32(s), -1, age, l.stale_safe_stop_ticks);
    } else if (x.age_ticks > l.stale_degraded_ticks) {
      f.Add(Cause::kStaleSample, Mode::kDegraded, I32(s), -1, age, l.stale_degraded_ticks);
    }
  }
}

void CheckRest(const SupervisorModel& m, const SupervisorInput& in, Findings& f) noexcept {
  for (std::size_t t = 0; t < in.transports.size() && t < m.transport_names.size(); ++t) {
    if (in.transports[t].lost) f.Add(Cause::kLostPeer, Mode::kEStop, I32(t), -2, 1.0, 0.0);
    if (in.transports[t].fault) f.Add(Cause::kTransportFault, Mode::kSafeStop, I32(t), -1, 1.0, 0.0);
    if (in.transports[t].degraded) f.Add(Cause::kTransportDegraded, Mode::kDegraded, I32(t), -1, 1.0, 0.0);
  }
  const std::uint32_t misses = in.consecutive_deadline_misses;
  if (misses >= m.overrun_safe_stop)
    f.Add(Cause::kDeadlineOverrun, Mode::kSafeStop, -1, -1, misses, m.overrun_safe_stop);
  else if (misses >= m.overrun_degraded)
    f.Add(Cause::kDeadlineOverrun, Mode::kDegraded, -1, -1, misses, m.overrun_degraded);
  for (std::size_t k = 0; k < m.signal_limits.size(); ++k) {
    const SignalLimit& l = m.signal_limits[k];
    if (l.signal >= in.signals.size() || l.stream >= in.streams.size() || !in.streams[l.stream].seen) continue;
    const double v = in.signals[l.signal];
    if (!(v >= l.min && v <= l.max))
      f.Add(Cause::kSignalLimit, Mode::kSafeStop, I32(k), -1, v, std::isfinite(v) && v < l.min ? l.min : l.max);
  }
  if (in.estop_request) f.Add(Cause::kEStopRequest, Mode::kEStop, -1, -1, 1.0, 0.0);
}

}  // namespace

constexpr const char* kModeNames[] = {"nominal", "degraded", "safe-stop", "e-stop"};
static_assert(std::size(kModeNames) == kModeCount);
constexpr const char* kCauseNames[] = {"command limit",    "rate limit",         "non-finite command",
                                       "inference failed", "invalid sample",     "stale sample",
                                       "lost peer",        "transport degraded", "transport fault",
                                       "deadline overrun", "signal limit",       "e-stop request"};
static_assert(std::size(kCauseNames) == kCauseCount);

const char* ToString(Mode mode) noexcept {
  return EnumName(mode, kModeNames);
}

const char* ToString(Cause cause) noexcept {
  return EnumName(cause, kCauseNames);
}

Status ValidateSupervisorModel(const SupervisorModel& m) {
  for (const CommandLimit& c : m.commands) {
    const std::string w = "command '" + c.name + "': ";
    const bool moves = std::isfinite(c.rate) || c.stop == StopKind::kRamp;
    const struct {
      const char* name;
      double v;
    } numbers[] = {{"min", c.min},
                   {"max", c.max},
                   {"degraded_min", c.degraded_min},
                   {"degraded_max", c.degraded_max},
                   {"stop_rate", c.stop_rate},
                   {"stop_value", c.stop_value}};
    for (const auto& n : numbers) {
      if (!std::isfinite(n.v)) return Invalid(w + n.name + " = " + Num(n.v) + ": not finite");
      if (moves && std::abs(n.v) > kLimitBound)
        return Invalid(w + n.name + " = " + Num(n.v) + ": magnitude must be <= 1000");
    }
    if (!(c.min < c.max)) return Invalid(w + "min " + Num(c.min) + " is not below max " + Num(c.max));
    if (!(c.min <= c.degraded_min && c.degraded_min <= c.degraded_max && c.degraded_max <= c.max))
      return Invalid(w + "degraded limits [" + Num(c.degraded_min) + ", " + Num(c.degraded_max) + "] are not inside [" +
                     Num(c.min) + ", " + Num(c.max) + "]");
    if (!(c.rate > 0) || (std::isfinite(c.rate) && c.rate > kLimitBound))
      return Invalid(w + "rate = " + Num(c.rate) + ": must be > 0 and <= 1000 (or unlimited)");
    if (c.stop == StopKind::kRamp) {
      if (c.min > 0.0 || c.max < 0.0)
        return Invalid(w + "limits [" + Num(c.min) + ", " + Num(c.max) + "] exclude zero (stopping must be allowed)");
      if (!(c.stop_rate > 0) || (std::isfinite(c.rate) && c.stop_rate < c.rate))
        return Invalid(w + "stop_rate = " + Num(c.stop_rate) + ": must be > 0 and >= the rate " + Num(c.rate));
    } else if (c.stop == StopKind::kValue && (c.stop_value < c.min || c.stop_value > c.max)) {
      return Invalid(w + "stop_value = " + Num(c.stop_value) + ": outside [" + Num(c.min) + ", " + Num(c.max) + "]");
    } else if (c.stop == StopKind::kHoldInput &&
               (c.hold_input < 0 || static_cast<std::size_t>(c.hold_input) >= m.input_names.size())) {
      return Invalid(w + "hold_input " + std::to_string(c.hold_input) + " is not an input");
    }
  }
  for (const StreamLimit& s : m.streams) {
    if (s.silence_faults &&
        !(s.stale_degraded_ticks < s.stale_safe_stop_ticks && s.stale_safe_stop_ticks < s.lost_ticks))
      return Invalid("stream '" + s.name + "': stale limits " + std::to_string(s.stale_degraded_ticks) +
                     " (degraded), " + std::to_string(s.stale_safe_stop_ticks) + " (safe-stop), " +
                     std::to_string(s.lost_ticks) + " (lost) must increase");
    if (s.invalid_safe_stop < 1) return Invalid("stream '" + s.name + "': invalid_safe_stop must be >= 1");
  }
  for (const SignalLimit& l : m.signal_limits)
    if (!(std::isfinite(l.min) && std::isfinite(l.max) && l.min <= l.max))
      return Invalid("signal limit '" + l.name + "': [" + Num(l.min) + ", " + Num(l.max) + "] is not a range");
  if (!(m.overrun_degraded >= 1 && m.overrun_safe_stop > m.overrun_degraded))
    return Invalid("overrun limits " + std::to_string(m.overrun_degraded) + " (degraded), " +
                   std::to_string(m.overrun_safe_stop) + " (safe-stop) must satisfy 1 <= degraded < safe-stop");
  return {};
}

SupervisorState MakeSupervisorState(const SupervisorModel& m) {
  SupervisorState s;
  for (const CommandLimit& c : m.commands) s.previous.push_back(Sane(0.0, c.min, c.max));
  s.invalid_run.assign(m.streams.size(), 0);
  return s;
}

Decision Supervise(const SupervisorModel& m, const SupervisorInput& in, std::uint64_t tick, SupervisorState& st,
                   std::span<double> out) noexcept {
  const std::size_t n = m.commands.size();
  Findings f;
  const bool sized = in.command.size() == n && out.size() == n && st.previous.size() == n &&
                     in.streams.size() == m.streams.size() && st.invalid_run.size() == m.streams.size() &&
                     in.transports.size() == m.transport_names.size();
  if (!sized) f.Add(Cause::kNonFiniteCommand, Mode::kSafeStop, -1, -1, 0.0, 0.0);
  const std::size_t k_end = std::min({n, in.command.size(), out.size(), st.previous.size()});
  // The command: a non-finite element or a failed inference holds the previous command (as sent).
  std::int32_t bad = -1;
  for (std::size_t k = 0; k < k_end; ++k)
    if (bad < 0 && !std::isfinite(in.command[k])) bad = I32(k);
  if (bad >= 0) f.Add(Cause::kNonFiniteCommand, Mode::kSafeStop, bad, -1, in.command[static_cast<std::size_t>(bad)], 0);
  if (in.inference_failed) f.Add(Cause::kInferenceFailed, Mode::kSafeStop, -1, -1, 0.0, 0.0);
  const bool hold = bad >= 0 || in.inference_failed;
  for (std::size_t k = 0; k < k_end; ++k) {
    const CommandLimit& c = m.commands[k];
    const double prev = Sane(st.previous[k], c.min, c.max);
    double v = hold ? prev : in.command[k];
    if (v < c.min || v > c.max) {
      f.Add(Cause::kCommandLimit, m.command_limit_degrades ? Mode::kDegraded : Mode::kNominal, I32(k), -1, v,
            v < c.min ? c.min : c.max);
      v = std::clamp(v, c.min, c.max);
    }
    out[k] = v;
  }
  CheckStreams(m, in, st, f);
  CheckRest(m, in, f);

  // Latch upward.
  Decision d = f.worst;
  if (static_cast<std::uint8_t>(st.mode) > static_cast<std::uint8_t>(Mode::kEStop)) st.mode = Mode::kEStop;
  if (d.any && d.cause_mode > st.mode) {
    st.mode = d.cause_mode;
    ++st.transitions;
    d.transition = true;
  }

  // The command of the mode.
  std::int32_t limited = -1;
  double change = 0;  // the first rate-limited command's requested change
  for (std::size_t k = 0; k < k_end; ++k) {
    const CommandLimit& c = m.commands[k];
    const double prev = Sane(st.previous[k], c.min, c.max);
    double v = out[k];
    switch (st.mode) {
      case Mode::kNominal:
      case Mode::kDegraded: {
        if (st.mode == Mode::kDegraded) v = std::clamp(v, c.degraded_min, c.degraded_max);
        const double stepped = Toward(prev, v, c.rate);
        if (stepped != v && limited < 0) {
          limited = I32(k);
          change = v - prev;
        }
        v = stepped;
        break;
      }
      case Mode::kEStop:
        if (!m.estop_damps) {
          v = Sane(0.0, c.min, c.max);
          break;
        }
        [[fallthrough]];  // e-stop that damps: safe-stop's commands
      case Mode::kSafeStop:
        if (c.stop == StopKind::kRamp) {
          v = Toward(prev, 0.0, c.stop_rate);
        } else if (c.stop == StopKind::kValue) {
          v = c.stop_value;
        } else {
          const auto i = static_cast<std::size_t>(c.hold_input);
          v = Sane(i < in.inputs.size() ? in.inputs[i] : 0.0, c.min, c.max);
        }
        break;
    }
    out[k] = v;
    st.previous[k] = v;
  }
  if (limited >= 0) {
    const auto k = static_cast<std::size_t>(limited);
    f.Add(Cause::kRateLimit, Mode::kNominal, limited, -1, change, m.commands[k].rate);
    if (!d.any) {
      const bool transition = d.transition;
      d = f.worst;
      d.transition = transition;
    }
  }
  d.mode = st.mode;
  d.causes = f.causes;
  if (d.any && d.cause == Cause::kInferenceFailed) d.detail = in.inference_status;
  ++st.ticks;
  for (std::size_t c = 0; c < kCauseCount; ++c)
    if ((f.causes >> c) & 1u) ++st.counts.n[c];
  const auto mi = static_cast<std::size_t>(st.mode);
  ++st.ticks_in_mode[mi];
  if (d.transition) {
    // A jump over a level (nominal -> safe-stop) enters only the level reached.
    st.entered[mi] = d;
    st.entered_tick[mi] = tick;
  }
  st.last = d;
  return d;
}

bool Reset(SupervisorState& st, bool armed) noexcept {
  if (armed) return false;
  st.mode = Mode::kNominal;
  std::fill(st.previous.begin(), st.previous.end(), 0.0);
  std::fill(st.invalid_run.begin(), st.invalid_run.end(), 0u);
  st.last = Decision{};
  return true;
}

std::size_t Describe(const SupervisorModel& m, const Decision& d, char* buf, std::size_t size) noexcept {
  if (size == 0) return 0;
  const char* mode = ToString(d.any ? d.cause_mode : d.mode);
  // The i-th entry's name (its .name, or the string itself), "?" when i is out of range.
  auto name = [](const auto& v, std::int32_t i) -> const char* {
    if (i < 0 || static_cast<std::size_t>(i) >= v.size()) return "?";
    const auto& e = v[static_cast<std::size_t>(i)];
    if constexpr (std::is_same_v<std::decay_t<decltype(e)>, std::string>) {
      return e.c_str();
    } else {
      return e.name.c_str();
    }
  };
  const char* input = name(m.input_names, d.input);
  const char* cause = ToString(d.cause);
  int len = 0;
  if (!d.any) {
    len = std::snprintf(buf, size, "%s: all clear", mode);
  } else {
    switch (d.cause) {
      case Cause::kCommandLimit:
      case Cause::kRateLimit:
        len = std::snprintf(buf, size, "%s: %s: %s = %g (limit %g)", mode, cause, name(m.commands, d.subject), d.value,
                            d.limit);
        break;
      case Cause::kNonFiniteCommand:
        len = std::snprintf(buf, size, "%s: %s: %s = %g", mode, cause, name(m.commands, d.subject), d.value);
        break;
      case Cause::kInvalidSample:
        len = std::snprintf(buf, size, "%s: %s: %s = %g (%.0f in a row)", mode, cause, input, d.value, d.limit);
        break;
      case Cause::kStaleSample:
        len = std::snprintf(buf, size, "%s: %s: %s: age %.0f ticks > %.0f", mode, cause, name(m.streams, d.subject),
                            d.value, d.limit);
        break;
      case Cause::kLostPeer:
        if (d.input == -2) {
          len = std::snprintf(buf, size, "%s: %s: transport '%s' reports the peer gone", mode, cause,
                              name(m.transport_names, d.subject));
        } else {
          len = std::snprintf(buf, size, "%s: %s: %s: no sample for %.0f ticks > %.0f", mode, cause,
                              name(m.streams, d.subject), d.value, d.limit);
        }
        break;
      case Cause::kTransportDegraded:
      case Cause::kTransportFault:
        len = std::snprintf(buf, size, "%s: %s: '%s'", mode, cause, name(m.transport_names, d.subject));
        break;
      case Cause::kDeadlineOverrun:
        len = std::snprintf(buf, size, "%s: %s: %.0f consecutive misses >= %.0f", mode, cause, d.value, d.limit);
        break;
      case Cause::kSignalLimit:
        len = std::snprintf(buf, size, "%s: %s: %s = %g (limit %g)", mode, cause, name(m.signal_limits, d.subject),
                            d.value, d.limit);
        break;
      case Cause::kInferenceFailed:
        len = std::snprintf(buf, size, "%s: %s: %s", mode, cause, d.detail != nullptr ? d.detail : "");
        break;
      case Cause::kEStopRequest: len = std::snprintf(buf, size, "%s: %s", mode, cause); break;
    }
  }
  return len < 0 ? 0 : std::min(static_cast<std::size_t>(len), size - 1);
}

std::string Describe(const SupervisorModel& m, const Decision& d) {
  char buf[256];
  Describe(m, d, buf, sizeof buf);
  return buf;
}

}  // namespace pbppo::safety
