#include "runtime/loop/loop.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "runtime/core/clock.hpp"
#include "runtime/loop/log.hpp"

namespace pbppo::loop {

using robot::MotorCommand;
using robot::RobotData;
using robot::RobotModel;
using safety::Mode;

std::unique_ptr<LoopData> MakeLoopData(const RobotModel& model, CommandSource* source, const LoopOptions& options) {
  std::unique_ptr<LoopData> l(new LoopData());
  l->source_ = source;
  l->options_ = options;
  l->answered_.assign(model.motors.size(), 0);
  l->q0_.assign(model.motors.size(), 0.0);
  for (const robot::CommandSpec& c : model.commands) l->desired_.push_back(c.neutral);
  std::vector<std::string> limited;
  for (const auto& s : model.supervisor_model.signal_limits) limited.push_back(s.name);
  // The model checked every supervised signal's name at load.
  l->limit_signals_ = std::move(robot::SignalProgram::Create(model, limited)).value();
  l->limit_values_.assign(limited.size(), 0.0);
  l->sup_ = safety::MakeSupervisorState(model.supervisor_model);
  l->operator_ = model.op.any();
  return l;
}

std::vector<std::string> DescribeChanges(const LoopData& l, bool with_phases) {
  std::vector<std::string> out;
  // "phase: 40 changes in all, the first 32 above"
  const auto more = [&](const char* what, const char* changes, std::uint64_t all, std::size_t shown) {
    if (all <= shown) return;
    std::string line = what;
    line += std::to_string(all);
    line += changes;
    line += " in all, the first ";
    line += std::to_string(shown);
    line += " above";
    out.push_back(std::move(line));
  };
  if (with_phases) {
    for (const PhaseChange& p : l.phase_changes()) {
      std::string line = "phase: tick ";
      line += std::to_string(p.tick);
      line += ": ";
      line += ToString(p.from);
      line += " -> ";
      line += ToString(p.to);
      out.push_back(std::move(line));
    }
    more("phase: ", " changes", l.phase_change_count(), l.phase_changes().size());
  }
  for (const ModeChange& m : l.mode_changes()) {
    std::string line = "mode change: tick ";
    line += std::to_string(m.tick);
    line += ": ";
    line += m.reason;
    out.push_back(std::move(line));
  }
  more("mode change: ", "", l.mode_change_count(), l.mode_changes().size());
  return out;
}

std::string Describe(const OperatorStatus& s) {
  if (s.requests == 0) return "";
  std::string out = std::to_string(s.requests) + " requests, " + std::to_string(s.refused) + " refused";
  if (s.refused > 0) out += "; the last: " + std::string(s.last);
  return out;
}

LoopStatus LoopData::Status() const noexcept {
  LoopStatus s;
  (void)status_.Read(&s);  // version 0: no tick yet, the zero status
  return s;
}

bool LoopData::ResetSupervisor() noexcept {
  if (!safety::Reset(sup_, phase_ != Phase::kDisarmed)) return false;
  estop_.store(false, std::memory_order_relaxed);
  stopped_by_ = 0;
  healthy_ticks_ = 0;
  return true;
}

struct TickImpl {
  static void Enter(LoopData& l, Phase p, std::uint64_t tick) noexcept {
    if (l.phase_count_ < LoopData::kMaxChanges) l.phases_[l.phase_count_] = PhaseChange{tick, l.phase_, p};
    ++l.phase_count_;
    l.phase_ = p;
    l.phase_start_[static_cast<std::size_t>(p)] = tick;
    std::fill(l.answered_.begin(), l.answered_.end(), std::uint8_t{0});
  }

  static void StartRun(const RobotModel& m, const RobotData& d, LoopData& l) noexcept {
    Enter(l, Phase::kRun, d.tick);
    if (l.source_ != nullptr) l.source_->Start(m, d, l);
  }

  // The value safe-stop (and shutdown damping) sends for command k.
  static double StopValue(const RobotModel& m, const RobotData& d, std::size_t k) noexcept {
    const safety::CommandLimit& c = m.supervisor_model.commands[k];
    double v = 0.0;
    if (c.stop == safety::StopKind::kValue) v = c.stop_value;
    if (c.stop == safety::StopKind::kHoldInput) v = d.fields[static_cast<std::size_t>(c.hold_input)];
    return std::clamp(std::isfinite(v) ? v : 0.0, c.min, c.max);
  }

