#include "firmware/auv/auv_controller.hpp"

#include <cmath>

#include "runtime/policy/blob.hpp"
#include "runtime/robot/auv_signals.hpp"
#include "runtime/rt/tick_clock.hpp"

namespace pbppo::firmware {

Result<AuvControllerConfig> AuvControllerConfigOf(const robot::RobotModel& m) {
  const int sensor = m.StreamIndex("sensor"), v = m.CommandIndex("surge_speed"), w = m.CommandIndex("yaw_rate");
  auto field = [&](const char* name) -> const robot::FieldSpec* {
    const int k = m.FieldIndex(name);
    return k < 0 ? nullptr : &m.fields[static_cast<std::size_t>(k)];
  };
  const robot::FieldSpec *beams = field("sonar_beams"), *sonar = field("sonar_0_m"), *surge = field("surge_mps"),
                         *rate = field("yaw_rate_radps"), *x = field("x_m"), *depth = field("depth_m");
  auto setpoint = m.Parameter("depth_m");
  if (sensor < 0 || v < 0 || w < 0 || !beams || !sonar || !surge || !rate || !x || !depth || !setpoint)
    return MakeError(ErrorCode::kMismatch, m.path +
                                               ": not the AUV (stream sensor, commands surge_speed and yaw_rate, "
                                               "the sample's fields and parameters.depth_m)");
  const robot::StreamSpec& st = m.streams[static_cast<std::size_t>(sensor)];
  const robot::CommandSpec &cv = m.commands[static_cast<std::size_t>(v)], &cw = m.commands[static_cast<std::size_t>(w)];
  AuvControllerConfig c;
  safety::AuvSupervisorConfig& s = c.supervisor;
  c.control_period_s = m.tick_period_s;
  c.depth_setpoint_m = *setpoint;
  s.v_min_mps = cv.min;
  s.v_max_mps = cv.max;
  s.w_max_radps = cw.max;
  s.degraded_v_max_mps = cv.degraded_max;
  s.dv_max_mps = cv.rate;
  s.dw_max_radps = cw.rate;
  s.stop_dv_mps = cv.stop_rate;
  s.stop_dw_radps = cw.stop_rate;
  s.stale_degraded_ticks = st.stale_degraded_ticks;
  s.stale_safe_stop_ticks = st.stale_safe_stop_ticks;
  s.lost_peer_ticks = st.lost_ticks;
  s.invalid_safe_stop = st.invalid_safe_stop;
  s.overrun_degraded = m.supervisor.overrun_degraded;
  s.overrun_safe_stop = m.supervisor.overrun_safe_stop;
  s.sonar_beams = static_cast<std::uint32_t>(beams->max);
  s.sonar_max_m = sonar->max;
  s.speed_max_mps = surge->max;
  s.rate_max_radps = rate->max;
  s.position_max_m = x->max;
  s.depth_min_m = depth->min;
  s.depth_max_m = depth->max;
  char why[256];
  if (!safety::ValidateAuvSupervisorConfig(s, why, sizeof why))
    return MakeError(ErrorCode::kInvalidValue, m.path + ": " + why);
  return c;
}

AuvController::AuvController(AuvControllerConfig config, robot::IoLayout layout, policy::PolicyModel model,
                             robot::ObservationBuilder builder)
    : config_(std::move(config)), layout_(std::move(layout)), model_(std::move(model)), builder_(std::move(builder)) {}

Result<std::unique_ptr<AuvController>> AuvController::Create(const robot::RobotModel& robot,
                                                             const std::string& blob_path, double tick_period_s) {
  auto ticking = robot::WithTickPeriod(robot, tick_period_s > 0 ? tick_period_s : robot.tick_period_s);
  if (!ticking) return std::move(ticking).error();
  auto config = AuvControllerConfigOf(*ticking);
  if (!config) return std::move(config).error();
  if (!robot.io) return MakeError(ErrorCode::kMismatch, robot.path + ": files: no io_layout");
  auto model = policy::PolicyModel::FromFile(blob_path);
  if (!model) return std::move(model).error();
  auto c = Create(*config, *robot.io, std::move(*model));
  if (!c) return MakeError(c.error().code, blob_path + " on " + robot.path + ": " + c.error().message);
  return c;
}

Result<std::unique_ptr<AuvController>> AuvController::Create(const AuvControllerConfig& config,
                                                             const robot::IoLayout& layout, policy::PolicyModel model) {
  char why[256];
  if (!safety::ValidateAuvSupervisorConfig(config.supervisor, why, sizeof why))
    return MakeError(ErrorCode::kInvalidValue, why);
  if (layout.robot != "auv")
    return MakeError(ErrorCode::kMismatch, "io layout: robot is '" + layout.robot + "', expected 'auv'");
  if (auto st = robot::CheckPolicyMatchesLayout(model.description(), layout); !st) return st.error();
  auto builder = robot::ObservationBuilder::Create(layout, robot::AuvSignalNames(config.supervisor.sonar_beams));
  if (!builder) return std::move(builder).error();
  std::int32_t v = -1, w = -1;
  for (std::size_t i = 0; i < layout.actions.size(); ++i) {
    const std::string& cmd = layout.actions[i].command;
    std::int32_t* slot = cmd == "surge_speed" ? &v : cmd == "yaw_rate" ? &w : nullptr;
    if (slot == nullptr || *slot >= 0)
      return MakeError(ErrorCode::kMismatch,
                       "io layout 'auv': actions[" + std::to_string(i) + "] '" + layout.actions[i].name +
                           "': command '" + cmd +
                           (slot == nullptr ? "' is not one of surge_speed, yaw_rate" : "' appears twice"));
    *slot = static_cast<std::int32_t>(i);
  }
  if (v < 0 || w < 0)
    return MakeError(ErrorCode::kMismatch,
                     std::string("io layout 'auv': no action with command ") + (v < 0 ? "surge_speed" : "yaw_rate"));
  std::unique_ptr<AuvController> c(new AuvController(config, layout, std::move(model), std::move(*builder)));
  auto data = policy::MakePolicyData(c->model_);
  if (!data) return std::move(data).error();
  c->data_.emplace(std::move(*data));
  c->v_index_ = static_cast<std::uint32_t>(v);
  c->w_index_ = static_cast<std::uint32_t>(w);
  c->signals_.assign(robot::kAuvSignalCapacity, 0.0);
  c->obs_.assign(c->builder_.observation_size(), 0.0f);
  return c;
}

void AuvController::Arm() noexcept {
  if (!armed_) first_armed_tick_ = true;
  armed_ = true;
}

bool AuvController::ResetSupervisor() noexcept {
  if (!safety::ResetAuvSupervisor(sup_, armed_)) return false;
  estop_request_.store(false, std::memory_order_relaxed);
  return true;
}

void AuvController::Tick(const robot::AuvSensorSample* latest, std::uint64_t tick, robot::AuvCommand& out) noexcept {
  const std::int64_t t0 = MonotonicNs();
  ++ticks_;
  // Observe: a new sample resets the age; the signal table through the IO layout.
  if (latest != nullptr && (!have_sample_ || latest->tick != sample_.tick || latest->stamp_ns != sample_.stamp_ns)) {
    sample_ = *latest;
    have_sample_ = true;
    sample_age_ = 0;
  } else if (sample_age_ < 0xffffffffu) {
    ++sample_age_;
  }
  const char* field = "";
  double value = 0;
  const bool valid = have_sample_ && safety::CheckAuvSample(config_.supervisor, sample_, &field, &value) == 0;
  if (armed_ && valid) {
    robot::AuvSignalsFromSample(sample_, config_.depth_setpoint_m, signals_.data());
    builder_.Build(signals_.data(), first_armed_tick_, obs_.data());
    first_armed_tick_ = false;
  }
  const std::int64_t t1 = MonotonicNs();
  // Infer (only armed, and only once an observation exists).
  double v = 0.0, w = 0.0;
  if (armed_ && !first_armed_tick_) {
    std::span<float> in = data_->observation();
    for (std::size_t i = 0; i < in.size(); ++i) in[i] = obs_[i];
    const policy::ForwardStatus fs = policy::Forward(model_, *data_);
    const std::span<const float> a = data_->action();
    v = static_cast<double>(a[v_index_]);
    w = static_cast<double>(a[w_index_]);
    if (fs != policy::ForwardStatus::kOk && std::isfinite(v) && std::isfinite(w)) v = std::nan("");
    ++policy_runs_;
  }
  const std::int64_t t2 = MonotonicNs();
  // Supervise.
  safety::AuvSupervisorInput in;
  in.v_mps = v;
  in.w_radps = w;
  in.sample = have_sample_ ? &sample_ : nullptr;
  in.sample_age_ticks = sample_age_;
  in.peer_lost = peer_lost_;
  in.consecutive_deadline_misses = deadline_misses_in_row_;
  in.estop_request = estop_request_.load(std::memory_order_relaxed);
  decision_ = safety::SuperviseAuv(config_.supervisor, in, sup_);
  sup_ = decision_.state;
  if (decision_.transition) {
    if (change_count_ < kMaxModeChanges) {
      ModeChange& c = changes_[change_count_];
      c.tick = tick;
      c.mode = sup_.mode;
      safety::DescribeAuv(decision_, c.reason, sizeof c.reason);
    }
    ++change_count_;
  }
  if (!armed_) {  // disarmed: nothing moves (the supervisor still watches and latches)
    sup_.v_mps = sup_.w_radps = 0.0;
    decision_.v_mps = decision_.w_radps = 0.0;
  }
  out.tick = tick;
  out.answers = have_sample_ ? sample_.tick : 0;
  out.surge_speed_mps = decision_.v_mps;
  out.yaw_rate_radps = decision_.w_radps;
  out.mode = static_cast<std::uint8_t>(sup_.mode);
  const std::int64_t t3 = MonotonicNs();
  out.stamp_ns = t3;
  profiler_.Record(rt::Stage::kObserve, t1 - t0);
  profiler_.Record(rt::Stage::kInfer, t2 - t1);
  profiler_.Record(rt::Stage::kSupervise, t3 - t2);
  robot::AuvControllerStatus st;
  st.tick = ticks_;
  st.mode = static_cast<std::uint8_t>(sup_.mode);
  st.cause = sup_.latched_cause;
  st.stale_samples = sup_.cause_ticks[4];
  st.invalid_samples = sup_.cause_ticks[3];
  st.limited_commands = sup_.cause_ticks[0] + sup_.cause_ticks[1];
  status_box_.Write(st);
}

void AuvController::ShutdownCommand(std::uint64_t tick, robot::AuvCommand& out) const noexcept {
  out.tick = tick;
  out.stamp_ns = MonotonicNs();
  out.answers = have_sample_ ? sample_.tick : 0;
  out.surge_speed_mps = 0.0;
  out.yaw_rate_radps = 0.0;
  out.mode = static_cast<std::uint8_t>(safety::AuvMode::kEStop);
}

robot::AuvControllerStatus AuvController::Status() const {
  robot::AuvControllerStatus s;
  (void)status_box_.Read(&s);  // version 0: no tick yet, the zero status
  s.deadline_misses = profiler_.deadline_misses();
  const rt::LatencyStats t = profiler_.histogram(rt::Stage::kTick).Snapshot().Stats();
  s.tick_median_us = static_cast<double>(t.p50_ns) / 1000.0;
  s.tick_max_us = static_cast<double>(t.max_ns) / 1000.0;
  return s;
}

}  // namespace pbppo::firmware
