#include "sim_hil/quadruped_rig.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "report/plots.hpp"
#include "runtime/core/clock.hpp"
#include "runtime/policy/blob.hpp"

namespace pbppo::sim {

QuadrupedRig::~QuadrupedRig() = default;

Result<std::unique_ptr<QuadrupedRig>> QuadrupedRig::Make(const robot::RobotModel& model, QuadrupedHilOptions hil,
                                                         loop::Schedule schedule, const RigOptions& o) {
  if (!model.can) return MakeError(ErrorCode::kMismatch, model.path + ": the rig needs a CAN map");
  std::unique_ptr<QuadrupedRig> r(new QuadrupedRig(model));
  r->memory_ = o.interfaces.empty();
  r->wait_ns_ = r->memory_ ? 0 : o.wait_ns;
  if (r->memory_) {
    std::vector<std::string> names;
    for (const auto& b : model.can->buses) names.push_back(b.name);
    r->network_ = std::make_unique<can::MemoryCanNetwork>(names);
    hil.network = r->network_.get();
    hil.interfaces.clear();
  } else {
    hil.interfaces = o.interfaces;
  }
  auto h = QuadrupedHil::Make(model, hil);
  if (!h) return std::move(h).error();
  r->hil_ = std::move(*h);
  can::CanTransportOptions co;
  co.interfaces = o.interfaces;
  co.network = r->network_.get();
  co.command_record_capacity = o.command_record_capacity;
  auto c = can::CanTransport::Open(model, "can", co);
  if (!c) return std::move(c).error();
  r->can_ = std::move(*c);
  r->can_->SetLockStep(r->wait_ns_);
  auto s = loop::ScheduleTransport::Create(model, std::move(schedule));
  if (!s) return std::move(s).error();
  r->schedule_ = std::move(*s);
  auto src = loop::LoadSource(model, {o.policy, "", o.self_test, o.kernel, o.switch_policies});
  if (!src) return std::move(src).error();
  r->source_ = std::move(*src);
  r->data_ = robot::MakeRobotData(model);
  r->loop_ = loop::MakeLoopData(model, r->source_.source.get());
  r->transports_[0] = r->can_.get();
  r->transports_[1] = o.operator_transport != nullptr ? o.operator_transport : r->schedule_.get();
  r->supervise_deadlines_ = o.supervise_deadlines;
  r->arm_ = o.arm;
  r->trace_every_ = o.trace_every;
  if (o.realtime)
    r->clock_ =
        std::make_unique<rt::FreeRunningClock>(static_cast<std::int64_t>(std::llround(model.tick_period_s * 1e9)));
  const char* names[3] = {"command_vx", "command_vy", "command_yaw_rate"};
  for (int k = 0; k < 3; ++k) r->cmd_field_[k] = model.FieldIndex(names[k]);
  return r;
}

bool QuadrupedRig::Tick() noexcept {
  TickController();
  return TickPlant();
}

void QuadrupedRig::StartClock() noexcept {
  if (clock_) clock_->Start();
}

void QuadrupedRig::TickController() noexcept {
  std::uint32_t from_hil[8] = {};
  for (std::size_t b = 0; b < hil_->bus_count() && b < 8; ++b) from_hil[b] = hil_->sent_last_tick(b);
  can_->Expect({from_hil, hil_->bus_count()});
  rt::TickTiming timing;
  if (clock_) {
    (void)clock_->Wait(timing);
    if (!supervise_deadlines_) timing.consecutive_misses = 0;  // counted by the profiler, not acted on
  } else {
    timing.wake_ns = timing.deadline_ns = MonotonicNs();  // lock-step: the tick starts now
  }
  timing.tick = tick_;  // simulated time: one tick per tick, whatever the clock skipped
  const std::int64_t t0 = MonotonicNs();
  status_ = loop::Tick(model_, data_, *loop_, transports_, timing);
  last_tick_ns_ = MonotonicNs() - t0;
}

bool QuadrupedRig::TickPlant() noexcept {
  std::uint32_t from_ctl[8] = {};
  for (std::size_t b = 0; b < can_->bus_count() && b < 8; ++b) from_ctl[b] = can_->sent_last_tick(b);
  const bool ok = hil_->Tick(from_ctl, wait_ns_);
  if (trace_every_ == 0 || tick_ % trace_every_ != 0) {
    ++tick_;
    return ok;
  }
  // The trace.
  const QuadrupedPlant& p = hil_->plant();
  RigSample t;
  t.t_s = static_cast<double>(tick_ + 1) * model_.tick_period_s;
  FillBaseSample(p, &t);
  for (int k = 0; k < 3; ++k) {
    const double c =
        cmd_field_[k] >= 0 && data_.streams[model_.fields[static_cast<std::size_t>(cmd_field_[k])].stream].seen
            ? data_.fields[static_cast<std::size_t>(cmd_field_[k])]
            : 0.0;
    (k == 0 ? t.cmd_vx : k == 1 ? t.cmd_vy : t.cmd_yaw_rate) = static_cast<float>(c);
  }
  t.schedule_phase = schedule_->schedule().PhaseAt(static_cast<double>(tick_) * model_.tick_period_s);
  t.loop_phase = static_cast<std::uint8_t>(loop_->phase());
  t.mode = static_cast<std::uint8_t>(loop_->supervisor().mode);
  trace_.push_back(t);  // the harness's (RunSchedule reserves it); the controller's tick is above
  ++tick_;
  return ok;
}

bool QuadrupedRig::RunSchedule(double extra_s) {
  const auto total =
      static_cast<std::uint64_t>(std::llround((schedule_->schedule().duration_s() + extra_s) / model_.tick_period_s));
  if (trace_every_ != 0) trace_.reserve(trace_.size() + total / trace_every_ + 1);
  if (arm_) loop_->Arm();
  if (clock_) clock_->Start();
  while (tick_ < total) {
    if (!Tick()) return false;
    if (status_ != loop::TickStatus::kRunning) break;
  }
  return true;
}

RigReport QuadrupedRig::Report(double settle_s, bool by_command) const {
  return ReportOfTrace(trace_, schedule_->schedule(), settle_s, by_command);
}

void FillBaseSample(const QuadrupedPlant& p, RigSample* t) noexcept {
  const BaseState& b = p.base();
  const double w = b.quat_wxyz[0], x = b.quat_wxyz[1], y = b.quat_wxyz[2], z = b.quat_wxyz[3];
  // Rows of R (base to world): world = R base; base = R^T world.
  const double r00 = 1 - 2 * (y * y + z * z), r01 = 2 * (x * y - w * z);
  const double r10 = 2 * (x * y + w * z), r11 = 1 - 2 * (x * x + z * z);
  const double r20 = 2 * (x * z - w * y), r21 = 2 * (y * z + w * x), r22 = 1 - 2 * (x * x + y * y);
  const double* v = b.velocity_mps;
  t->x_m = static_cast<float>(b.position_m[0]);
  t->y_m = static_cast<float>(b.position_m[1]);
  t->z_m = static_cast<float>(b.position_m[2] - p.TerrainHeightAt(b.position_m[0], b.position_m[1]));
  t->yaw_rad = static_cast<float>(std::atan2(r10, r00));
  t->vx_mps = static_cast<float>(r00 * v[0] + r10 * v[1] + r20 * v[2]);
  t->vy_mps = static_cast<float>(r01 * v[0] + r11 * v[1] + r21 * v[2]);
  t->yaw_rate_radps = static_cast<float>(b.angular_radps[2]);
  t->tilt_rad = static_cast<float>(std::acos(std::clamp(r22, -1.0, 1.0)));
  t->feet = static_cast<std::uint8_t>(p.foot_contacts());
  t->body_contact = p.body_contact();
}

void PrintRigReport(const RigReport& r) {
  std::printf("%-10s %6s %6s | %8s %8s %8s | %8s %8s %8s\n", "phase", "from", "to", "cmd vx", "cmd vy", "cmd wz",
              "|e| vx", "|e| vy", "|e| wz");
  for (const PhaseTracking& p : r.phases) {
    if (p.samples == 0) {  // shorter than the settling time
      std::printf("%-10s %6.1f %6.1f | %8.2f %8.2f %8.2f | %26s\n", p.name.c_str(), p.start_s, p.end_s, p.command[0],
                  p.command[1], p.command[2], "(settling)");
      continue;
    }
    std::printf("%-10s %6.1f %6.1f | %8.2f %8.2f %8.2f | %8.3f %8.3f %8.3f\n", p.name.c_str(), p.start_s, p.end_s,
                p.command[0], p.command[1], p.command[2], p.mean_abs_error[0], p.mean_abs_error[1],
                p.mean_abs_error[2]);
  }
  std::printf("walked %.2f m; %s\n", r.distance_m,
              r.fell ? ("FELL at " + std::to_string(r.fell_at_s) + " s").c_str() : "no fall");
}

RigReport ReportOfTrace(const std::vector<RigSample>& trace, const loop::Schedule& s, double settle_s,
                        bool by_command) {
  RigReport rep;
  if (!by_command)
    for (const loop::SchedulePhase& ph : s.phases) {
      PhaseTracking t;
      t.name = ph.name;
      t.start_s = ph.start_s;
      t.end_s = ph.start_s + ph.duration_s;
      rep.phases.push_back(t);
    }
  // By command: a phase per command held at least kHeldS; the samples between (a ramp, a stick
  // moving) are in none.
  constexpr double kHeldS = 0.2;
  std::vector<std::int32_t> phase_of(by_command ? trace.size() : 0, -1);
  const auto same = [](const RigSample& a, const RigSample& b) {
    return a.cmd_vx == b.cmd_vx && a.cmd_vy == b.cmd_vy && a.cmd_yaw_rate == b.cmd_yaw_rate;
  };
  for (std::size_t i = 0, j = 0; by_command && i < trace.size(); i = j) {
    for (j = i + 1; j < trace.size() && same(trace[j], trace[i]);) ++j;
    if (trace[j - 1].t_s - trace[i].t_s < kHeldS && !(i == 0 && j == trace.size())) continue;
    PhaseTracking t;
    t.name = "command " + std::to_string(rep.phases.size() + 1);
    t.start_s = trace[i].t_s;
    t.end_s = trace[j - 1].t_s;
    t.command[0] = trace[i].cmd_vx;
    t.command[1] = trace[i].cmd_vy;
    t.command[2] = trace[i].cmd_yaw_rate;
    for (std::size_t k = i; k < j; ++k) phase_of[k] = static_cast<std::int32_t>(rep.phases.size());
    rep.phases.push_back(t);
  }
  for (std::size_t i = 0; i < trace.size(); ++i) {
    const RigSample& x = trace[i];
    // A fall: tilted beyond 60 degrees, or the body on the ground while the controller held or
    // walked. Elsewhere the body may rest on the ground: after a safe-stop the damped robot sits
    // down onto it (the safe state), as it does in passive after a sit-down and in the shutdown's
    // damping; re-armed, or armed from passive, it gets up from there in arming and stand-up.
    const bool stopped = x.mode >= static_cast<std::uint8_t>(safety::Mode::kSafeStop);
    const auto loop_phase = static_cast<loop::Phase>(x.loop_phase);
    const bool standing = loop_phase == loop::Phase::kHold || loop_phase == loop::Phase::kRun;
    if (!rep.fell && ((x.body_contact && !stopped && standing) || x.tilt_rad > 1.047f)) {
      rep.fell = true;
      rep.fell_at_s = x.t_s;
    }
    std::size_t phase = 0;
    if (by_command) {
      if (phase_of[i] < 0) continue;
      phase = static_cast<std::size_t>(phase_of[i]);
    } else {
      if (x.schedule_phase < 0) continue;
      phase = static_cast<std::size_t>(x.schedule_phase);
    }
    PhaseTracking& t = rep.phases[phase];
    if (x.t_s < t.start_s + settle_s) continue;
    const double cmd[3] = {static_cast<double>(x.cmd_vx), static_cast<double>(x.cmd_vy),
                           static_cast<double>(x.cmd_yaw_rate)};
    const double meas[3] = {static_cast<double>(x.vx_mps), static_cast<double>(x.vy_mps),
                            static_cast<double>(x.yaw_rate_radps)};
    for (int k = 0; k < 3; ++k) {
      t.command[k] = cmd[k];
      t.mean_abs_error[k] += std::fabs(cmd[k] - meas[k]);
      t.mean_measured[k] += meas[k];
    }
    ++t.samples;
  }
  for (PhaseTracking& t : rep.phases) {
    for (int k = 0; k < 3 && t.samples > 0; ++k) {
      t.mean_abs_error[k] /= static_cast<double>(t.samples);
      t.mean_measured[k] /= static_cast<double>(t.samples);
    }
    rep.max_planar_error = std::max({rep.max_planar_error, t.mean_abs_error[0], t.mean_abs_error[1]});
  }
  for (std::size_t i = 1; i < trace.size(); ++i)
    rep.distance_m += static_cast<double>(std::hypot(trace[i].x_m - trace[i - 1].x_m, trace[i].y_m - trace[i - 1].y_m));
  return rep;
}

Status WriteRigTrace(const std::vector<RigSample>& trace, const std::string& path, std::uint32_t every) {
  std::string text =
      "t_s,x_m,y_m,z_m,yaw_rad,vx_mps,vy_mps,yaw_rate_radps,cmd_vx,cmd_vy,cmd_yaw_rate,tilt_rad,schedule_phase,"
      "loop_phase,mode,feet,body_contact\n";
  char line[320];
  for (std::size_t i = 0; i < trace.size(); i += std::max<std::uint32_t>(every, 1)) {
    const RigSample& s = trace[i];
    std::snprintf(line, sizeof line, "%.3f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.3f,%.3f,%.3f,%.4f,%d,%d,%d,%d,%d\n",
                  s.t_s, static_cast<double>(s.x_m), static_cast<double>(s.y_m), static_cast<double>(s.z_m),
                  static_cast<double>(s.yaw_rad), static_cast<double>(s.vx_mps), static_cast<double>(s.vy_mps),
                  static_cast<double>(s.yaw_rate_radps), static_cast<double>(s.cmd_vx), static_cast<double>(s.cmd_vy),
                  static_cast<double>(s.cmd_yaw_rate), static_cast<double>(s.tilt_rad), s.schedule_phase, s.loop_phase,
                  s.mode, s.feet, s.body_contact ? 1 : 0);
    text += line;
  }
  return policy::WriteFileAtomic(path, {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()});
}

std::string PngStem(const std::string& png) {
  return png.size() > 4 && png.substr(png.size() - 4) == ".png" ? png.substr(0, png.size() - 4) : png;
}

Status PlotRigTrace(const std::vector<RigSample>& trace, const std::string& what, bool phases, const std::string& png,
                    std::uint32_t every) {
  static constexpr const char* kNames[3] = {"vx", "vy", "yaw rate"};
  const std::size_t step = std::max<std::uint32_t>(every, 1);
  report::TimeSeriesPlot ts;
  ts.title = what + ": commanded (dashed) and measured velocity";
  const char* labels[3] = {"vx [m/s]", "vy [m/s]", "yaw rate [rad/s]"};
  for (int k = 0; k < 3; ++k) {
    report::TimeSeriesPlot::Panel p;
    p.ylabel = labels[k];
    report::TimeSeriesPlot::Series cmd, meas;
    cmd.title = std::string("command ") + kNames[k];
    cmd.dashed = true;
    meas.title = std::string("measured ") + kNames[k];
    for (std::size_t i = 0; i < trace.size(); i += step) {
      const RigSample& s = trace[i];
      const double c[3] = {static_cast<double>(s.cmd_vx), static_cast<double>(s.cmd_vy),
                           static_cast<double>(s.cmd_yaw_rate)};
      const double m[3] = {static_cast<double>(s.vx_mps), static_cast<double>(s.vy_mps),
                           static_cast<double>(s.yaw_rate_radps)};
      cmd.x.push_back(static_cast<double>(s.t_s));
      cmd.y.push_back(c[k]);
      meas.x.push_back(static_cast<double>(s.t_s));
      meas.y.push_back(m[k]);
    }
    p.series = {cmd, meas};
    ts.panels.push_back(p);
  }
  if (phases) {  // an operator's requests move the phases: show them
    report::TimeSeriesPlot::Panel p;
    p.ylabel = "phase, mode";
    report::TimeSeriesPlot::Series phase, mode;
    phase.title = "phase (2 stand-up, 3 hold, 4 run, 9 sit-down, 10 passive)";
    mode.title = "mode (2 safe-stop, 3 e-stop)";
    mode.dashed = true;
    mode.group = 1;
    for (std::size_t i = 0; i < trace.size(); i += step) {
      const RigSample& s = trace[i];
      phase.x.push_back(static_cast<double>(s.t_s));
      phase.y.push_back(s.loop_phase);
      mode.x.push_back(static_cast<double>(s.t_s));
      mode.y.push_back(s.mode);
    }
    p.series = {phase, mode};
    ts.panels.push_back(p);
  }
  if (auto st = report::PlotTimeSeries(ts, png); !st) return st;
  report::MapPlot map;
  map.title = what + ": base path (top view)";
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  report::MapPlot::Path path;
  for (std::size_t i = 0; i < trace.size(); i += step) {
    const RigSample& s = trace[i];
    path.xy.push_back({static_cast<double>(s.x_m), static_cast<double>(s.y_m)});
    x0 = std::min(x0, static_cast<double>(s.x_m));
    x1 = std::max(x1, static_cast<double>(s.x_m));
    y0 = std::min(y0, static_cast<double>(s.y_m));
    y1 = std::max(y1, static_cast<double>(s.y_m));
  }
  map.paths.push_back(path);
  map.arena = {x0 - 0.5, x1 + 0.5, y0 - 0.5, y1 + 0.5};
  return report::PlotMap(map, PngStem(png) + "_path.png");
}

}  // namespace pbppo::sim