  static bool Armed(const RobotModel& m, Phase p) noexcept {
    return p == Phase::kRun || (m.phases.enable_motors && (p == Phase::kStandUp || p == Phase::kHold ||
                                                           p == Phase::kSitDown || p == Phase::kPassive));
  }

  // "lost peer, stale sample" (the causes of `bits`) into buf.
  static void CauseList(std::uint32_t bits, char* buf, std::size_t size) noexcept {
    std::size_t at = 0;
    buf[0] = '\0';
    for (std::size_t c = 0; c < safety::kCauseCount && at < size; ++c) {
      if (((bits >> c) & 1u) == 0) continue;
      const int n = std::snprintf(buf + at, size - at, "%s%s", at > 0 ? ", " : "",
                                  safety::ToString(static_cast<safety::Cause>(c)));
      if (n < 0) break;
      at += static_cast<std::size_t>(n);
    }
  }

  // The robot file's recovery rule, at the start of a tick (Recovery in loop.hpp): a re-arm by
  // request or automatically, or a refused request.
  static void Recover(const RobotModel& m, const RobotData& d, LoopData& l, const TickEvents& ev) noexcept {
    const robot::RecoverySpec& r = m.supervisor.recovery;
    RecoveryStatus& st = l.recovery_;
    const bool armed = Armed(m, l.phase_), stopped = l.sup_.mode >= Mode::kSafeStop && armed;
    const bool healthy = l.healthy_ticks_ >= r.healthy_ticks;
    const bool automatic =
        r.automatic && stopped && healthy && (l.stopped_by_ & ~r.causes) == 0 && st.automatic < r.max_automatic;
    if (!automatic && !ev.rearm) return;  // the common tick: nothing to do
    char causes[96];
    CauseList(l.stopped_by_, causes, sizeof causes);
    if (ev.rearm && !automatic && !(stopped && healthy)) {
      ++st.refused;
      st.last_tick = d.tick;
      st.last_refused = true;
      if (!armed) {
        std::snprintf(st.last, sizeof st.last, "re-arm request refused: not armed (%s)", ToString(l.phase_));
      } else if (!stopped) {
        std::snprintf(st.last, sizeof st.last, "re-arm request refused: nothing to recover from (%s, %s)",
                      ToString(l.phase_), safety::ToString(l.sup_.mode));
      } else {
        std::snprintf(st.last, sizeof st.last, "re-arm request refused: healthy for %u ticks, %u needed (%s: %s)",
                      l.healthy_ticks_, r.healthy_ticks, safety::ToString(l.sup_.mode), causes);
      }
      return;
    }
    if (automatic) {
      ++st.automatic;
    } else {
      ++st.requested;
    }
    st.last_tick = d.tick;
    st.last_refused = false;
    std::snprintf(st.last, sizeof st.last, "re-armed %s after %u healthy ticks (stopped by: %s)",
                  automatic ? "automatically" : "on request", l.healthy_ticks_, causes);
    if (l.mode_count_ < LoopData::kMaxChanges) {
      ModeChange& c = l.modes_[l.mode_count_];
      c.tick = d.tick;
      c.mode = Mode::kNominal;
      std::snprintf(c.reason, sizeof c.reason, "nominal: %.110s", st.last);
    }
    ++l.mode_count_;
    Enter(l, Phase::kDisarmed, d.tick);
    (void)safety::Reset(l.sup_, false);
    l.stopped_by_ = 0;
    l.healthy_ticks_ = 0;
    l.source_done_ = false;
  }

