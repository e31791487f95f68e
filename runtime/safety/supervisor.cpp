#include "runtime/safety/supervisor.hpp"

#include <cmath>

namespace pbppo::safety {
namespace {

struct Finding {
  Mode mode = Mode::kNominal;
  Fault fault = Fault::kNone;
  std::int32_t channel = -1, field = -1, transport = -1;
};

// Keeps the first finding of the most severe level.
void Raise(Finding& worst, Mode mode, Fault fault, std::int32_t channel, std::int32_t field, std::int32_t transport) {
  if (mode > worst.mode) worst = Finding{mode, fault, channel, field, transport};
}

std::int32_t I32(std::size_t v) {
  return static_cast<std::int32_t>(v);
}

}  // namespace

const char* ToString(Mode mode) noexcept {
  switch (mode) {
    case Mode::kNominal: return "nominal";
    case Mode::kDegraded: return "degraded";
    case Mode::kSafeStop: return "safe-stop";
    case Mode::kEStop: return "e-stop";
  }
  return "?";
}

const char* ToString(Fault fault) noexcept {
  switch (fault) {
    case Fault::kNone: return "none";
    case Fault::kCommandLimit: return "command outside limits";
    case Fault::kStaleFeedback: return "stale feedback";
    case Fault::kNonFiniteCommand: return "non-finite command";
    case Fault::kNonFiniteFeedback: return "non-finite feedback";
    case Fault::kFeedbackLimit: return "feedback outside limits";
    case Fault::kTransportDegraded: return "transport degraded";
    case Fault::kTransportFault: return "transport fault";
    case Fault::kEStopRequest: return "e-stop requested";
  }
  return "?";
}

Status ValidateSupervisorModel(const SupervisorModel& m) {
  auto fail = [](const std::string& what) { return MakeError(ErrorCode::kInvalidValue, "supervisor model: " + what); };
  const std::size_t nc = std::size_t{m.channels} * m.command_fields;
  const std::size_t nf = std::size_t{m.channels} * m.feedback_fields;
  if (m.command_min.size() != nc || m.command_max.size() != nc)
    return fail("command_min/command_max have " + std::to_string(m.command_min.size()) + "/" +
                std::to_string(m.command_max.size()) + " entries, channels x command_fields is " + std::to_string(nc));
  if (m.feedback_min.size() != nf || m.feedback_max.size() != nf)
    return fail("feedback_min/feedback_max have " + std::to_string(m.feedback_min.size()) + "/" +
                std::to_string(m.feedback_max.size()) + " entries, channels x feedback_fields is " +
                std::to_string(nf));
  if (m.channel_names.size() != m.channels) return fail("channel_names: one name per channel expected");
  if (m.command_field_names.size() != m.command_fields) return fail("command_field_names: one per field expected");
  if (m.feedback_field_names.size() != m.feedback_fields) return fail("feedback_field_names: one per field expected");
  if (m.transport_names.size() != m.transports) return fail("transport_names: one per transport expected");
  for (std::size_t i = 0; i < nc; ++i)
    if (!(m.command_min[i] < m.command_max[i]))
      return fail("channel '" + m.channel_names[i / m.command_fields] + "' command field '" +
                  m.command_field_names[i % m.command_fields] + "': min " + std::to_string(m.command_min[i]) +
                  " is not below max " + std::to_string(m.command_max[i]));
  for (std::size_t i = 0; i < nf; ++i)
    if (!(m.feedback_min[i] < m.feedback_max[i]))
      return fail("channel '" + m.channel_names[i / m.feedback_fields] + "' feedback field '" +
                  m.feedback_field_names[i % m.feedback_fields] + "': min " + std::to_string(m.feedback_min[i]) +
                  " is not below max " + std::to_string(m.feedback_max[i]));
  if (!(0 < m.stale_degraded_ticks && m.stale_degraded_ticks <= m.stale_safe_stop_ticks &&
        m.stale_safe_stop_ticks < m.stale_estop_ticks))
    return fail("stale thresholds " + std::to_string(m.stale_degraded_ticks) + " (degraded), " +
                std::to_string(m.stale_safe_stop_ticks) + " (safe-stop), " + std::to_string(m.stale_estop_ticks) +
                " (e-stop) must satisfy 0 < degraded <= safe-stop < e-stop");
  return {};
}

Decision Supervise(const SupervisorModel& m, const SupervisorInput& in, Mode previous) noexcept {
  Finding worst;
  const std::size_t nc = std::size_t{m.channels} * m.command_fields;
  const std::size_t nf = std::size_t{m.channels} * m.feedback_fields;
  if (in.command.size() != nc) Raise(worst, Mode::kSafeStop, Fault::kNonFiniteCommand, 0, -1, -1);
  if (in.feedback.size() != nf || in.feedback_age_ticks.size() != m.channels)
    Raise(worst, Mode::kSafeStop, Fault::kNonFiniteFeedback, 0, -1, -1);
  if (in.transports.size() != m.transports) Raise(worst, Mode::kSafeStop, Fault::kTransportFault, -1, -1, 0);

  if (in.estop_request) Raise(worst, Mode::kEStop, Fault::kEStopRequest, -1, -1, -1);
  for (std::size_t t = 0; t < in.transports.size() && t < m.transports; ++t) {
    if (in.transports[t].fault) Raise(worst, Mode::kSafeStop, Fault::kTransportFault, -1, -1, I32(t));
    if (in.transports[t].degraded) Raise(worst, Mode::kDegraded, Fault::kTransportDegraded, -1, -1, I32(t));
  }
  for (std::size_t c = 0; c < m.channels; ++c) {
    if (c < in.feedback_age_ticks.size()) {
      const std::uint32_t age = in.feedback_age_ticks[c];
      if (age >= m.stale_estop_ticks) Raise(worst, Mode::kEStop, Fault::kStaleFeedback, I32(c), -1, -1);
      if (age >= m.stale_safe_stop_ticks) Raise(worst, Mode::kSafeStop, Fault::kStaleFeedback, I32(c), -1, -1);
      if (age >= m.stale_degraded_ticks) Raise(worst, Mode::kDegraded, Fault::kStaleFeedback, I32(c), -1, -1);
    }
    if (in.command.size() == nc) {
      for (std::size_t f = 0; f < m.command_fields; ++f) {
        const std::size_t k = c * m.command_fields + f;
        const double v = in.command[k];
        if (!std::isfinite(v)) {
          Raise(worst, Mode::kSafeStop, Fault::kNonFiniteCommand, I32(c), I32(f), -1);
        } else if (v < m.command_min[k] || v > m.command_max[k]) {
          Raise(worst, Mode::kDegraded, Fault::kCommandLimit, I32(c), I32(f), -1);
        }
      }
    }
    if (in.feedback.size() == nf) {
      for (std::size_t f = 0; f < m.feedback_fields; ++f) {
        const std::size_t k = c * m.feedback_fields + f;
        const double v = in.feedback[k];
        if (!std::isfinite(v)) {
          Raise(worst, Mode::kSafeStop, Fault::kNonFiniteFeedback, I32(c), I32(f), -1);
        } else if (v < m.feedback_min[k] || v > m.feedback_max[k]) {
          Raise(worst, Mode::kSafeStop, Fault::kFeedbackLimit, I32(c), I32(f), -1);
        }
      }
    }
  }
  Decision d;
  d.mode = worst.mode > previous ? worst.mode : previous;
  d.transition = d.mode != previous;
  d.fault = worst.fault;
  d.fault_mode = worst.mode;
  d.channel = worst.channel;
  d.field = worst.field;
  d.transport = worst.transport;
  return d;
}

std::uint32_t LimitCommand(const SupervisorModel& m, std::span<double> command) noexcept {
  std::uint32_t changed = 0;
  const std::size_t n = std::min(command.size(), m.command_min.size());
  for (std::size_t k = 0; k < n; ++k) {
    double& v = command[k];
    const double lo = m.command_min[k], hi = m.command_max[k];
    double w = v;
    if (!std::isfinite(w)) w = lo > 0 ? lo : (hi < 0 ? hi : 0.0);
    w = w < lo ? lo : (w > hi ? hi : w);
    if (!(w == v)) ++changed;
    v = w;
  }
  return changed;
}

Decision Step(const SupervisorModel& m, const SupervisorInput& in, std::uint64_t tick, SupervisorData& data) noexcept {
  const Decision d = Supervise(m, in, data.mode);
  ++data.decisions;
  ++data.findings[static_cast<std::size_t>(d.fault)];
  if (d.transition) {
    ++data.transitions;
    // A jump over a level (nominal -> safe-stop) enters only the level reached.
    data.entered[static_cast<std::size_t>(d.mode)] = d;
    data.entered_tick[static_cast<std::size_t>(d.mode)] = tick;
  }
  data.mode = d.mode;
  ++data.ticks_in_mode[static_cast<std::size_t>(d.mode)];
  return d;
}

std::string Describe(const SupervisorModel& m, const Decision& d) {
  std::string s = std::string(ToString(d.fault_mode)) + ": " + ToString(d.fault);
  if (d.channel >= 0 && static_cast<std::size_t>(d.channel) < m.channel_names.size())
    s += ", channel '" + m.channel_names[static_cast<std::size_t>(d.channel)] + "'";
  if (d.field >= 0) {
    const bool cmd = d.fault == Fault::kCommandLimit || d.fault == Fault::kNonFiniteCommand;
    const auto& names = cmd ? m.command_field_names : m.feedback_field_names;
    if (static_cast<std::size_t>(d.field) < names.size())
      s += std::string(cmd ? ", command " : ", feedback ") + names[static_cast<std::size_t>(d.field)];
  }
  if (d.transport >= 0 && static_cast<std::size_t>(d.transport) < m.transport_names.size())
    s += ", transport '" + m.transport_names[static_cast<std::size_t>(d.transport)] + "'";
  return s;
}

}  // namespace pbppo::safety
