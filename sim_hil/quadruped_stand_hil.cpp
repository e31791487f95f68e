#include "sim_hil/quadruped_stand_hil.hpp"

#include <algorithm>

namespace pbppo::sim {

Result<std::unique_ptr<StandHil>> StandHil::Make(const robot::RobotDescription& robot, const robot::CanMap& map,
                                                 const StandHilOptions& options) {
  std::unique_ptr<StandHil> h(new StandHil());
  if (options.interfaces.size() != map.buses.size())
    return MakeError(ErrorCode::kMismatch, "stand HIL: " + std::to_string(options.interfaces.size()) +
                                               " interfaces given, the CAN map has " +
                                               std::to_string(map.buses.size()) + " buses");
  auto plant = QuadrupedStandPlant::Make(robot);
  if (!plant.ok()) return std::move(plant).error();
  h->plant_ = std::move(*plant);
  if (!options.initial_q_rad.empty()) {
    if (auto s = h->plant_->Reset(options.initial_q_rad, std::vector<double>(robot.joint_count(), 0.0)); !s)
      return s.error();
  }
  auto table = can::BuildCodecTable(map, can::CanRole::kDevices);
  if (!table.ok()) return std::move(table).error();
  h->table_ = std::move(*table);
  h->rx_data_ = can::MakeCanRxData(h->table_);
  for (std::size_t m = 0; m < map.motors.size(); ++m) {
    const robot::CanMotor& cm = map.motors[m];
    const auto it = std::find(robot.joint_names.begin(), robot.joint_names.end(), cm.joint);
    if (it == robot.joint_names.end())
      return MakeError(ErrorCode::kMismatch,
                       "stand HIL: CAN map motor '" + cm.joint + "' is not a joint of " + robot.urdf_path);
    const std::size_t j = static_cast<std::size_t>(it - robot.joint_names.begin());
    MitMotorConfig c;
    c.motor_id = cm.id;
    c.reply_id = cm.reply_id;
    c.range = map.range_of(cm);
    c.tau_limit_nm = std::min({robot.joint_at(j).effort_nm, c.range.t_max, -c.range.t_min});
    c.timeout_ticks = options.timeout_ticks;
    c.drop_probability = options.drop_probability;
    c.max_drop_burst = options.max_drop_burst;
    c.seed = options.seed;
    if (static_cast<int>(m) == options.silent_motor) c.silent_from_tick = options.silent_from_tick;
    h->motors_.push_back(c);
    h->motor_state_.push_back(MakeMitMotorState(c));
    h->joint_of_motor_.push_back(j);
  }
  if (map.motors.size() != robot.joint_count())
    return MakeError(ErrorCode::kMismatch, "stand HIL: the CAN map has " + std::to_string(map.motors.size()) +
                                               " motors, the robot " + std::to_string(robot.joint_count()) +
                                               " actuated joints");
  for (std::size_t b = 0; b < map.buses.size(); ++b) {
    can::SocketCanOptions o;
    o.interface = options.interfaces[b];
    o.fd = map.buses[b].fd;
    o.rx_ids = h->table_.rx_ids[b];
    o.receive_all = options.receive_all;
    o.rcvbuf_bytes = 1 << 20;
    auto bus = can::SocketCanBus::Open(o);
    if (!bus.ok()) return std::move(bus).error();
    h->buses_.push_back(std::move(*bus));
    h->rx_.emplace_back(256);
    h->tx_.emplace_back();
    h->tx_.back().reserve(256);
  }
  h->sent_last_.assign(map.buses.size(), 0);
  h->tau_.assign(robot.joint_count(), 0.0);
  if (!map.imus.empty()) {
    h->has_imu_ = true;
    h->imu_bus_ = map.imus[0].bus;
    h->imu_id_ = map.imus[0].id;
    if (map.imus[0].format != robot::ImuFormat::kClassic)
      return MakeError(ErrorCode::kUnsupported,
                       "stand HIL: imus[0] '" + map.imus[0].name + "'.format: only the classic format is emulated");
  }
  return h;
}

bool StandHil::Tick(const std::uint32_t* expect_per_bus, std::int64_t wait_ns) noexcept {
  const QuadrupedStandPlant& p = *plant_;
  for (std::size_t b = 0; b < buses_.size(); ++b) {
    tx_[b].clear();
    const std::size_t want = expect_per_bus != nullptr ? expect_per_bus[b] : 0;
    const std::size_t n = buses_[b]->ReceiveAtLeast(rx_[b], want, wait_ns);
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
  if (has_imu_) {
    can::ImuSample s;
    p.BaseImu(s.quat_wxyz, s.gyro_rad_s, s.accel_m_s2);
    s.seq = imu_seq_++;
    s.status = can::kImuOrientationValid;
    can::CanFrame f[3];
    can::MakeImuClassicFrames(imu_id_, s, f);
    for (const auto& x : f) tx_[imu_bus_].push_back(x);
  }
  for (std::size_t b = 0; b < buses_.size(); ++b) sent_last_[b] = static_cast<std::uint32_t>(buses_[b]->Send(tx_[b]));
  ++tick_;
  return ok;
}

}  // namespace pbppo::sim