  // The operator's requests from the robot's fields (Operator requests in loop.hpp).
  static void OperatorRequests(const RobotModel& m, const RobotData& d, LoopData& l, TickEvents& ev) noexcept {
    if (!l.operator_) return;
    const robot::OperatorSpec& op = m.op;
    const auto valid = [&](std::int32_t f) {
      return d.streams[m.fields[static_cast<std::size_t>(f)].stream].invalid_input < 0;
    };
    const std::int32_t fields[kOperatorRequestCount] = {op.arm,   op.walk,          op.stop, op.estop,
                                                        op.rearm, op.switch_policy, op.sit};
    // The phases the robot file narrowed a request to (operator.from; 0: the controller's own).
    const robot::PhaseSet from[kOperatorRequestCount] = {op.from_arm, 0, 0, 0, 0, op.from_switch, op.from_sit};
    static constexpr const char* kFromWhy[kOperatorRequestCount] = {
        "not a phase operator.from.arm names", "", "", "", "", "not a phase operator.from.switch_policy names",
        "not a phase operator.from.sit names"};
    static constexpr const char* kName[kOperatorRequestCount] = {"arm",   "walk",   "stop", "estop",
                                                                 "rearm", "switch", "sit"};
    bool rise[kOperatorRequestCount] = {};
    for (std::size_t i = 0; i < kOperatorRequestCount; ++i) {
      const std::int32_t f = fields[i];
      if (f < 0 || (i != 3 && !valid(f))) continue;  // an invalid sample asks nothing (but e-stop), nor forgets
      const bool held = d.fields[static_cast<std::size_t>(f)] >= 0.5;
      rise[i] = held && l.operator_held_[i] == 0;
      l.operator_held_[i] = held ? 1 : 0;
      if (!rise[i]) continue;
      ++l.operator_status_.requests;
      if (from[i] != 0 && !robot::InPhases(from[i], l.phase_)) {
        Refuse(l, d.tick, kName[i], kFromWhy[i]);
        rise[i] = false;
        continue;
      }
      ev.operator_rises = static_cast<std::uint8_t>(ev.operator_rises | (1u << i));
    }
    ev.arm = ev.arm || rise[0];
    ev.walk = rise[1];
    if (rise[2]) {
      l.stop_.store(true, std::memory_order_relaxed);
      ev.stop = true;
    }
    ev.estop = ev.estop || rise[3];
    ev.rearm = ev.rearm || rise[4];
    if (op.deadman >= 0) ev.deadman = valid(op.deadman) && d.fields[static_cast<std::size_t>(op.deadman)] >= 0.5;
  }

  // An operator's request the phase did not take (OperatorStatus in loop.hpp).
  static void Refuse(LoopData& l, std::uint64_t tick, const char* request, const char* why) noexcept {
    OperatorStatus& st = l.operator_status_;
    ++st.refused;
    st.last_tick = tick;
    std::snprintf(st.last, sizeof st.last, "%s refused at tick %llu: %s (%s)", request,
                  static_cast<unsigned long long>(tick), why, ToString(l.phase_));
  }

  // Per motor: the measured pose, inside the commands' limits (a joint resting on its stop, a
  // little past its limit, is commanded from the limit), where a stand-up starts.
  static void MeasuredPose(const RobotModel& m, const RobotData& d, LoopData& l) noexcept {
    for (std::size_t k = 0; k < m.motors.size(); ++k) {
      const robot::MotorSpec& mo = m.motors[k];
      const double q = d.fields[mo.q_field];
      l.q0_[k] = mo.velocity_commanded() ? q : std::clamp(q, m.commands[mo.q].min, m.commands[mo.q].max);
    }
  }

  // Stand-up (from the measured pose) and hold, or straight to hold without a stand-up.
  static void EnterStandUp(const RobotModel& m, LoopData& l, std::uint64_t tick) noexcept {
    if (m.phases.stand_up_ticks > 0) {
      Enter(l, Phase::kStandUp, tick);
      Ramp(m, l, 0, false);
    } else {
      Enter(l, Phase::kHold, tick);
    }
  }

  // Sit-down (from the measured pose), then passive.
  static void EnterSitDown(const RobotModel& m, const RobotData& d, LoopData& l, std::uint64_t tick) noexcept {
    MeasuredPose(m, d, l);
    Enter(l, Phase::kSitDown, tick);
    Ramp(m, l, 0, true);
  }

