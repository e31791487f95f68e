// MIT (mini-cheetah) motor protocol: pure, allocation-free encode/decode of the 8-byte command
// frame, the 6-byte reply frame and the special mode frames. No OS headers; the HIL simulator's
// motor emulators use the same functions. Layout (big-endian, bit-packed), see docs/can.md:
//
//   command (id = motor id, 8 bytes)  p[15:8] | p[7:0] | v[11:4] | v[3:0] kp[11:8] | kp[7:0] |
//                                     kd[11:4] | kd[3:0] t[11:8] | t[7:0]
//   reply (id = reply id, 6 bytes)    motor_id | p[15:8] | p[7:0] | v[11:4] | v[3:0] i[11:8] | i[7:0]
//   special (id = motor id, 8 bytes)  FF FF FF FF FF FF FF FC enter motor mode, ...FD exit, ...FE zero
#pragma once

#include <cstdint>

#include "runtime/robot/mit_range.hpp"
#include "runtime/transport/can/can_frame.hpp"

namespace pbppo::can {

inline constexpr unsigned kMitPositionBits = 16;
inline constexpr unsigned kMitVelocityBits = 12;
inline constexpr unsigned kMitGainBits = 12;
inline constexpr unsigned kMitTorqueBits = 12;
inline constexpr std::uint8_t kMitCommandLen = 8;
inline constexpr std::uint8_t kMitReplyLen = 6;

// Linear ranges flashed into a driver: robot data (models/<robot>/can_map.yaml).
using MitRange = robot::MitRange;

struct MitCommand {
  double q_rad = 0;
  double dq_rad_s = 0;
  double kp_nm_rad = 0;
  double kd_nm_s_rad = 0;
  double tau_ff_nm = 0;
};

struct MitReply {
  std::uint8_t motor_id = 0;
  double q_rad = 0;
  double dq_rad_s = 0;
  double tau_nm = 0;
};

// Bits of EncodeMitCommand's result: which fields were clamped or were not finite.
enum MitEncodeFlags : std::uint16_t {
  kMitClampedPosition = 1u << 0,
  kMitClampedVelocity = 1u << 1,
  kMitClampedKp = 1u << 2,
  kMitClampedKd = 1u << 3,
  kMitClampedTorque = 1u << 4,
  kMitNonFinitePosition = 1u << 8,
  kMitNonFiniteVelocity = 1u << 9,
  kMitNonFiniteKp = 1u << 10,
  kMitNonFiniteKd = 1u << 11,
  kMitNonFiniteTorque = 1u << 12,
};

enum class MitSpecial : std::uint8_t {
  kEnterMotorMode = 0xFC,
  kExitMotorMode = 0xFD,
  kSetZero = 0xFE,
};

// Raw codes of a command or reply (the integers on the wire).
struct MitCommandCodes {
  std::uint16_t p;
  std::uint16_t v, kp, kd, t;  // 12 bits each
};
struct MitReplyCodes {
  std::uint8_t motor_id;
  std::uint16_t p;
  std::uint16_t v, t;  // 12 bits each
};

// Writes the 8 data bytes of a command; values are clamped into the range first (non-finite
// values become the code nearest zero). Returns MitEncodeFlags (0 = nothing clamped).
std::uint16_t EncodeMitCommand(const MitRange& range, const MitCommand& cmd, std::uint8_t out[8]) noexcept;
void PackMitCommand(const MitCommandCodes& c, std::uint8_t out[8]) noexcept;
MitCommandCodes UnpackMitCommand(const std::uint8_t in[8]) noexcept;
// Decodes a command frame's data (the driver side: emulators, logs). False if len != 8 or the
// bytes are a special frame.
bool DecodeMitCommand(const MitRange& range, const std::uint8_t* data, std::uint8_t len, MitCommand* out) noexcept;

// Reply: 6 bytes. Encode is the driver side (emulators); Decode is the controller side.
std::uint16_t EncodeMitReply(const MitRange& range, const MitReply& reply, std::uint8_t out[6]) noexcept;
void PackMitReply(const MitReplyCodes& c, std::uint8_t out[6]) noexcept;
MitReplyCodes UnpackMitReply(const std::uint8_t in[6]) noexcept;
// False if len != 6. The caller checks out->motor_id against the motor it expects.
bool DecodeMitReply(const MitRange& range, const std::uint8_t* data, std::uint8_t len, MitReply* out) noexcept;

void EncodeMitSpecial(MitSpecial kind, std::uint8_t out[8]) noexcept;
// True (and *kind) if the 8 bytes are FF x7 followed by FC, FD or FE.
bool DecodeMitSpecial(const std::uint8_t* data, std::uint8_t len, MitSpecial* kind) noexcept;

// Whole frames (id, len, flags set; classic frame).
CanFrame MakeMitCommandFrame(std::uint32_t motor_id, const MitRange& range, const MitCommand& cmd,
                             std::uint16_t* flags = nullptr) noexcept;
CanFrame MakeMitReplyFrame(std::uint32_t reply_id, const MitRange& range, const MitReply& reply) noexcept;
CanFrame MakeMitSpecialFrame(std::uint32_t motor_id, MitSpecial kind) noexcept;

}  // namespace pbppo::can
