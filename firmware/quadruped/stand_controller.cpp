#include "firmware/quadruped/stand_controller.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <set>
#include <sstream>

#include "runtime/core/clock.hpp"
#include "runtime/robot/text_file.hpp"
#include "runtime/robot/yaml_fields.hpp"

namespace pbppo::firmware {
namespace {

constexpr std::size_t kCmdFields = 5;  // q, dq, kp, kd, tau
constexpr std::size_t kFbFields = 2;   // q, dq
// Feedback beyond a joint limit by more than this is a fault (the stand has no hard stops).
constexpr double kFeedbackMarginRad = 0.3;

}  // namespace

const char* ToString(Phase phase) noexcept {
  switch (phase) {
    case Phase::kArming: return "arming";
    case Phase::kRamp: return "ramp";
    case Phase::kHold: return "hold";
    case Phase::kTrajectory: return "trajectory";
    case Phase::kShutdownDamping: return "shutdown-damping";
    case Phase::kMotorOff: return "motor-off";
    case Phase::kDone: return "done";
    case Phase::kFailed: return "failed";
  }
  return "?";
}

Result<Trajectory> ParseTrajectory(const std::string& yaml_text, const std::string& origin,
                                   const robot::RobotDescription& robot) {
  auto doc = robot::ParseYaml(yaml_text, origin);
  if (!doc) return std::move(doc).error();
  const YAML::Node root = *doc;
  const robot::YamlFields f(origin);
  constexpr double kInf = HUGE_VAL;
  if (auto st = f.Keys(root, "", {"duration_s", "joints"}); !st) return st.error();
  Trajectory t;
  if (auto st = f.Number(root, "duration_s", "", -kInf, kInf, &t.duration_s); !st) return st.error();
  if (!(t.duration_s > 0)) return f.Fail("duration_s", "is not positive");
  YAML::Node joints;
  if (auto st = f.List(root, "joints", "", true, &joints); !st) return st.error();
  if (joints.size() == 0) return f.Fail("joints", "is empty");
  std::set<std::string> seen;
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const YAML::Node j = joints[i];
    std::string where = "joints[" + std::to_string(i) + "]";
    if (auto st = f.Keys(j, where, {"joint", "amplitude_rad", "frequency_hz", "phase_rad"}); !st) return st.error();
    std::string name;
    if (auto st = f.Text(j, "joint", where, &name); !st) return st.error();
    where += " '" + name + "'";
    const auto it = std::find(robot.joint_names.begin(), robot.joint_names.end(), name);
    if (it == robot.joint_names.end()) return f.Fail(where + ".joint", "is not an actuated joint of the robot");
    if (!seen.insert(name).second) return f.Fail(where + ".joint", "listed twice");
    JointSinusoid s;
    s.joint = static_cast<std::uint32_t>(it - robot.joint_names.begin());
    for (const Status& st : {f.Number(j, "amplitude_rad", where, 0.0, kInf, &s.amplitude_rad),
                             f.Number(j, "frequency_hz", where, -kInf, kInf, &s.frequency_hz),
                             f.OptionalNumber(j, "phase_rad", where, -kInf, kInf, &s.phase_rad)}) {
      if (!st) return st.error();
    }
    if (!(s.frequency_hz > 0) || s.frequency_hz > 10) return f.Fail(where + ".frequency_hz", "is outside (0, 10] Hz");
    // The whole sinusoid must stay inside the joint's limits.
    const robot::UrdfJoint& uj = robot.joint_at(s.joint);
    const double centre = robot.default_q_rad[s.joint] - s.amplitude_rad * std::sin(s.phase_rad);
    if (centre - s.amplitude_rad < uj.lower_rad || centre + s.amplitude_rad > uj.upper_rad) {
      std::ostringstream ss;
      ss << "sweeps [" << centre - s.amplitude_rad << ", " << centre + s.amplitude_rad
         << "] rad, outside the joint's limits [" << uj.lower_rad << ", " << uj.upper_rad << "]";
      return f.Fail(where + ".amplitude_rad", ss.str());
    }
    t.joints.push_back(s);
  }
  return t;
}

