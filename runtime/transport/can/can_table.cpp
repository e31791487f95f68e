#include "runtime/transport/can/can_table.hpp"

#include <algorithm>
#include <cstdio>

namespace pbppo::can {
namespace {

std::string Hex(std::uint32_t v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%03X", v);
  return b;
}

}  // namespace

Result<CanCodecTable> BuildCodecTable(const robot::CanMap& map, CanRole role) {
  CanCodecTable t;
  t.role = role;
  t.bus_count = static_cast<std::uint32_t>(map.buses.size());
  t.by_id.assign(map.buses.size(), {});
  t.rx_ids.assign(map.buses.size(), {});
  if (map.motors.size() > 0xFFFF || map.imus.size() > 0xFFFF)
    return MakeError(ErrorCode::kLimit, "can map '" + map.robot + "': more than 65535 motors or IMUs");
  auto put = [&](std::uint32_t bus, std::uint32_t id, CodecEntry e, const std::string& who) -> Status {
    if (bus >= t.bus_count) return MakeError(ErrorCode::kInvalidValue, who + ": bus index out of range");
    if (id > kStandardIdMask)
      return MakeError(ErrorCode::kInvalidValue, who + ": identifier " + Hex(id) + " is not 11-bit");
    CodecEntry& slot = t.by_id[bus][id];
    if (slot.kind != CodecKind::kNone)
      return MakeError(ErrorCode::kInvalidValue, who + ": identifier " + Hex(id) + " on bus '" + map.buses[bus].name +
                                                     "' is already in the table");
    slot = e;
    t.rx_ids[bus].push_back(id);
    return {};
  };
  for (std::size_t i = 0; i < map.motors.size(); ++i) {
    const robot::CanMotor& m = map.motors[i];
    if (m.actuator >= map.actuators.size())
      return MakeError(ErrorCode::kInvalidValue, "motor '" + m.joint + "': actuator index out of range");
    t.range.push_back(map.range_of(m));
    t.motor_bus.push_back(m.bus);
    t.motor_id.push_back(m.id);
    t.reply_id.push_back(m.reply_id);
    const auto idx = static_cast<std::uint16_t>(i);
    const std::string who = "motor '" + m.joint + "'";
    if (role == CanRole::kController) {
      if (auto st = put(m.bus, m.reply_id, {CodecKind::kMitReply, 0, idx}, who + ".reply_id"); !st) return st.error();
    } else {
      if (auto st = put(m.bus, m.id, {CodecKind::kMitCommand, 0, idx}, who + ".id"); !st) return st.error();
    }
  }
  for (std::size_t i = 0; i < map.imus.size(); ++i) {
    const robot::CanImu& u = map.imus[i];
    t.imu_bus.push_back(u.bus);
    t.imu_id.push_back(u.id);
    t.imu_format.push_back(u.format);
    if (role != CanRole::kController) continue;
    const auto idx = static_cast<std::uint16_t>(i);
    const std::string who = "IMU '" + u.name + "'";
    if (u.format == robot::ImuFormat::kFd) {
      if (auto st = put(u.bus, u.id, {CodecKind::kImuFd, 0, idx}, who + ".id"); !st) return st.error();
    } else {
      for (std::uint8_t k = 0; k < 3; ++k) {
        if (auto st = put(u.bus, u.id + k, {CodecKind::kImuClassic, k, idx}, who + ".id"); !st) return st.error();
      }
    }
  }
  for (auto& ids : t.rx_ids) std::sort(ids.begin(), ids.end());
  return t;
}

CanRxData MakeCanRxData(const CanCodecTable& table) {
  CanRxData d;
  d.reply.assign(table.motor_count(), {});
  d.reply_count.assign(table.motor_count(), 0);
  d.command.assign(table.motor_count(), {});
  d.command_count.assign(table.motor_count(), 0);
  d.last_special.assign(table.motor_count(), 0);
  d.special_count.assign(table.motor_count(), 0);
  d.imu.assign(table.imu_count(), {});
  d.imu_count.assign(table.imu_count(), 0);
  d.imu_assembler.assign(table.imu_count(), {});
  return d;
}

DispatchResult DispatchFrame(const CanCodecTable& t, std::uint32_t bus, const CanFrame& f, CanRxData& d,
                             BusStats& stats) noexcept {
  const CodecEntry e = t.Lookup(bus, f);
  auto wrong_length = [&stats] {
    ++stats.wrong_lengths;
    return DispatchResult::kWrongLength;
  };
  // A frame taken and its device's sample complete: counted for both.
  auto decoded = [&stats](std::uint64_t* count) {
    ++*count;
    ++stats.decoded;
    return DispatchResult::kDecoded;
  };
  switch (e.kind) {
    case CodecKind::kNone: break;
    case CodecKind::kMitReply: {
      MitReply r;
      if (!DecodeMitReply(t.range[e.index], f.data, f.len, &r)) return wrong_length();
      if (r.motor_id != t.motor_id[e.index]) {
        ++stats.wrong_motor_id;
        return DispatchResult::kWrongMotorId;
      }
      d.reply[e.index] = r;
      return decoded(&d.reply_count[e.index]);
    }
    case CodecKind::kMitCommand: {
      if (f.len != kMitCommandLen) return wrong_length();
      MitSpecial special{};
      if (!DecodeMitSpecial(f.data, f.len, &special)) {
        DecodeMitCommand(t.range[e.index], f.data, f.len, &d.command[e.index]);
        return decoded(&d.command_count[e.index]);
      }
      d.last_special[e.index] = static_cast<std::uint8_t>(special);
      return decoded(&d.special_count[e.index]);
    }
    case CodecKind::kImuFd:
      if (!DecodeImuFd(f.data, f.len, &d.imu[e.index])) return wrong_length();
      return decoded(&d.imu_count[e.index]);
    case CodecKind::kImuClassic:
      if (f.len != kImuClassicLen) return wrong_length();
      // Each of the three frames is taken; the third completes a sample.
      if (FeedImuClassic(d.imu_assembler[e.index], e.sub, f.data, f.len, &d.imu[e.index]))
        return decoded(&d.imu_count[e.index]);
      ++stats.decoded;  // taken; the sample is not complete yet
      return DispatchResult::kPartial;
  }
  ++stats.unknown_ids;
  return DispatchResult::kUnknownId;
}

}  // namespace pbppo::can
