// The loop's state as a log's snapshot holds it (SaveState, LoadState in runtime/loop/loop.hpp):
// everything a tick carries to the next, written field by field.
#include <string>

#include "runtime/loop/loop.hpp"

namespace pbppo::loop {

using robot::RobotData;
using robot::RobotModel;

struct StateImpl {
  static void PutDecision(StateWriter& o, const safety::Decision& d) noexcept {
    o.Put(d.mode);
    o.Put(d.any);
    o.Put(d.cause);
    o.Put(d.cause_mode);
    o.Put(d.subject);
    o.Put(d.input);
    o.Put(d.value);
    o.Put(d.limit);
    o.Put(d.causes);
    o.Put(d.transition);
  }
  static bool GetDecision(StateReader& in, safety::Decision& d) {
    d.detail = "";
    return in.GetBelow(d.mode, safety::kModeCount, "decision.mode") && in.GetBool(d.any, "decision.any") &&
           in.GetBelow(d.cause, safety::kCauseCount, "decision.cause") &&
           in.GetBelow(d.cause_mode, safety::kModeCount, "decision.cause_mode") &&
           in.Get(d.subject, "decision.subject") && in.Get(d.input, "decision.input") &&
           in.Get(d.value, "decision.value") && in.Get(d.limit, "decision.limit") &&
           in.Get(d.causes, "decision.causes") && in.GetBool(d.transition, "decision.transition");
  }
  static void PutText(StateWriter& o, const char* text, std::size_t size) noexcept { o.PutSpan<char>({text, size}); }
  static bool GetText(StateReader& in, char* text, std::size_t size, const char* field) {
    if (!in.GetSpan<char>({text, size}, field)) return false;
    text[size - 1] = '\0';
    return true;
  }

  static void Save(const RobotData& d, const LoopData& l, StateWriter& o) noexcept {
    // The robot's data.
    o.Put(d.tick);
    o.PutSpan<double>(d.fields);
    o.PutSpan<std::uint8_t>(d.fresh);
    o.Put(static_cast<std::uint32_t>(d.streams.size()));
    for (const safety::StreamState& st : d.streams) {
      o.Put(st.seen);
      o.Put(st.age_ticks);
      o.Put(st.invalid_input);
      o.Put(st.invalid_value);
    }
    o.PutSpan<std::uint64_t>(d.samples);
    o.Put(static_cast<std::uint32_t>(d.transports.size()));
    for (const safety::TransportHealth& h : d.transports) {
      o.Put(h.degraded);
      o.Put(h.fault);
      o.Put(h.lost);
    }
    o.PutSpan<double>(d.command);
    o.PutSpan<robot::MotorCommand>(d.motors);
    o.Put(d.mode);
    // The loop's.
    o.Put(l.phase_);
    o.PutSpan<std::uint64_t>(l.phase_start_);
    o.Put(l.source_done_);
    o.Put(l.ended_);
    o.PutSpan<std::uint8_t>(l.answered_);
    o.PutSpan<double>(l.q0_);
    o.PutSpan<double>(l.desired_);
    o.PutSpan<double>(l.limit_values_);
    const safety::SupervisorState& s = l.sup_;
    o.Put(s.mode);
    o.PutSpan<double>(s.previous);
    o.PutSpan<std::uint32_t>(s.invalid_run);
    o.Put(s.ticks);
    o.Put(s.transitions);
    o.PutSpan<std::uint64_t>(s.counts.n);
    o.PutSpan<std::uint64_t>(s.ticks_in_mode);
    for (const safety::Decision& e : s.entered) PutDecision(o, e);
    o.PutSpan<std::uint64_t>(s.entered_tick);
    PutDecision(o, s.last);
    o.Put(static_cast<std::uint32_t>(l.modes_.size()));
    for (const ModeChange& c : l.modes_) {
      o.Put(c.tick);
      o.Put(c.mode);
      PutText(o, c.reason, sizeof c.reason);
    }
    o.Put(l.mode_count_);
    o.Put(static_cast<std::uint32_t>(l.phases_.size()));
    for (const PhaseChange& c : l.phases_) {
      o.Put(c.tick);
      o.Put(c.from);
      o.Put(c.to);
    }
    o.Put(l.phase_count_);
    o.Put(l.healthy_ticks_);
    o.Put(l.stopped_by_);
    const RecoveryStatus& r = l.recovery_;
    for (std::uint64_t v : {r.stops, r.automatic, r.requested, r.refused, r.last_tick}) o.Put(v);
    o.Put(r.last_refused);
    PutText(o, r.last, sizeof r.last);
    if (l.operator_) {
      o.PutSpan<std::uint8_t>(l.operator_held_);
      const OperatorStatus& op = l.operator_status_;
      for (std::uint64_t v : {op.requests, op.refused, op.last_tick}) o.Put(v);
      PutText(o, op.last, sizeof op.last);
    }
    // The source's.
    o.Put(l.source_ != nullptr);
    if (l.source_ != nullptr) l.source_->SaveState(o);
  }