Result<Trajectory> LoadTrajectory(const std::string& path, const robot::RobotDescription& robot) {
  auto text = robot::ReadTextFile(path);
  if (!text) return std::move(text).error();
  return ParseTrajectory(*text, std::filesystem::path(path).filename().string(), robot);
}

StandController::~StandController() = default;

Result<std::unique_ptr<StandController>> StandController::Make(const robot::RobotDescription& robot,
                                                               const robot::CanMap& map,
                                                               const StandControllerOptions& options) {
  std::unique_ptr<StandController> c(new StandController());
  c->robot_ = &robot;
  c->options_ = options;
  if (options.interfaces.size() != map.buses.size())
    return MakeError(ErrorCode::kMismatch, "controller: " + std::to_string(options.interfaces.size()) +
                                               " interfaces given, the CAN map has " +
                                               std::to_string(map.buses.size()) + " buses");
  if (map.motors.size() != robot.joint_count())
    return MakeError(ErrorCode::kMismatch, "controller: the CAN map has " + std::to_string(map.motors.size()) +
                                               " motors, the robot " + std::to_string(robot.joint_count()) +
                                               " actuated joints");
  auto table = can::BuildCodecTable(map, can::CanRole::kController);
  if (!table.ok()) return std::move(table).error();
  c->table_ = std::move(*table);
  c->rx_ = can::MakeCanRxData(c->table_);
  const std::size_t n = map.motors.size();
  c->motor_of_joint_.assign(n, 0);
  safety::SupervisorModel& sm = c->sup_model_;
  sm.channels = static_cast<std::uint32_t>(n);
  sm.command_fields = kCmdFields;
  sm.feedback_fields = kFbFields;
  sm.transports = static_cast<std::uint32_t>(map.buses.size());
  sm.command_field_names = {"q_rad", "dq_rad_s", "kp_nm_rad", "kd_nm_s_rad", "tau_ff_nm"};
  sm.feedback_field_names = {"q_rad", "dq_rad_s"};
  sm.transport_names = options.interfaces;
  for (std::size_t m = 0; m < n; ++m) {
    const auto it = std::find(robot.joint_names.begin(), robot.joint_names.end(), map.motors[m].joint);
    if (it == robot.joint_names.end())
      return MakeError(ErrorCode::kMismatch,
                       "controller: CAN map motor '" + map.motors[m].joint + "' is not a joint of " + robot.urdf_path);
    const std::size_t j = static_cast<std::size_t>(it - robot.joint_names.begin());
    c->joint_of_motor_.push_back(j);
    c->motor_of_joint_[j] = m;
    const robot::UrdfJoint& uj = robot.joint_at(j);
    const can::MitRange& r = map.range_of(map.motors[m]);
    const double tau = std::min({uj.effort_nm, r.t_max, -r.t_min});
    const double v = std::min({uj.velocity_rad_s, r.v_max, -r.v_min});
    sm.channel_names.push_back(map.motors[m].joint);
    for (double x : {std::max(uj.lower_rad, r.p_min), -v, std::max(0.0, r.kp_min), std::max(0.0, r.kd_min), -tau})
      sm.command_min.push_back(x);
    for (double x : {std::min(uj.upper_rad, r.p_max), v, r.kp_max, r.kd_max, tau}) sm.command_max.push_back(x);
    sm.feedback_min.push_back(uj.lower_rad - kFeedbackMarginRad);
    sm.feedback_min.push_back(-1.5 * v);
    sm.feedback_max.push_back(uj.upper_rad + kFeedbackMarginRad);
    sm.feedback_max.push_back(1.5 * v);
  }
  if (auto s = safety::ValidateSupervisorModel(sm); !s) return s.error();
  for (std::size_t b = 0; b < map.buses.size(); ++b) {
    can::SocketCanOptions o;
    o.interface = options.interfaces[b];
    o.fd = map.buses[b].fd;
    o.rx_ids = c->table_.rx_ids[b];
    o.receive_all = options.receive_all;
    o.rcvbuf_bytes = 1 << 20;
    auto bus = can::SocketCanBus::Open(o);
    if (!bus.ok()) return std::move(bus).error();
    c->buses_.push_back(std::move(*bus));
    c->rx_buf_.emplace_back(256);
    c->tx_buf_.emplace_back();
    c->tx_buf_.back().reserve(64);
  }
  if (!options.candump_path.empty()) {
    auto log = can::CandumpLogger::Open(options.candump_path, options.interfaces, 1 << 16);
    if (!log.ok()) return std::move(log).error();
    c->log_ = std::move(*log);
  }
  c->sent_last_.assign(map.buses.size(), 0);
  c->seen_replies_.assign(n, 0);
  c->frames_sent_.assign(n, 0);
  c->age_.assign(n, 0);
  c->answered_.assign(n, false);
  for (auto* v : {&c->q_, &c->dq_, &c->q0_, &c->q_des_, &c->dq_des_, &c->track_max_}) v->assign(n, 0.0);
  c->command_.assign(n * kCmdFields, 0.0);
  c->feedback_.assign(n * kFbFields, 0.0);
  c->health_.assign(map.buses.size(), {});
  c->last_stats_.assign(map.buses.size(), {});
  c->records_.reserve(options.command_record_capacity);
  return c;
}

