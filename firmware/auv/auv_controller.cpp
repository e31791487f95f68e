#include "firmware/auv/auv_controller.hpp"

#include <cmath>

#include "runtime/policy/blob.hpp"
#include "runtime/robot/auv_signals.hpp"
#include "runtime/robot/yaml_fields.hpp"
#include "runtime/rt/tick_clock.hpp"

namespace pbppo::firmware {

Result<AuvControllerConfig> LoadAuvControllerConfig(const std::string& path) {
  auto doc = robot::LoadYamlFile(path);
  if (!doc) return std::move(doc).error();
  const YAML::Node root = *doc;
  const robot::YamlFields f(path);
  YAML::Node sim, task, sonar, sup;
  for (const Status& st : {f.Map(root, "simulation", "", &sim), f.Map(root, "task", "", &task),
                           f.Map(root, "sonar", "", &sonar), f.Map(root, "supervisor", "", &sup)}) {
    if (!st) return st.error();
  }
  AuvControllerConfig c;
  safety::AuvSupervisorConfig& s = c.supervisor;
  double accel = 0, yaw_accel = 0, stop = 0, stop_yaw = 0, beams = 0;
  std::array<double, 2> surge{}, depth{};
  const std::string S = "supervisor";
  for (const Status& st : {
           f.Number(sim, "control_period_s", "simulation", 1e-4, 10.0, &c.control_period_s),
           f.Number(task, "depth_m", "task", 0.0, 1e4, &c.depth_setpoint_m),
           f.Number(sonar, "beams", "sonar", 1, robot::kAuvMaxSonarBeams, &beams),
           f.Number(sonar, "max_range_m", "sonar", 0.1, 1000.0, &s.sonar_max_m),
           f.Range(sup, "surge_speed_mps", S, -10.0, 10.0, &surge),
           f.Number(sup, "yaw_rate_max_radps", S, 0.0, 10.0, &s.w_max_radps),
           f.Number(sup, "degraded_surge_max_mps", S, 0.0, 10.0, &s.degraded_v_max_mps),
           f.Number(sup, "surge_accel_max_mps2", S, 1e-6, 100.0, &accel),
           f.Number(sup, "yaw_accel_max_radps2", S, 1e-6, 100.0, &yaw_accel),
           f.Number(sup, "stop_decel_mps2", S, 1e-6, 1000.0, &stop),
           f.Number(sup, "stop_yaw_decel_radps2", S, 1e-6, 1000.0, &stop_yaw),
           f.Count(sup, "stale_degraded_ticks", S, 0, 1000000, &s.stale_degraded_ticks),
           f.Count(sup, "stale_safe_stop_ticks", S, 1, 1000000, &s.stale_safe_stop_ticks),
           f.Count(sup, "lost_peer_ticks", S, 1, 1000000, &s.lost_peer_ticks),
           f.Count(sup, "invalid_safe_stop", S, 1, 1000000, &s.invalid_safe_stop),
           f.Count(sup, "overrun_degraded", S, 1, 1000000, &s.overrun_degraded),
           f.Count(sup, "overrun_safe_stop", S, 1, 1000000, &s.overrun_safe_stop),
           f.Number(sup, "speed_max_mps", S, 0.0, 1e3, &s.speed_max_mps),
           f.Number(sup, "rate_max_radps", S, 0.0, 1e3, &s.rate_max_radps),
           f.Range(sup, "depth_range_m", S, -1e4, 1e5, &depth),
       }) {
    if (!st) return st.error();
  }
  s.v_min_mps = surge[0];
  s.v_max_mps = surge[1];
  s.depth_min_m = depth[0];
  s.depth_max_m = depth[1];
  s.sonar_beams = static_cast<std::uint32_t>(beams);
  s.sonar_max_m *= 1.0001;  // a range reading at exactly the maximum is valid
  s.dv_max_mps = accel * c.control_period_s;
  s.dw_max_radps = yaw_accel * c.control_period_s;
  s.stop_dv_mps = stop * c.control_period_s;
  s.stop_dw_radps = stop_yaw * c.control_period_s;
  char why[256];
  if (!safety::ValidateAuvSupervisorConfig(s, why, sizeof why))
    return MakeError(ErrorCode::kInvalidValue, path + ": " + why +
                                                   " (rates are the yaml's per-second values times "
                                                   "simulation.control_period_s)");
  return c;
}

AuvController::AuvController(AuvControllerConfig config, robot::IoLayout layout, policy::PolicyModel model,
                             robot::ObservationBuilder builder)
    : config_(std::move(config)), layout_(std::move(layout)), model_(std::move(model)), builder_(std::move(builder)) {}

AuvControllerConfig ForTickPeriod(const AuvControllerConfig& c, double tick_period_s) {
  AuvControllerConfig r = c;
  const double k = tick_period_s / c.control_period_s;  // ticks per control period = 1 / k
  auto periods = [&](std::uint32_t n) {
    return static_cast<std::uint32_t>(std::min(1e6, std::ceil(static_cast<double>(n) / k)));
  };
  // Ticking at the control period a sample's age is a whole number of periods, so "older than n
  // periods" means n samples missed. Ticking faster, a sample that is due every period arrives a
  // few ticks early or late; the limit is n and a half periods, so that a sample a little late
  // still counts as on time and a missed one does not (the same at the control period itself).
  auto missed = [&](std::uint32_t n) {
    return static_cast<std::uint32_t>(std::min(1e6, std::floor((static_cast<double>(n) + 0.5) / k + 1e-9)));
  };
  r.supervisor.stale_degraded_ticks = missed(c.supervisor.stale_degraded_ticks);
  r.supervisor.stale_safe_stop_ticks = missed(c.supervisor.stale_safe_stop_ticks);
  r.supervisor.lost_peer_ticks = periods(c.supervisor.lost_peer_ticks);
  r.supervisor.dv_max_mps = c.supervisor.dv_max_mps * k;
  r.supervisor.dw_max_radps = c.supervisor.dw_max_radps * k;
  r.supervisor.stop_dv_mps = c.supervisor.stop_dv_mps * k;
  r.supervisor.stop_dw_radps = c.supervisor.stop_dw_radps * k;
  return r;
}

Result<std::unique_ptr<AuvController>> AuvController::Create(const std::string& auv_yaml,
                                                             const std::string& io_layout_yaml,
                                                             const std::string& blob_path, double tick_period_s) {
  auto config = LoadAuvControllerConfig(auv_yaml);
  if (!config) return std::move(config).error();
  if (tick_period_s > 0) *config = ForTickPeriod(*config, tick_period_s);
  auto layout = robot::LoadIoLayout(io_layout_yaml);
  if (!layout) return std::move(layout).error();
  auto model = policy::PolicyModel::FromFile(blob_path);
  if (!model) return std::move(model).error();
  auto c = Create(*config, *layout, std::move(*model));
  if (!c) return MakeError(c.error().code, blob_path + " on " + io_layout_yaml + ": " + c.error().message);
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