  static bool Load(RobotData& d, LoopData& l, StateReader& in) {
    bool ok = in.Get(d.tick, "data.tick") && in.GetSpan<double>(d.fields, "data.fields") &&
              in.GetSpan<std::uint8_t>(d.fresh, "data.fresh") && in.GetCount(d.streams.size(), "data.streams");
    for (safety::StreamState& st : d.streams)
      ok = ok && in.GetBool(st.seen, "data.streams.seen") && in.Get(st.age_ticks, "data.streams.age_ticks") &&
           in.Get(st.invalid_input, "data.streams.invalid_input") &&
           in.Get(st.invalid_value, "data.streams.invalid_value");
    ok = ok && in.GetSpan<std::uint64_t>(d.samples, "data.samples") &&
         in.GetCount(d.transports.size(), "data.transports");
    for (safety::TransportHealth& h : d.transports)
      ok = ok && in.GetBool(h.degraded, "data.transports.degraded") && in.GetBool(h.fault, "data.transports.fault") &&
           in.GetBool(h.lost, "data.transports.lost");
    ok = ok && in.GetSpan<double>(d.command, "data.command") &&
         in.GetSpan<robot::MotorCommand>(d.motors, "data.motors") &&
         in.GetBelow(d.mode, safety::kModeCount, "data.mode");
    if (!ok) return false;
    for (robot::MotorCommand c : d.motors)
      if (static_cast<std::uint8_t>(c) > 3)
        return in.Fail("field 'data.motors': " + std::to_string(static_cast<int>(c)) + " is not a motor command");
    safety::SupervisorState& s = l.sup_;
    ok = in.GetBelow(l.phase_, kPhaseCount, "loop.phase") &&
         in.GetSpanUpTo<std::uint64_t>(l.phase_start_, "loop.phase_start") &&
         in.GetBool(l.source_done_, "loop.source_done") && in.GetBool(l.ended_, "loop.ended") &&
         in.GetSpan<std::uint8_t>(l.answered_, "loop.answered") && in.GetSpan<double>(l.q0_, "loop.q0") &&
         in.GetSpan<double>(l.desired_, "loop.desired") && in.GetSpan<double>(l.limit_values_, "loop.limit_values") &&
         in.GetBelow(s.mode, safety::kModeCount, "supervisor.mode") &&
         in.GetSpan<double>(s.previous, "supervisor.previous") &&
         in.GetSpan<std::uint32_t>(s.invalid_run, "supervisor.invalid_run") && in.Get(s.ticks, "supervisor.ticks") &&
         in.Get(s.transitions, "supervisor.transitions") &&
         in.GetSpan<std::uint64_t>(s.counts.n, "supervisor.counts") &&
         in.GetSpan<std::uint64_t>(s.ticks_in_mode, "supervisor.ticks_in_mode");
    for (safety::Decision& e : s.entered) ok = ok && GetDecision(in, e);
    ok = ok && in.GetSpan<std::uint64_t>(s.entered_tick, "supervisor.entered_tick") && GetDecision(in, s.last) &&
         in.GetCount(l.modes_.size(), "loop.mode_changes");
    for (ModeChange& c : l.modes_)
      ok = ok && in.Get(c.tick, "loop.mode_changes.tick") &&
           in.GetBelow(c.mode, safety::kModeCount, "loop.mode_changes.mode") &&
           GetText(in, c.reason, sizeof c.reason, "loop.mode_changes.reason");
    ok = ok && in.Get(l.mode_count_, "loop.mode_change_count") && in.GetCount(l.phases_.size(), "loop.phase_changes");
    for (PhaseChange& c : l.phases_)
      ok = ok && in.Get(c.tick, "loop.phase_changes.tick") &&
           in.GetBelow(c.from, kPhaseCount, "loop.phase_changes.from") &&
           in.GetBelow(c.to, kPhaseCount, "loop.phase_changes.to");
    RecoveryStatus& r = l.recovery_;
    ok = ok && in.Get(l.phase_count_, "loop.phase_change_count") && in.Get(l.healthy_ticks_, "loop.healthy_ticks") &&
         in.Get(l.stopped_by_, "loop.stopped_by") && in.Get(r.stops, "recovery.stops") &&
         in.Get(r.automatic, "recovery.automatic") && in.Get(r.requested, "recovery.requested") &&
         in.Get(r.refused, "recovery.refused") && in.Get(r.last_tick, "recovery.last_tick") &&
         in.GetBool(r.last_refused, "recovery.last_refused") && GetText(in, r.last, sizeof r.last, "recovery.last");
    OperatorStatus& op = l.operator_status_;
    if (ok && l.operator_)
      ok = in.GetSpanUpTo<std::uint8_t>(l.operator_held_, "loop.operator_held") &&
           in.Get(op.requests, "operator.requests") && in.Get(op.refused, "operator.refused") &&
           in.Get(op.last_tick, "operator.last_tick") && GetText(in, op.last, sizeof op.last, "operator.last");
    if (!ok) return false;
    bool has_source = false;
    if (!in.GetBool(has_source, "source")) return false;
    if (has_source != (l.source_ != nullptr))
      return in.Fail(std::string("field 'source': the snapshot was taken ") + (has_source ? "with" : "without") +
                     " a command source, the replay has " + (l.source_ != nullptr ? "one" : "none"));
    return l.source_ == nullptr || l.source_->LoadState(in);
  }
};

void SaveState(const RobotModel&, const RobotData& data, const LoopData& loop, StateWriter& out) noexcept {
  StateImpl::Save(data, loop, out);
}

Status LoadState(const RobotModel& model, RobotData& data, LoopData& loop, std::span<const std::uint8_t> bytes) {
  (void)model;
  StateReader in(bytes);
  if (!StateImpl::Load(data, loop, in)) return MakeError(ErrorCode::kFormat, "snapshot: " + in.error());
  if (in.left() != 0)
    return MakeError(ErrorCode::kFormat, "snapshot: " + std::to_string(in.left()) + " bytes after the last field");
  return {};
}

}  // namespace pbppo::loop