void StandController::Stop() {
  if (log_) log_->Stop();
}

std::uint64_t StandController::candump_dropped() const noexcept {
  return log_ ? log_->dropped() : 0;
}

double StandController::rms_tracking_error_rad() const noexcept {
  return track_n_ == 0 ? 0.0 : std::sqrt(track_sq_ / static_cast<double>(track_n_ * q_.size()));
}

void StandController::Enter(Phase p) noexcept {
  phase_ = p;
  phase_start_[static_cast<std::size_t>(p)] = tick_;
  std::fill(answered_.begin(), answered_.end(), false);
}

void StandController::Tick(const std::uint32_t* expect_per_bus, std::int64_t wait_ns) noexcept {
  // 1. Receive and decode.
  for (std::size_t b = 0; b < buses_.size(); ++b) {
    const std::size_t want = expect_per_bus != nullptr ? expect_per_bus[b] : 0;
    const std::size_t got = buses_[b]->ReceiveAtLeast(rx_buf_[b], want, wait_ns);
    for (std::size_t k = 0; k < got; ++k) {
      const can::CanFrame& f = rx_buf_[b][k];
      if (log_) log_->Push(static_cast<std::uint32_t>(b), f);
      if (!f.error()) can::DispatchFrame(table_, static_cast<std::uint32_t>(b), f, rx_, buses_[b]->stats());
    }
    const can::BusStats& s = buses_[b]->stats();
    const can::BusStats& l = last_stats_[b];
    health_[b].fault = s.is_bus_off || s.rx_errors > l.rx_errors || s.tx_errors > l.tx_errors;
    health_[b].degraded =
        s.tx_dropped > l.tx_dropped || s.error_passive > l.error_passive || s.rx_dropped_kernel > l.rx_dropped_kernel;
    last_stats_[b] = s;
  }
  for (std::size_t m = 0; m < age_.size(); ++m) {
    const std::size_t j = joint_of_motor_[m];
    if (rx_.reply_count[m] != seen_replies_[m]) {
      seen_replies_[m] = rx_.reply_count[m];
      age_[m] = 0;
      answered_[m] = true;
      q_[j] = rx_.reply[m].q_rad;
      dq_[j] = rx_.reply[m].dq_rad_s;
    } else if (age_[m] < UINT32_MAX) {
      ++age_[m];
    }
  }
  // 2. Phase logic and commands.
  if (shutdown_requested_.load(std::memory_order_relaxed) &&
      (phase_ == Phase::kArming || phase_ == Phase::kRamp || phase_ == Phase::kHold || phase_ == Phase::kTrajectory))
    Enter(phase_ == Phase::kArming ? Phase::kMotorOff : Phase::kShutdownDamping);
  ComputeCommands();
  // 3. Send.
  SendCommands();
  ++tick_;
}

