// The flat id -> codec table, built at set-up from the CAN map (runtime/robot/can_map.hpp), and
// the per-frame dispatcher that uses it in the tick: look up (bus, id), check the length, decode
// into the data. One table per role: the controller receives replies and IMU frames; a device
// emulator (HIL) receives commands. No allocation and no OS call after Build.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/can_map.hpp"
#include "runtime/transport/can/bus_stats.hpp"
#include "runtime/transport/can/can_frame.hpp"
#include "runtime/transport/can/imu_codec.hpp"
#include "runtime/transport/can/mit_codec.hpp"

namespace pbppo::can {

enum class CanRole : std::uint8_t { kController, kDevices };

enum class CodecKind : std::uint8_t {
  kNone = 0,
  kMitReply,    // controller side
  kImuClassic,  // controller side, sub = frame index 0..2
  kImuFd,       // controller side
  kMitCommand,  // device side (command or special frame)
};

struct CodecEntry {
  CodecKind kind = CodecKind::kNone;
  std::uint8_t sub = 0;
  std::uint16_t index = 0;  // motor or IMU index in the map
};

inline constexpr std::size_t kIdTableSize = kStandardIdMask + 1;

struct CanCodecTable {
  CanRole role = CanRole::kController;
  std::uint32_t bus_count = 0;
  std::vector<std::array<CodecEntry, kIdTableSize>> by_id;  // [bus][11-bit id]
  std::vector<std::vector<std::uint32_t>> rx_ids;           // per bus, sorted: the kernel filters
  // Per motor (map order).
  std::vector<MitRange> range;
  std::vector<std::uint32_t> motor_bus, motor_id, reply_id;
  // Per IMU.
  std::vector<std::uint32_t> imu_bus, imu_id;
  std::vector<robot::ImuFormat> imu_format;

  std::size_t motor_count() const noexcept { return range.size(); }
  std::size_t imu_count() const noexcept { return imu_bus.size(); }
  CodecEntry Lookup(std::uint32_t bus, const CanFrame& f) const noexcept {
    if (bus >= bus_count || (f.flags & (kFlagExtended | kFlagError | kFlagRtr)) != 0 || f.id > kStandardIdMask)
      return {};
    return by_id[bus][f.id];
  }
};

Result<CanCodecTable> BuildCodecTable(const robot::CanMap& map, CanRole role);

// What the dispatcher writes: the latest value of every device and how often it arrived.
struct CanRxData {
  std::vector<MitReply> reply;  // controller: per motor
  std::vector<std::uint64_t> reply_count;
  std::vector<MitCommand> command;  // devices: per motor
  std::vector<std::uint64_t> command_count;
  std::vector<std::uint8_t> last_special;  // devices: last MitSpecial byte per motor (0: none)
  std::vector<std::uint64_t> special_count;
  std::vector<ImuSample> imu;  // per IMU
  std::vector<std::uint64_t> imu_count;
  std::vector<ImuAssembler> imu_assembler;
};

CanRxData MakeCanRxData(const CanCodecTable& table);

enum class DispatchResult : std::uint8_t { kDecoded, kUnknownId, kWrongLength, kWrongMotorId, kPartial };

// Decodes one received frame into `data`, counting unknown ids and wrong lengths in `stats`
// (such frames are ignored). Error frames must not be passed here (the transport takes them).
DispatchResult DispatchFrame(const CanCodecTable& table, std::uint32_t bus, const CanFrame& frame, CanRxData& data,
                             BusStats& stats) noexcept;

}  // namespace pbppo::can
