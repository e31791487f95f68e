#include "runtime/transport/can/can_transport.hpp"

#include "runtime/core/clock.hpp"

namespace pbppo::can {

Result<std::vector<std::string>> ParseInterfaceList(const std::string& list) {
  std::vector<std::string> out;
  for (std::size_t at = 0; !list.empty();) {
    const std::size_t comma = list.find(',', at);
    out.push_back(list.substr(at, comma == std::string::npos ? std::string::npos : comma - at));
    if (out.back().empty())
      return MakeError(ErrorCode::kInvalidValue, "CAN interface list '" + list + "': an empty interface name");
    if (comma == std::string::npos) break;
    at = comma + 1;
  }
  return out;
}

Result<std::unique_ptr<CanTransport>> CanTransport::Open(const robot::RobotModel& m, const std::string& name,
                                                         const CanTransportOptions& o) {
  const int index = m.TransportIndex(name);
  if (index < 0 || m.transports[static_cast<std::size_t>(index)].kind != "can" || !m.can)
    return MakeError(ErrorCode::kMismatch, m.path + ": no CAN transport '" + name + "' with a can_map");
  const robot::CanMap& map = *m.can;
  std::unique_ptr<CanTransport> t(new CanTransport());
  t->first_link_ = m.transports[static_cast<std::size_t>(index)].first_link;
  // A copy moved in: copy-assigning draws a false -Wnull-dereference from GCC 12 for aarch64.
  t->interfaces_ = std::vector<std::string>(o.interfaces);
  if (o.network != nullptr) {
    if (o.network->bus_count() != map.buses.size())
      return MakeError(ErrorCode::kMismatch, "can: the in-process network has " +
                                                 std::to_string(o.network->bus_count()) + " buses, the CAN map " +
                                                 std::to_string(map.buses.size()));
    t->interfaces_.clear();
    for (std::size_t b = 0; b < map.buses.size(); ++b) t->interfaces_.push_back("mem:" + map.buses[b].name);
  }
  if (t->interfaces_.empty())
    for (const auto& b : map.buses) t->interfaces_.push_back(b.interface);
  if (t->interfaces_.size() != map.buses.size())
    return MakeError(ErrorCode::kMismatch, "can: " + std::to_string(t->interfaces_.size()) +
                                               " interfaces given, the CAN map has " +
                                               std::to_string(map.buses.size()) + " buses");
  auto table = BuildCodecTable(map, CanRole::kController);
  if (!table.ok()) return std::move(table).error();
  t->table_ = std::move(*table);
  t->rx_ = MakeCanRxData(t->table_);
  for (std::size_t b = 0; b < map.buses.size(); ++b) {
    SocketCanOptions so;
    so.interface = t->interfaces_[b];
    so.fd = map.buses[b].fd;
    so.rx_ids = t->table_.rx_ids[b];
    so.receive_all = o.receive_all;
    so.rcvbuf_bytes = 1 << 20;
    if (o.network != nullptr) {
      auto bus = o.network->Attach(b, so.rx_ids, so.fd, so.receive_all);
      if (!bus.ok()) return std::move(bus).error();
      t->buses_.push_back(std::move(*bus));
    } else {
      auto bus = SocketCanBus::Open(so);
      if (!bus.ok()) return std::move(bus).error();
      t->buses_.push_back(std::move(*bus));
    }
    t->rx_buf_.emplace_back(256);
    t->tx_buf_.emplace_back();
    t->tx_buf_.back().reserve(64);
  }
  if (!o.candump_path.empty()) {
    auto log = CandumpLogger::Open(o.candump_path, t->interfaces_, 1 << 16);
    if (!log.ok()) return std::move(log).error();
    t->log_ = std::move(*log);
  }
  const std::size_t buses = map.buses.size();
  t->sent_last_.assign(buses, 0);
  t->imu_frames_.assign(buses, 0);
  for (const robot::CanImu& u : map.imus) t->imu_frames_[u.bus] += u.format == robot::ImuFormat::kClassic ? 3 : 1;
  t->expect_.assign(buses, 0);
  t->seen_replies_.assign(map.motors.size(), 0);
  t->frames_sent_.assign(map.motors.size(), 0);
  t->have_q_.assign(map.motors.size(), 0);
  t->last_q_.assign(map.motors.size(), 0.0);
  t->turns_.assign(map.motors.size(), 0);
  t->seen_imu_.assign(map.imus.size(), 0);
  for (const robot::CanImu& u : map.imus) {
    const int s = m.StreamIndex(u.name);
    if (s < 0) return MakeError(ErrorCode::kMismatch, m.path + ": no stream for IMU '" + u.name + "'");
    t->imu_stream_.push_back(static_cast<std::uint32_t>(s));
    t->imu_first_field_.push_back(m.streams[static_cast<std::size_t>(s)].first_field);
  }
  t->last_stats_.assign(buses, {});
  t->record_capacity_ = o.command_record_capacity;
  t->records_.reserve(o.command_record_capacity);
  return t;
}

CanTransport::~CanTransport() {
  Stop();
}

void CanTransport::Stop() {
  if (log_) log_->Stop();
}

std::uint64_t CanTransport::candump_dropped() const noexcept {
  return log_ ? log_->dropped() : 0;
}

void CanTransport::Expect(std::span<const std::uint32_t> per_bus) noexcept {
  for (std::size_t b = 0; b < expect_.size() && b < per_bus.size(); ++b) expect_[b] = per_bus[b];
  expect_set_ = true;
}

double CanTransport::Unwrap(std::size_t motor, double q) noexcept {
  // Less than half the range between two replies (the model checks the motors' lost limit): a jump
  // of more than half the range is a wrap.
  const MitRange& r = table_.range[motor];
  const double span = r.p_max - r.p_min;
  if (have_q_[motor] != 0) {
    const double step = q - last_q_[motor];
    if (step > 0.5 * span) --turns_[motor];
    if (step < -0.5 * span) ++turns_[motor];
  }
  have_q_[motor] = 1;
  last_q_[motor] = q;
  return q + static_cast<double>(turns_[motor]) * span;
}

void CanTransport::Read(const robot::RobotModel& m, robot::RobotData& d) noexcept {
  std::uint32_t sent = 0;
  for (std::uint32_t s : sent_last_) sent += s;
  for (std::size_t b = 0; b < buses_.size(); ++b) {
    const std::size_t want =
        expect_set_ ? expect_[b] : (wait_ns_ > 0 ? sent_last_[b] + (sent > 0 ? imu_frames_[b] : 0) : 0);
    const std::int64_t wait = expect_set_ || wait_ns_ > 0 ? wait_ns_ : 0;
    const std::size_t got = buses_[b]->ReceiveAtLeast(rx_buf_[b], want, wait);
    for (std::size_t k = 0; k < got; ++k) {
      const CanFrame& f = rx_buf_[b][k];
      if (log_) log_->Push(static_cast<std::uint32_t>(b), f);
      if (!f.error()) DispatchFrame(table_, static_cast<std::uint32_t>(b), f, rx_, buses_[b]->stats());
    }
    const BusStats& s = buses_[b]->stats();
    const BusStats& l = last_stats_[b];
    safety::TransportHealth& h = d.transports[first_link_ + b];
    h.fault = s.is_bus_off || s.rx_errors > l.rx_errors || s.tx_errors > l.tx_errors;
    h.degraded =
        s.tx_dropped > l.tx_dropped || s.error_passive > l.error_passive || s.rx_dropped_kernel > l.rx_dropped_kernel;
    last_stats_[b] = s;
  }
  expect_set_ = false;
  for (std::size_t k = 0; k < m.motors.size(); ++k) {
    if (rx_.reply_count[k] == seen_replies_[k]) continue;
    seen_replies_[k] = rx_.reply_count[k];
    const robot::MotorSpec& mo = m.motors[k];
    d.fields[mo.q_field] = mo.continuous ? Unwrap(k, rx_.reply[k].q_rad) : rx_.reply[k].q_rad;
    d.fields[mo.dq_field] = rx_.reply[k].dq_rad_s;
    d.fields[mo.tau_field] = rx_.reply[k].tau_nm;
    d.fresh[mo.stream] = 1;
  }
  for (std::size_t u = 0; u < seen_imu_.size(); ++u) {
    if (rx_.imu_count[u] == seen_imu_[u]) continue;
    seen_imu_[u] = rx_.imu_count[u];
    const ImuSample& x = rx_.imu[u];
    double* f = &d.fields[imu_first_field_[u]];  // qw qx qy qz, gyro x y z, accel x y z (robot_model_devices.cpp)
    for (int i = 0; i < 4; ++i) f[i] = x.quat_wxyz[i];
    for (int i = 0; i < 3; ++i) f[4 + i] = x.gyro_rad_s[i];
    for (int i = 0; i < 3; ++i) f[7 + i] = x.accel_m_s2[i];
    d.fresh[imu_stream_[u]] = 1;
  }
}

void CanTransport::Write(const robot::RobotModel& m, robot::RobotData& d) noexcept {
  for (auto& v : tx_buf_) v.clear();
  const auto now = static_cast<std::uint64_t>(RealtimeNs());
  for (std::size_t k = 0; k < m.motors.size(); ++k) {
    const std::uint32_t id = table_.motor_id[k];
    CanFrame f;
    switch (d.motors[k]) {
      case robot::MotorCommand::kNone: continue;
      case robot::MotorCommand::kEnable: f = MakeMitSpecialFrame(id, MitSpecial::kEnterMotorMode); break;
      case robot::MotorCommand::kDisable: f = MakeMitSpecialFrame(id, MitSpecial::kExitMotorMode); break;
      case robot::MotorCommand::kCommand: {
        const robot::MotorSpec& mo = m.motors[k];
        // A velocity-commanded motor has no position target: p_des 0 and kp 0.
        const bool velocity = mo.velocity_commanded();
        const MitCommand c{velocity ? 0.0 : d.command[mo.q], d.command[mo.dq], velocity ? 0.0 : d.command[mo.kp],
                           d.command[mo.kd], d.command[mo.tau]};
        f = MakeMitCommandFrame(id, table_.range[k], c);
        if (records_.size() < record_capacity_) {
          records_.push_back(CommandRecord{d.tick, static_cast<std::uint32_t>(k), c.q_rad, c.dq_rad_s, c.kp_nm_rad,
                                           c.kd_nm_s_rad, c.tau_ff_nm});
        } else if (record_capacity_ > 0) {
          ++records_dropped_;
        }
        break;
      }
    }
    f.timestamp_ns = now;
    tx_buf_[table_.motor_bus[k]].push_back(f);
    ++frames_sent_[k];
  }
  for (std::size_t b = 0; b < buses_.size(); ++b) {
    sent_last_[b] = static_cast<std::uint32_t>(buses_[b]->Send(tx_buf_[b]));
    if (log_)
      for (const auto& f : tx_buf_[b]) log_->Push(static_cast<std::uint32_t>(b), f);
  }
}

}  // namespace pbppo::can