void StandController::ComputeCommands() noexcept {
  const robot::RobotDescription& r = *robot_;
  const double dt = options_.tick_s;
  const double t = static_cast<double>(tick_ - phase_start_[static_cast<std::size_t>(phase_)]) * dt;
  const std::size_t n = q_.size();
  switch (phase_) {
    case Phase::kArming:
      if (std::all_of(answered_.begin(), answered_.end(), [](bool a) { return a; })) {
        q0_ = q_;  // no allocation: same size
        Enter(Phase::kRamp);
        for (auto& a : age_) a = 0;
      } else if (tick_ - phase_start_[0] >= options_.arming_timeout_ticks) {
        Enter(Phase::kFailed);
      }
      break;
    case Phase::kRamp: {
      const double x = std::min(1.0, t / options_.ramp_s);
      const double s = x * x * (3 - 2 * x), ds = 6 * x * (1 - x) / options_.ramp_s;
      for (std::size_t j = 0; j < n; ++j) {
        q_des_[j] = q0_[j] + (r.default_q_rad[j] - q0_[j]) * s;
        dq_des_[j] = (r.default_q_rad[j] - q0_[j]) * ds;
      }
      if (x >= 1.0) Enter(Phase::kHold);
      break;
    }
    case Phase::kHold:
      for (std::size_t j = 0; j < n; ++j) {
        q_des_[j] = r.default_q_rad[j];
        dq_des_[j] = 0;
      }
      if (options_.has_trajectory && phase_start_[static_cast<std::size_t>(Phase::kTrajectory)] == 0 &&
          t >= options_.hold_s)
        Enter(Phase::kTrajectory);
      break;
    case Phase::kTrajectory: {
      for (std::size_t j = 0; j < n; ++j) {
        q_des_[j] = r.default_q_rad[j];
        dq_des_[j] = 0;
      }
      for (const JointSinusoid& s : options_.trajectory.joints) {
        const double w = 2 * std::numbers::pi * s.frequency_hz;
        q_des_[s.joint] += s.amplitude_rad * (std::sin(w * t + s.phase_rad) - std::sin(s.phase_rad));
        dq_des_[s.joint] = s.amplitude_rad * w * std::cos(w * t + s.phase_rad);
      }
      double sq = 0;
      for (std::size_t j = 0; j < n; ++j) {
        const double e = std::abs(q_[j] - q_des_[j]);
        track_max_[j] = std::max(track_max_[j], e);
        sq += e * e;
      }
      track_sq_ += sq;
      ++track_n_;
      if (t >= options_.trajectory.duration_s) {
        if (options_.shutdown_after_trajectory) {
          Enter(Phase::kShutdownDamping);
        } else {
          Enter(Phase::kHold);
        }
      }
      break;
    }
    case Phase::kShutdownDamping:
      if (t >= options_.damping_s) Enter(Phase::kMotorOff);
      break;
    case Phase::kMotorOff:
      if (tick_ > phase_start_[static_cast<std::size_t>(Phase::kMotorOff)] &&
          (std::all_of(answered_.begin(), answered_.end(), [](bool a) { return a; }) ||
           tick_ - phase_start_[static_cast<std::size_t>(Phase::kMotorOff)] >= options_.motor_off_timeout_ticks))
        Enter(Phase::kDone);
      break;
    case Phase::kDone:
    case Phase::kFailed: break;
  }
  // Command vector in the supervisor's layout (per motor).
  for (std::size_t m = 0; m < n; ++m) {
    const std::size_t j = joint_of_motor_[m];
    double* c = &command_[m * kCmdFields];
    if (phase_ == Phase::kShutdownDamping) {
      c[0] = std::clamp(q_[j], sup_model_.command_min[m * kCmdFields], sup_model_.command_max[m * kCmdFields]);
      c[1] = 0;
      c[2] = 0;
      c[3] = r.damping_kd_nm_s_rad;
      c[4] = 0;
    } else {
      c[0] = q_des_[j];
      c[1] = dq_des_[j];
      c[2] = r.kp_nm_rad;
      c[3] = r.kd_nm_s_rad;
      c[4] = 0;
    }
    feedback_[m * kFbFields] = q_[j];
    feedback_[m * kFbFields + 1] = dq_[j];
  }
}