  // Whether this hold follows a walk (run after the last arming and the last passive): the stand
  // after the dead-man's release (or the command source's end).
  static bool AfterRelease(const LoopData& l) noexcept {
    const auto start = [&](Phase p) { return l.phase_start_[static_cast<std::size_t>(p)]; };
    return start(Phase::kRun) > start(Phase::kArming) && start(Phase::kRun) > start(Phase::kPassive);
  }

  // The fault a request is refused for while the supervisor holds the robot, or nullptr.
  static const char* Latched(const LoopData& l) noexcept {
    if (l.sup_.mode < Mode::kSafeStop) return nullptr;
    return l.sup_.mode == Mode::kEStop ? "e-stop is latched" : "safe-stop is latched";
  }

  // Why the phase does not take a sit request, or nullptr.
  static const char* NoSit(const LoopData& l) noexcept {
    if (l.phase_ != Phase::kStandUp && l.phase_ != Phase::kHold && l.phase_ != Phase::kRun) return "not standing";
    return Latched(l);
  }

  // Arm / disarm / stop requests, then the phase's own transitions and its command.
  static void Phases(const RobotModel& m, RobotData& d, LoopData& l, TickEvents ev) noexcept {
    // (OperatorRequests, in Tick, added the operator's requests to ev.)
    const std::uint64_t tick = d.tick;
    const bool motors = m.phases.enable_motors;
    if (!ev.stop) {
      const Phase before = l.phase_;
      Recover(m, d, l, ev);
      if (l.phase_ != before) ev.arm = true;  // re-armed: arm again from disarmed, below
    }
    for (std::size_t k = 0; k < m.motors.size(); ++k)
      if (d.fresh[m.motors[k].stream] != 0) l.answered_[k] = 1;
    if (ev.disarm && !motors && l.phase_ == Phase::kRun) Enter(l, Phase::kDisarmed, tick);
    const auto rose = [&ev](OperatorRequest r) {
      return ((static_cast<unsigned>(ev.operator_rises) >> static_cast<unsigned>(r)) & 1u) != 0;
    };
    if (rose(OperatorRequest::kArm) && !ev.stop) {
      if (l.phase_ != Phase::kDisarmed && l.phase_ != Phase::kPassive) {
        Refuse(l, tick, "arm", m.phases.sit_down_ticks > 0 ? "not disarmed or passive" : "not disarmed");
      } else if (Latched(l) != nullptr) {
        Refuse(l, tick, "arm", Latched(l));  // re-arm first (the recovery rule)
      }
    }
    if (ev.arm && l.phase_ == Phase::kPassive && Latched(l) == nullptr && !ev.stop) {
      MeasuredPose(m, d, l);  // stand up from where it sits
      EnterStandUp(m, l, tick);
    }
    if (rose(OperatorRequest::kSit) && !ev.stop) {
      if (const char* why = NoSit(l); why != nullptr) {
        Refuse(l, tick, "sit", why);
      } else {
        EnterSitDown(m, d, l, tick);
      }
    }
    if (ev.arm && l.phase_ == Phase::kDisarmed && Latched(l) == nullptr) {
      if (motors) {
        Enter(l, Phase::kArming, tick);
      } else {
        StartRun(m, d, l);
      }
    }
    // Arming is not supervised (the motors are not answering yet): an e-stop request there switches
    // them off at once, in motor-off, where the supervisor takes the request and latches e-stop.
    if (ev.estop && l.phase_ == Phase::kArming) Enter(l, Phase::kMotorOff, tick);
    if (ev.stop) {
      switch (l.phase_) {
        case Phase::kArming: Enter(l, Phase::kMotorOff, tick); break;
        case Phase::kDisarmed:
        case Phase::kStandUp:
        case Phase::kHold:
        case Phase::kRun:
        case Phase::kSitDown:
        case Phase::kPassive:
          Enter(l, !motors ? Phase::kDone : m.phases.damping_ticks > 0 ? Phase::kDamping : Phase::kMotorOff, tick);
          break;
        default: break;
      }
    }
    for (std::size_t k = 0; k < m.commands.size(); ++k) l.desired_[k] = m.commands[k].neutral;
    const std::uint64_t in_phase = tick - l.phase_start_[static_cast<std::size_t>(l.phase_)];
    const bool all = std::all_of(l.answered_.begin(), l.answered_.end(), [](std::uint8_t a) { return a != 0; });
    if (rose(OperatorRequest::kWalk) && l.phase_ != Phase::kHold) Refuse(l, tick, "walk", "not holding");
    if (rose(OperatorRequest::kSwitch)) {
      if (l.phase_ != Phase::kHold && l.phase_ != Phase::kRun) {
        Refuse(l, tick, "switch", "not holding or running");
      } else if (Latched(l) != nullptr) {
        Refuse(l, tick, "switch", Latched(l));
      } else if (l.source_ == nullptr || !l.source_->Switch()) {
        Refuse(l, tick, "switch", "one command source");
      }
    }
    switch (l.phase_) {
      case Phase::kArming:
        if (all) {
          MeasuredPose(m, d, l);
          for (const robot::MotorSpec& mo : m.motors) d.streams[mo.stream].age_ticks = 0;
          // Armed again by the recovery rule (disarmed and arming at the re-arm's tick): passive,
          // if the robot file says so.
          const RecoveryStatus& re = l.recovery_;
          if (m.op.rearm_to_passive && re.automatic + re.requested > 0 &&
              l.phase_start_[static_cast<std::size_t>(Phase::kDisarmed)] ==
                  l.phase_start_[static_cast<std::size_t>(Phase::kArming)]) {
            Enter(l, Phase::kPassive, tick);
          } else {
            EnterStandUp(m, l, tick);
          }
        } else if (in_phase >= m.phases.arming_timeout_ticks) {
          Enter(l, Phase::kFailed, tick);
        }
        break;
      case Phase::kStandUp:
        if (Ramp(m, l, in_phase, false)) Enter(l, Phase::kHold, tick);
        break;
      case Phase::kSitDown:
        if (Ramp(m, l, in_phase, true)) Enter(l, Phase::kPassive, tick);
        break;
      case Phase::kHold:
        if (l.source_ != nullptr && !l.source_done_ && in_phase >= m.phases.hold_ticks && ev.deadman &&
            (m.op.walk < 0 || ev.walk)) {
          StartRun(m, d, l);
        } else if (rose(OperatorRequest::kWalk)) {
          Refuse(l, tick, "walk",
                 !ev.deadman            ? "the dead-man is not held"
                 : l.source_ == nullptr ? "nothing to run"
                 : l.source_done_       ? "the command source has finished"
                                        : "hold_s is not over");
        } else if (m.op.deadman_sit_after_ticks > 0 && in_phase == m.op.deadman_sit_after_ticks && !ev.deadman &&
                   AfterRelease(l) && Latched(l) == nullptr) {
          EnterSitDown(m, d, l, tick);  // released and not held again: sit down, then passive
        }
        break;
      case Phase::kRun:
        if (!ev.deadman) {  // released: stand (a robot without motors disarms)
          if (motors) {
            MeasuredPose(m, d, l);
            EnterStandUp(m, l, tick);
          } else {
            Enter(l, Phase::kDisarmed, tick);
          }
          break;
        }
        if (l.source_ != nullptr && !l.source_->Compute(m, d, l, l.desired_)) {
          l.source_done_ = true;
          if (l.options_.shutdown_after_source) {
            Enter(l, motors ? Phase::kDamping : Phase::kDone, tick);
          } else if (motors) {
            Enter(l, Phase::kHold, tick);
          }
        }
        break;
      case Phase::kDamping:
        if (in_phase >= m.phases.damping_ticks) Enter(l, Phase::kMotorOff, tick);
        break;
      case Phase::kMotorOff:
        if (in_phase > 0 && (all || in_phase >= m.phases.motor_off_timeout_ticks)) Enter(l, Phase::kDone, tick);
        break;
      case Phase::kDisarmed:
        // Nothing is sent to the motors, so they do not answer (a motor replies to a command): their
        // silence is not judged until arming has them answering (as at arming's end). Nor is the
        // IMUs': a simulator in lock-step steps its plant, and so sends its IMU samples, only on the
        // commands it is sent (on a robot the IMU streams anyway, and is judged from arming on).
        if (motors) {
          for (const robot::MotorSpec& mo : m.motors) d.streams[mo.stream].age_ticks = 0;
          for (std::size_t s = 0; s < m.streams.size(); ++s)
            if (m.streams[s].kind == robot::StreamKind::kImu) d.streams[s].age_ticks = 0;
        }
        break;
      case Phase::kPassive:
      case Phase::kDone:
      case Phase::kFailed: break;
    }
    if (l.phase_ == Phase::kDamping || l.phase_ == Phase::kPassive)
      for (std::size_t k = 0; k < m.commands.size(); ++k) l.desired_[k] = StopValue(m, d, k);
  }

