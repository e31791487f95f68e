#include "sim_hil/quadruped_hil.hpp"

#include <algorithm>

#include "runtime/transport/can/socketcan.hpp"

namespace pbppo::sim {
namespace {
constexpr std::uint32_t kErrBusOff = 0x40;  // the bus-off error class (linux/can/error.h CAN_ERR_BUSOFF)
}  // namespace

const char* ToString(HilFaultKind kind) noexcept {
  switch (kind) {
    case HilFaultKind::kSilentMotor: return "silent-motor";
    case HilFaultKind::kImuSilent: return "imu-silent";
    case HilFaultKind::kDropFrames: return "drop-frames";
    case HilFaultKind::kBusOff: return "bus-off";
    case HilFaultKind::kPush: return "push";
  }
  return "?";
}

Result<std::unique_ptr<QuadrupedHil>> QuadrupedHil::Make(const robot::RobotModel& model,
                                                         const QuadrupedHilOptions& options) {
  if (!model.body || !model.can)
    return MakeError(ErrorCode::kMismatch, model.path + ": the quadruped HIL needs a description and a CAN map");
  const robot::RobotDescription& robot = *model.body;
  const robot::CanMap& map = *model.can;
  std::unique_ptr<QuadrupedHil> h(new QuadrupedHil());
  std::vector<std::string> interfaces = options.interfaces;
  if (interfaces.empty() && options.network == nullptr)
    for (const auto& b : map.buses) interfaces.push_back(b.interface);
  if (options.network != nullptr && options.network->bus_count() != map.buses.size())
    return MakeError(ErrorCode::kMismatch, "quadruped HIL: the in-process network has " +
                                               std::to_string(options.network->bus_count()) + " buses, the CAN map " +
                                               std::to_string(map.buses.size()));
  if (options.network == nullptr && interfaces.size() != map.buses.size())
    return MakeError(ErrorCode::kMismatch, "quadruped HIL: " + std::to_string(interfaces.size()) +
                                               " interfaces given, the CAN map has " +
                                               std::to_string(map.buses.size()) + " buses");
  if (map.motors.size() != robot.joint_count())
    return MakeError(ErrorCode::kMismatch, "quadruped HIL: the CAN map has " + std::to_string(map.motors.size()) +
                                               " motors, the robot " + std::to_string(robot.joint_count()) +
                                               " actuated joints");
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
  auto table = can::BuildCodecTable(map, can::CanRole::kDevices);
  if (!table.ok()) return std::move(table).error();
  h->table_ = std::move(*table);
  h->rx_data_ = can::MakeCanRxData(h->table_);
  h->per_bus_.assign(map.buses.size(), 0);
  for (std::size_t m = 0; m < map.motors.size(); ++m) {
    const robot::CanMotor& cm = map.motors[m];
    const auto it = std::find(robot.joint_names.begin(), robot.joint_names.end(), cm.joint);
    if (it == robot.joint_names.end())
      return MakeError(ErrorCode::kMismatch,
                       "quadruped HIL: CAN map motor '" + cm.joint + "' is not a joint of " + robot.urdf_path);
    const std::size_t j = static_cast<std::size_t>(it - robot.joint_names.begin());
    MitMotorConfig c;
    c.motor_id = cm.id;
    c.reply_id = cm.reply_id;
    c.range = map.range_of(cm);
    c.tau_limit_nm = std::min({robot.joint_at(j).effort_nm, c.range.t_max, -c.range.t_min});
    c.timeout_ticks = options.timeout_ticks;
    c.seed = options.seed + m;
    h->motors_.push_back(c);
    h->motor_state_.push_back(MakeMitMotorState(c));
    h->joint_of_motor_.push_back(j);
    ++h->per_bus_[cm.bus];
  }
  for (std::size_t i = 0; i < options.faults.size(); ++i) {
    const HilFault& f = options.faults[i];
    const std::string where = "quadruped HIL: faults[" + std::to_string(i) + "] (" + ToString(f.kind) + ")";
    if (i > 0 && f.tick < options.faults[i - 1].tick)
      return MakeError(ErrorCode::kInvalidValue, where + ": faults must be sorted by tick");
    if (f.kind == HilFaultKind::kSilentMotor && (f.motor < 0 || static_cast<std::size_t>(f.motor) >= map.motors.size()))
      return MakeError(ErrorCode::kInvalidValue,
                       where + ": motor " + std::to_string(f.motor) + " is not in the CAN map");
    if (f.kind == HilFaultKind::kBusOff && (f.bus < 0 || static_cast<std::size_t>(f.bus) >= map.buses.size()))
      return MakeError(ErrorCode::kInvalidValue, where + ": bus " + std::to_string(f.bus) + " is not in the CAN map");
    if (f.kind == HilFaultKind::kDropFrames && !(f.probability >= 0 && f.probability <= 1))
      return MakeError(ErrorCode::kInvalidValue,
                       where + ": probability " + std::to_string(f.probability) + " is not in [0, 1]");
    if (f.kind == HilFaultKind::kPush && !ground)
      return MakeError(ErrorCode::kInvalidValue, where + ": a push needs the ground mount");
  }
  h->faults_ = options.faults;
  h->network_ = options.network;
  for (std::size_t b = 0; b < map.buses.size(); ++b) {
    if (options.network != nullptr) {
      auto bus = options.network->Attach(b, h->table_.rx_ids[b], map.buses[b].fd, options.receive_all);
      if (!bus.ok()) return std::move(bus).error();
      h->buses_.push_back(std::move(*bus));
    } else {
      can::SocketCanOptions o;
      o.interface = interfaces[b];
      o.fd = map.buses[b].fd;
      o.rx_ids = h->table_.rx_ids[b];
      o.receive_all = options.receive_all;
      o.rcvbuf_bytes = 1 << 20;
      auto bus = can::SocketCanBus::Open(o);
      if (!bus.ok()) return std::move(bus).error();
      h->buses_.push_back(std::move(*bus));
    }
    h->rx_.emplace_back(256);
    h->tx_.emplace_back();
    h->tx_.back().reserve(256);
  }
  h->sent_last_.assign(map.buses.size(), 0);
  h->bus_off_.assign(map.buses.size(), 0);
  h->tau_.assign(robot.joint_count(), 0.0);
  if (!map.imus.empty()) {
    h->has_imu_ = true;
    h->imu_bus_ = map.imus[0].bus;
    h->imu_id_ = map.imus[0].id;
    if (map.imus[0].format != robot::ImuFormat::kClassic)
      return MakeError(ErrorCode::kUnsupported,
                       "quadruped HIL: imus[0] '" + map.imus[0].name + "'.format: only the classic format is emulated");
  }
  return h;
}

void QuadrupedHil::ApplyFaults() noexcept {
  while (next_fault_ < faults_.size() && faults_[next_fault_].tick <= tick_) {
    const HilFault& f = faults_[next_fault_++];
    switch (f.kind) {
      case HilFaultKind::kSilentMotor: motors_[static_cast<std::size_t>(f.motor)].silent_from_tick = tick_; break;
      case HilFaultKind::kImuSilent: imu_silent_ = true; break;
      case HilFaultKind::kDropFrames:
        for (MitMotorConfig& c : motors_) {
          c.drop_probability = f.probability;
          c.max_drop_burst = f.max_burst;
        }
        break;
      case HilFaultKind::kBusOff: {
        const auto b = static_cast<std::size_t>(f.bus);
        bus_off_[b] = 1;
        if (network_ != nullptr) {
          network_->SetBusOff(b, true);
        } else {  // SocketCAN: the controller reads a bus-off error frame, then silence
          can::CanFrame err;
          err.flags = can::kFlagError;
          err.id = kErrBusOff;
          err.len = 8;
          (void)buses_[b]->Send({&err, 1});
        }
        break;
      }
      case HilFaultKind::kPush: plant_->Push(f.velocity_mps[0], f.velocity_mps[1], f.velocity_mps[2]); break;
    }
  }
}

bool QuadrupedHil::Tick(const std::uint32_t* expect_per_bus, std::int64_t wait_ns) noexcept {
  ApplyFaults();
  const QuadrupedPlant& p = *plant_;
  for (std::size_t b = 0; b < buses_.size(); ++b) {
    tx_[b].clear();
    const std::size_t want = expect_per_bus != nullptr && bus_off_[b] == 0 ? expect_per_bus[b] : 0;
    const std::size_t n = buses_[b]->ReceiveAtLeast(rx_[b], want, wait_ns);
    if (bus_off_[b] != 0) continue;  // an off bus carries nothing
    for (std::size_t k = 0; k < n; ++k) {
      const can::CanFrame& f = rx_[b][k];
      if (f.error()) continue;
      const can::CodecEntry e = table_.Lookup(static_cast<std::uint32_t>(b), f);
      // The shared dispatcher checks identifier and length and counts strays.
      if (can::DispatchFrame(table_, static_cast<std::uint32_t>(b), f, rx_data_, buses_[b]->stats()) !=
              can::DispatchResult::kDecoded ||
          e.kind != can::CodecKind::kMitCommand)
        continue;
      const std::size_t m = e.index;
      const std::size_t j = joint_of_motor_[m];
      can::CanFrame reply;
      if (MitMotorReceive(motors_[m], motor_state_[m], f, tick_, p.q_rad(j), p.dq_rad_s(j), &reply))
        tx_[b].push_back(reply);
    }
  }
  for (std::size_t m = 0; m < motors_.size(); ++m) {
    const std::size_t j = joint_of_motor_[m];
    tau_[j] = MitMotorTorque(motors_[m], motor_state_[m], tick_, p.q_rad(j), p.dq_rad_s(j));
  }
  plant_->SetJointTorques(tau_.data(), tau_.size());
  const bool ok = plant_->Step();
  if (has_imu_ && !imu_silent_) {
    can::ImuSample s;
    p.BaseImu(s.quat_wxyz, s.gyro_rad_s, s.accel_m_s2);
    s.seq = imu_seq_++;
    s.status = can::kImuOrientationValid;
    can::CanFrame f[3];
    can::MakeImuClassicFrames(imu_id_, s, f);
    for (const auto& x : f) tx_[imu_bus_].push_back(x);
    ++imu_samples_;
  }
  for (std::size_t b = 0; b < buses_.size(); ++b)
    sent_last_[b] = bus_off_[b] != 0 ? 0 : static_cast<std::uint32_t>(buses_[b]->Send(tx_[b]));
  ++tick_;
  return ok;
}

}  // namespace pbppo::sim