void StandController::SendCommands() noexcept {
  const std::size_t n = q_.size();
  for (auto& v : tx_buf_) v.clear();
  const bool supervised = phase_ == Phase::kRamp || phase_ == Phase::kHold || phase_ == Phase::kTrajectory ||
                          phase_ == Phase::kShutdownDamping || phase_ == Phase::kMotorOff || phase_ == Phase::kDone;
  safety::Mode mode = sup_.mode;
  if (supervised) {
    const safety::SupervisorInput in{command_, feedback_, age_, health_, false};
    mode = safety::Step(sup_model_, in, tick_, sup_).mode;
  }
  clamped_fields_ += safety::LimitCommand(sup_model_, command_);
  const auto now = static_cast<std::uint64_t>(RealtimeNs());
  for (std::size_t m = 0; m < n; ++m) {
    const std::uint32_t id = table_.motor_id[m];
    can::CanFrame f;
    if (phase_ == Phase::kDone) continue;
    if (phase_ == Phase::kArming) {
      if (answered_[m]) continue;
      f = can::MakeMitSpecialFrame(id, can::MitSpecial::kEnterMotorMode);
    } else if (phase_ == Phase::kMotorOff || phase_ == Phase::kFailed || mode == safety::Mode::kEStop) {
      if (phase_ == Phase::kMotorOff && answered_[m] &&
          tick_ > phase_start_[static_cast<std::size_t>(Phase::kMotorOff)])
        continue;
      f = can::MakeMitSpecialFrame(id, can::MitSpecial::kExitMotorMode);
    } else {
      double* c = &command_[m * kCmdFields];
      if (mode == safety::Mode::kSafeStop) {  // damping: kp 0, kd damping, no feed-forward
        c[0] = std::clamp(q_[joint_of_motor_[m]], sup_model_.command_min[m * kCmdFields],
                          sup_model_.command_max[m * kCmdFields]);
        c[1] = 0;
        c[2] = 0;
        c[3] = robot_->damping_kd_nm_s_rad;
        c[4] = 0;
      }
      const can::MitCommand cmd{c[0], c[1], c[2], c[3], c[4]};
      f = can::MakeMitCommandFrame(id, table_.range[m], cmd);
      if (records_.size() < records_.capacity()) {
        records_.push_back(CommandRecord{tick_, static_cast<std::uint32_t>(m), c[0], c[1], c[2], c[3], c[4]});
      } else if (options_.command_record_capacity > 0) {
        ++records_dropped_;
      }
    }
    f.timestamp_ns = now;
    tx_buf_[table_.motor_bus[m]].push_back(f);
    ++frames_sent_[m];
  }
  for (std::size_t b = 0; b < buses_.size(); ++b) {
    sent_last_[b] = static_cast<std::uint32_t>(buses_[b]->Send(tx_buf_[b]));
    if (log_)
      for (const auto& f : tx_buf_[b]) log_->Push(static_cast<std::uint32_t>(b), f);
  }
}

}  // namespace pbppo::firmware