  // The stand-up (sit-down) ramp: a smoothstep from the measured pose to the default (sit) pose.
  // True at its end. Velocity-commanded motors (wheels) hold zero speed throughout (their neutral
  // commands).
  static bool Ramp(const RobotModel& m, LoopData& l, std::uint64_t in_phase, bool sit) noexcept {
    const std::uint32_t ticks = sit ? m.phases.sit_down_ticks : m.phases.stand_up_ticks;
    const double T = static_cast<double>(ticks) * m.tick_period_s;
    const double x = std::min(1.0, static_cast<double>(in_phase) / static_cast<double>(ticks));
    const double s = x * x * (3 - 2 * x), ds = 6 * x * (1 - x) / T;
    for (std::size_t k = 0; k < m.motors.size(); ++k) {
      const robot::MotorSpec& mo = m.motors[k];
      if (mo.velocity_commanded()) continue;
      const double target = sit ? mo.sit_q_rad : mo.default_q_rad;
      l.desired_[mo.q] = l.q0_[k] + (target - l.q0_[k]) * s;
      l.desired_[mo.dq] = (target - l.q0_[k]) * ds;
    }
    return x >= 1.0;
  }

  static void Supervise(const RobotModel& m, RobotData& d, LoopData& l, const rt::TickTiming& timing,
                        const TickEvents& ev) noexcept {
    const bool supervised = l.phase_ != Phase::kArming && l.phase_ != Phase::kFailed;
    if (supervised) {
      l.limit_signals_.Compute(d.fields, {}, l.limit_values_.data());
      const char* failure = l.source_ != nullptr && l.phase_ == Phase::kRun ? l.source_->failure() : nullptr;
      const safety::SupervisorInput in{.command = l.desired_,
                                       .inputs = d.fields,
                                       .streams = d.streams,
                                       .signals = l.limit_values_,
                                       .transports = d.transports,
                                       .consecutive_deadline_misses = timing.consecutive_misses,
                                       .inference_failed = failure != nullptr,
                                       .inference_status = failure != nullptr ? failure : "",
                                       .estop_request = ev.estop};
      const safety::Decision dec = safety::Supervise(m.supervisor_model, in, d.tick, l.sup_, d.command);
      constexpr std::uint32_t kFine = (1u << static_cast<unsigned>(safety::Cause::kCommandLimit)) |
                                      (1u << static_cast<unsigned>(safety::Cause::kRateLimit));
      if ((dec.causes & ~kFine) != 0) {
        l.healthy_ticks_ = 0;
      } else if (l.healthy_ticks_ < 0xffffffffu) {
        ++l.healthy_ticks_;
      }
      if (dec.transition && dec.cause_mode >= Mode::kSafeStop) {
        if (l.stopped_by_ == 0) ++l.recovery_.stops;  // the first rise to safe-stop or e-stop of this run
        l.stopped_by_ |= 1u << static_cast<unsigned>(dec.cause);
      }
      if (dec.transition) {
        if (l.mode_count_ < LoopData::kMaxChanges) {
          ModeChange& c = l.modes_[l.mode_count_];
          c.tick = d.tick;
          c.mode = l.sup_.mode;
          safety::Describe(m.supervisor_model, dec, c.reason, sizeof c.reason);
        }
        ++l.mode_count_;
      }
    } else {
      std::copy(l.desired_.begin(), l.desired_.end(), d.command.begin());
    }
    if (l.phase_ == Phase::kDisarmed) {  // nothing moves (the supervisor still watches and latches)
      for (std::size_t k = 0; k < m.commands.size(); ++k) d.command[k] = l.sup_.previous[k] = Idle(m, k);
    }
    d.mode = l.sup_.mode;
    // What each motor is sent.
    const std::uint64_t in_phase = d.tick - l.phase_start_[static_cast<std::size_t>(l.phase_)];
    for (std::size_t k = 0; k < m.motors.size(); ++k) {
      MotorCommand& mc = d.motors[k];
      switch (l.phase_) {
        case Phase::kDisarmed:
        case Phase::kDone: mc = MotorCommand::kNone; break;
        case Phase::kArming: mc = l.answered_[k] != 0 ? MotorCommand::kNone : MotorCommand::kEnable; break;
        case Phase::kFailed: mc = MotorCommand::kDisable; break;
        case Phase::kMotorOff:
          mc = in_phase > 0 && l.answered_[k] != 0 ? MotorCommand::kNone : MotorCommand::kDisable;
          break;
        default:  // e-stop: the motors off, or on with the damping commands (supervisor.estop: damping)
          mc = l.sup_.mode == Mode::kEStop && !m.supervisor_model.estop_damps ? MotorCommand::kDisable
                                                                              : MotorCommand::kCommand;
          break;
      }
    }
  }

