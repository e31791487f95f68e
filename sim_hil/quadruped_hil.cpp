#include "sim_hil/quadruped_hil.hpp"

namespace pbppo::sim {

const char* ToString(HilFaultKind kind) noexcept {
  switch (kind) {
    case HilFaultKind::kSilentMotor: return "silent-motor";
    case HilFaultKind::kImuSilent: return "imu-silent";
    case HilFaultKind::kDropFrames: return "drop-frames";
    case HilFaultKind::kBusOff: return "bus-off";
    case HilFaultKind::kBusRestored: return "bus restored";
    case HilFaultKind::kMotorBack: return "motor back";
    case HilFaultKind::kImuBack: return "imu back";
    case HilFaultKind::kBadReplies: return "bad replies";
    case HilFaultKind::kGoodReplies: return "good replies";
    case HilFaultKind::kPush: return "push";
  }
  return "?";
}

Result<std::unique_ptr<QuadrupedHil>> QuadrupedHil::Make(const robot::RobotModel& model,
                                                         const QuadrupedHilOptions& options) {
  auto devices = CanDevices::Make(model, options, "quadruped HIL");
  if (!devices.ok()) return std::move(devices).error();
  const robot::RobotDescription& robot = *model.body;
  const robot::CanMap& map = *model.can;
  std::unique_ptr<QuadrupedHil> h(new QuadrupedHil());
  h->devices_ = std::move(*devices);
  auto plant = QuadrupedPlant::Make(robot, options.plant);
  if (!plant.ok()) return std::move(plant).error();
  h->plant_ = std::move(*plant);
  const bool ground = options.plant.mount == Mount::kGround;
  std::vector<double> q0 = options.initial_q_rad;
  if (q0.empty()) q0 = ground ? robot.default_q_rad : std::vector<double>(robot.joint_count(), 0.0);
  if (auto s =
          h->plant_->Reset(q0, std::vector<double>(robot.joint_count(), 0.0), options.base_xyz, options.base_yaw_rad);
      !s)
    return s.error();
  for (std::size_t i = 0; i < options.faults.size(); ++i) {
    const HilFault& f = options.faults[i];
    const std::string where = "quadruped HIL: faults[" + std::to_string(i) + "] (" + ToString(f.kind) + ")";
    if (i > 0 && f.tick < options.faults[i - 1].tick)
      return MakeError(ErrorCode::kInvalidValue, where + ": faults must be sorted by tick");
    const bool motor_fault = f.kind == HilFaultKind::kSilentMotor || f.kind == HilFaultKind::kMotorBack ||
                             f.kind == HilFaultKind::kBadReplies || f.kind == HilFaultKind::kGoodReplies;
    if (motor_fault && (f.motor < 0 || static_cast<std::size_t>(f.motor) >= map.motors.size()))
      return MakeError(ErrorCode::kInvalidValue,
                       where + ": motor " + std::to_string(f.motor) + " is not in the CAN map");
    if ((f.kind == HilFaultKind::kBusOff || f.kind == HilFaultKind::kBusRestored) &&
        (f.bus < 0 || static_cast<std::size_t>(f.bus) >= map.buses.size()))
      return MakeError(ErrorCode::kInvalidValue, where + ": bus " + std::to_string(f.bus) + " is not in the CAN map");
    if (f.kind == HilFaultKind::kDropFrames && !(f.probability >= 0 && f.probability <= 1))
      return MakeError(ErrorCode::kInvalidValue,
                       where + ": probability " + std::to_string(f.probability) + " is not in [0, 1]");
    if (f.kind == HilFaultKind::kPush && !ground)
      return MakeError(ErrorCode::kInvalidValue, where + ": a push needs the ground mount");
  }
  h->faults_ = options.faults;
  for (auto* v : {&h->q_, &h->dq_, &h->tau_}) v->assign(robot.joint_count(), 0.0);
  return h;
}

void QuadrupedHil::ApplyFaults() noexcept {
  while (next_fault_ < faults_.size() && faults_[next_fault_].tick <= tick_) {
    const HilFault& f = faults_[next_fault_++];
    switch (f.kind) {
      case HilFaultKind::kSilentMotor: devices_->SilenceMotor(static_cast<std::size_t>(f.motor), tick_); break;
      case HilFaultKind::kImuSilent: devices_->SilenceImu(true); break;
      case HilFaultKind::kImuBack: devices_->SilenceImu(false); break;
      case HilFaultKind::kMotorBack: devices_->RestoreMotor(static_cast<std::size_t>(f.motor)); break;
      case HilFaultKind::kBadReplies: devices_->BadReplies(static_cast<std::size_t>(f.motor), true); break;
      case HilFaultKind::kGoodReplies: devices_->BadReplies(static_cast<std::size_t>(f.motor), false); break;
      case HilFaultKind::kDropFrames: devices_->DropFrames(f.probability, f.max_burst); break;
      case HilFaultKind::kBusOff: devices_->SetBusOff(static_cast<std::size_t>(f.bus), true); break;
      case HilFaultKind::kBusRestored: devices_->SetBusOff(static_cast<std::size_t>(f.bus), false); break;
      case HilFaultKind::kPush: plant_->Push(f.velocity_mps[0], f.velocity_mps[1], f.velocity_mps[2]); break;
    }
  }
}

bool QuadrupedHil::Tick(const std::uint32_t* expect_per_bus, std::int64_t wait_ns) noexcept {
  ApplyFaults();
  const QuadrupedPlant& p = *plant_;
  for (std::size_t j = 0; j < q_.size(); ++j) {
    q_[j] = p.q_rad(j);
    dq_[j] = p.dq_rad_s(j);
  }
  devices_->Receive(expect_per_bus, wait_ns, q_.data(), dq_.data(), tick_);
  devices_->Torques(q_.data(), dq_.data(), tick_, tau_.data());
  plant_->SetJointTorques(tau_.data(), tau_.size());
  const bool ok = plant_->Step();
  can::ImuSample s;
  if (devices_->has_imu()) p.BaseImu(s.quat_wxyz, s.gyro_rad_s, s.accel_m_s2);
  devices_->Send(s);
  ++tick_;
  return ok;
}

}  // namespace pbppo::sim
