#include "sim_hil/can_devices.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "runtime/transport/can/socketcan.hpp"

namespace pbppo::sim {
namespace {
constexpr std::uint32_t kErrBusOff = 0x40;      // the bus-off error class (linux/can/error.h CAN_ERR_BUSOFF)
constexpr std::uint32_t kErrRestarted = 0x100;  // the controller restarted (CAN_ERR_RESTARTED)
}  // namespace

Result<std::unique_ptr<CanDevices>> CanDevices::Make(const robot::RobotModel& model, const CanDevicesOptions& options,
                                                     const std::string& who) {
  if (!model.body || !model.can)
    return MakeError(ErrorCode::kMismatch, model.path + ": the " + who + " needs a description and a CAN map");
  const robot::RobotDescription& robot = *model.body;
  const robot::CanMap& map = *model.can;
  std::unique_ptr<CanDevices> h(new CanDevices());
  std::vector<std::string> interfaces = options.interfaces;
  if (interfaces.empty() && options.network == nullptr)
    for (const auto& b : map.buses) interfaces.push_back(b.interface);
  if (options.network != nullptr && options.network->bus_count() != map.buses.size())
    return MakeError(ErrorCode::kMismatch, who + ": the in-process network has " +
                                               std::to_string(options.network->bus_count()) + " buses, the CAN map " +
                                               std::to_string(map.buses.size()));
  if (options.network == nullptr && interfaces.size() != map.buses.size())
    return MakeError(ErrorCode::kMismatch, who + ": " + std::to_string(interfaces.size()) +
                                               " interfaces given, the CAN map has " +
                                               std::to_string(map.buses.size()) + " buses");
  if (map.motors.size() != robot.joint_count())
    return MakeError(ErrorCode::kMismatch, who + ": the CAN map has " + std::to_string(map.motors.size()) +
                                               " motors, the robot " + std::to_string(robot.joint_count()) +
                                               " actuated joints");
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
                       who + ": CAN map motor '" + cm.joint + "' is not a joint of " + robot.urdf_path);
    const std::size_t j = static_cast<std::size_t>(it - robot.joint_names.begin());
    MitMotorConfig c;
    c.motor_id = cm.id;
    c.reply_id = cm.reply_id;
    c.range = map.range_of(cm);
    c.tau_limit_nm = std::min({robot.joint_at(j).effort_nm, c.range.t_max, -c.range.t_min});
    c.timeout_ticks = options.timeout_ticks;
    c.wrap_position = robot.joint_at(j).continuous();
    c.seed = options.seed + m;
    h->motors_.push_back(c);
    h->motor_state_.push_back(MakeMitMotorState(c));
    h->joint_of_motor_.push_back(j);
    ++h->per_bus_[cm.bus];
  }
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
  h->bad_reply_.assign(h->motors_.size(), 0);
  if (!map.imus.empty()) {
    h->has_imu_ = true;
    h->imu_bus_ = map.imus[0].bus;
    h->imu_id_ = map.imus[0].id;
    if (map.imus[0].format != robot::ImuFormat::kClassic)
      return MakeError(ErrorCode::kUnsupported,
                       who + ": imus[0] '" + map.imus[0].name + "'.format: only the classic format is emulated");
  }
  return h;
}

void CanDevices::DropFrames(double probability, std::uint32_t max_burst) noexcept {
  for (MitMotorConfig& c : motors_) {
    c.drop_probability = probability;
    c.max_drop_burst = max_burst;
  }
}

void CanDevices::SetBusOff(std::size_t b, bool off) noexcept {
  if ((bus_off_[b] != 0) == off) return;
  bus_off_[b] = off ? 1 : 0;
  if (network_ != nullptr) {
    network_->SetBusOff(b, off);
  } else {  // SocketCAN: the controller reads a bus-off (then silence) or a restarted error frame
    can::CanFrame err;
    err.flags = can::kFlagError;
    err.id = off ? kErrBusOff : kErrRestarted;
    err.len = 8;
    (void)buses_[b]->Send({&err, 1});
  }
}

void CanDevices::Receive(const std::uint32_t* expect_per_bus, std::int64_t wait_ns, const double* q, const double* dq,
                         std::uint64_t tick) noexcept {
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
      const double reported = bad_reply_[m] != 0 ? motors_[m].range.p_max : q[j];
      if (MitMotorReceive(motors_[m], motor_state_[m], f, tick, reported, dq[j], &reply)) tx_[b].push_back(reply);
    }
  }
}

void CanDevices::Torques(const double* q, const double* dq, std::uint64_t tick, double* tau) noexcept {
  for (std::size_t m = 0; m < motors_.size(); ++m) {
    const std::size_t j = joint_of_motor_[m];
    tau[j] = MitMotorTorque(motors_[m], motor_state_[m], tick, q[j], dq[j]);
  }
}

void CanDevices::Send(const can::ImuSample& imu) noexcept {
  if (has_imu_ && !imu_silent_) {
    can::ImuSample s = imu;
    s.seq = imu_seq_++;
    s.status = can::kImuOrientationValid;
    can::CanFrame f[3];
    can::MakeImuClassicFrames(imu_id_, s, f);
    for (const auto& x : f) tx_[imu_bus_].push_back(x);
    ++imu_samples_;
  }
  for (std::size_t b = 0; b < buses_.size(); ++b)
    sent_last_[b] = bus_off_[b] != 0 ? 0 : static_cast<std::uint32_t>(buses_[b]->Send(tx_[b]));
}

HilLoopResult RunHilLoop(const std::function<bool()>& tick, bool lockstep, std::int64_t period_ns,
                         std::uint64_t max_ticks, const std::atomic<bool>& stop) {
  HilLoopResult r;
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  const auto t0 = std::chrono::steady_clock::now();
  while (!stop.load() && (max_ticks == 0 || r.ticks < max_ticks)) {
    r.ok = tick();
    ++r.ticks;
    if (!lockstep) {
      next.tv_nsec += period_ns;
      while (next.tv_nsec >= 1'000'000'000) {
        next.tv_nsec -= 1'000'000'000;
        ++next.tv_sec;
      }
      timespec now{};
      clock_gettime(CLOCK_MONOTONIC, &now);
      if (now.tv_sec > next.tv_sec || (now.tv_sec == next.tv_sec && now.tv_nsec > next.tv_nsec)) ++r.overruns;
      clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    }
    if (!r.ok) break;
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

void PrintDeviceSummary(const CanDevices& devices, const robot::CanMap& map, const double* q) {
  for (std::size_t m = 0; m < devices.motor_count(); ++m) {
    const auto& s = devices.motor(m);
    std::printf("  %-7s frames %llu replies %llu dropped %llu watchdog %llu motor_mode %d q %.4f\n",
                map.motors[m].joint.c_str(), static_cast<unsigned long long>(s.frames),
                static_cast<unsigned long long>(s.replies), static_cast<unsigned long long>(s.dropped),
                static_cast<unsigned long long>(s.timeouts), s.motor_mode ? 1 : 0, q[devices.joint_of_motor(m)]);
  }
  for (std::size_t b = 0; b < devices.bus_count(); ++b) {
    const auto& s = devices.bus_stats(b);
    std::printf("  bus %s: rx %llu tx %llu unknown ids %llu wrong lengths %llu error frames %llu\n",
                devices.interface(b).c_str(), static_cast<unsigned long long>(s.rx_frames),
                static_cast<unsigned long long>(s.tx_frames), static_cast<unsigned long long>(s.unknown_ids),
                static_cast<unsigned long long>(s.wrong_lengths), static_cast<unsigned long long>(s.error_frames));
  }
}

}  // namespace pbppo::sim