  static double Idle(const RobotModel& m, std::size_t k) noexcept {
    const safety::CommandLimit& c = m.supervisor_model.commands[k];
    return std::clamp(0.0, c.min, c.max);
  }

  static void Publish(LoopData& l, const RobotData& d) noexcept {
    LoopStatus s;
    s.tick = d.tick;
    s.phase = l.phase_;
    s.mode = l.sup_.mode;
    const safety::Mode mode = l.sup_.mode;
    s.any_latched = mode != Mode::kNominal && l.sup_.entered[static_cast<std::size_t>(mode)].any;
    if (s.any_latched) s.latched = l.sup_.entered[static_cast<std::size_t>(mode)].cause;
    s.counts = l.sup_.counts;
    s.rearms = l.recovery_.automatic + l.recovery_.requested;
    s.refused = l.recovery_.refused;
    std::memcpy(s.recovery, l.recovery_.last, sizeof s.recovery);
    l.status_.Write(s);
  }

  static TickStatus Tick(const RobotModel& m, RobotData& d, LoopData& l, std::span<robot::Transport* const> transports,
                         const rt::TickTiming& timing) noexcept;
  static void Shutdown(const RobotModel& m, RobotData& d, LoopData& l, std::span<robot::Transport* const> transports,
                       std::uint64_t tick) noexcept;
};

void CheckSample(const RobotModel& m, RobotData& d, bool stopping) noexcept {
  for (std::size_t s = 0; s < m.streams.size(); ++s) {
    safety::StreamState& st = d.streams[s];
    bool judged = !stopping;
    for (std::size_t k = 0; k < m.motors.size() && !judged; ++k) judged = m.motors[k].stream == s;
    if (d.fresh[s] != 0) {
      st.seen = true;
      st.age_ticks = 0;
      ++d.samples[s];
    } else if (st.age_ticks < 0xffffffffu && judged) {
      ++st.age_ticks;
    }
    st.invalid_input = -1;
    if (!st.seen) continue;
    const robot::StreamSpec& spec = m.streams[s];
    // A command source silent for longer than zero_after: its command stops.
    if (spec.zero_after_ticks > 0 && st.age_ticks > spec.zero_after_ticks)
      std::fill_n(d.fields.begin() + spec.first_field, spec.field_count, 0.0);
    for (std::uint32_t f = spec.first_field; f < spec.first_field + spec.field_count; ++f) {
      const double v = d.fields[f];
      if (!(v >= m.fields[f].min && v <= m.fields[f].max)) {
        st.invalid_input = static_cast<std::int32_t>(f);
        st.invalid_value = v;
        break;
      }
    }
  }
}

TickStatus Tick(const RobotModel& m, RobotData& d, LoopData& l, std::span<robot::Transport* const> transports,
                const rt::TickTiming& timing) noexcept {
  return TickImpl::Tick(m, d, l, transports, timing);
}

void Shutdown(const RobotModel& m, RobotData& d, LoopData& l, std::span<robot::Transport* const> transports,
              std::uint64_t tick) noexcept {
  TickImpl::Shutdown(m, d, l, transports, tick);
}

TickStatus TickImpl::Tick(const RobotModel& m, RobotData& d, LoopData& l, std::span<robot::Transport* const> transports,
                          const rt::TickTiming& timing) noexcept {
  rt::TickProfiler& prof = l.profiler_;
  if (timing.missed) prof.CountDeadlineMiss();
  prof.Record(rt::Stage::kJitter, timing.jitter_ns);
  const std::int64_t t0 = MonotonicNs();
  d.tick = timing.tick;
  // Read.
  std::fill(d.fresh.begin(), d.fresh.end(), std::uint8_t{0});
  for (robot::Transport* t : transports) t->Read(m, d);
  TickEvents ev;
  ev.arm = l.arm_.exchange(false, std::memory_order_relaxed);
  ev.disarm = l.disarm_.exchange(false, std::memory_order_relaxed);
  ev.stop = l.stop_.load(std::memory_order_relaxed);
  ev.estop = l.estop_.load(std::memory_order_relaxed);
  ev.rearm = l.rearm_.exchange(false, std::memory_order_relaxed);
  if (l.recorder != nullptr) {
    // A rotated log's next file begins here, with the state this tick starts from.
    if (l.recorder->snapshot_due()) l.recorder->Snapshot(m, d, l);
    l.recorder->Inputs(m, d, timing, ev);
  }
  // Stopping, only the motors' replies are read (the source may have ended the run).
  CheckSample(m, d, l.phase_ == Phase::kDamping || l.phase_ == Phase::kMotorOff || l.phase_ == Phase::kDone);
  TickImpl::OperatorRequests(m, d, l, ev);
  const std::int64_t t1 = MonotonicNs();
  prof.Record(rt::Stage::kReceive, t1 - t0);
  // Observe, infer (the source, in the run phase), supervise.
  Phases(m, d, l, ev);
  const std::int64_t t2 = MonotonicNs();
  Supervise(m, d, l, timing, ev);
  const std::int64_t t3 = MonotonicNs();
  prof.Record(rt::Stage::kSupervise, t3 - t2);
  // Write.
  for (robot::Transport* t : transports) t->Write(m, d);
  if (l.recorder != nullptr) l.recorder->Outputs(m, d, l.phase_);
  const std::int64_t t4 = MonotonicNs();
  prof.Record(rt::Stage::kSend, t4 - t3);
  prof.Record(rt::Stage::kTick, t4 - timing.wake_ns);
  Publish(l, d);
  if (l.options_.stop_at_end_field && m.lockstep_end_field >= 0) {
    const auto f = static_cast<std::size_t>(m.lockstep_end_field);
    // The run ends: a robot with motors shuts down on its own ticks, one without stops its clock
    // (the runner sees ended()) and sends its stop command.
    if (d.fresh[m.fields[f].stream] != 0 && d.fields[f] >= 0.5) {
      l.ended_ = true;
      if (m.phases.enable_motors) l.RequestStop();
    }
  }
  if (l.phase_ == Phase::kDone) return TickStatus::kDone;
  if (l.phase_ == Phase::kFailed) return TickStatus::kFailed;
  return TickStatus::kRunning;
}

void TickImpl::Shutdown(const RobotModel& m, RobotData& d, LoopData& l, std::span<robot::Transport* const> transports,
                        std::uint64_t tick) noexcept {
  d.tick = tick;
  if (l.phase_ != Phase::kDone) Enter(l, Phase::kDone, tick);
  for (std::size_t k = 0; k < m.commands.size(); ++k) d.command[k] = Idle(m, k);
  std::fill(d.motors.begin(), d.motors.end(), MotorCommand::kDisable);
  d.mode = Mode::kEStop;
  for (robot::Transport* t : transports) t->Write(m, d);
  if (l.recorder != nullptr) l.recorder->Outputs(m, d, l.phase_);
}

}  // namespace pbppo::loop
