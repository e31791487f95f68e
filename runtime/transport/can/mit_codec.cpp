#include "runtime/transport/can/mit_codec.hpp"

#include "runtime/transport/can/quantize.hpp"

namespace pbppo::can {
namespace {

std::uint16_t Code(double x, double lo, double hi, unsigned bits, std::uint16_t clamp_flag, std::uint16_t nf_flag,
                   std::uint16_t* flags) noexcept {
  const QuantizeResult q = ValueToCode(x, lo, hi, bits);
  if (q.clamped) *flags = static_cast<std::uint16_t>(*flags | clamp_flag);
  if (q.non_finite) *flags = static_cast<std::uint16_t>(*flags | nf_flag);
  return static_cast<std::uint16_t>(q.code);
}

std::uint8_t Byte(unsigned v) noexcept {
  return static_cast<std::uint8_t>(v & 0xFFu);
}

}  // namespace

void PackMitCommand(const MitCommandCodes& c, std::uint8_t out[8]) noexcept {
  out[0] = Byte(c.p >> 8u);
  out[1] = Byte(c.p);
  out[2] = Byte(c.v >> 4u);
  out[3] = Byte(((c.v & 0xFu) << 4u) | ((c.kp >> 8u) & 0xFu));
  out[4] = Byte(c.kp);
  out[5] = Byte(c.kd >> 4u);
  out[6] = Byte(((c.kd & 0xFu) << 4u) | ((c.t >> 8u) & 0xFu));
  out[7] = Byte(c.t);
}

MitCommandCodes UnpackMitCommand(const std::uint8_t in[8]) noexcept {
  MitCommandCodes c{};
  c.p = static_cast<std::uint16_t>((unsigned{in[0]} << 8u) | in[1]);
  c.v = static_cast<std::uint16_t>((unsigned{in[2]} << 4u) | (unsigned{in[3]} >> 4u));
  c.kp = static_cast<std::uint16_t>(((unsigned{in[3]} & 0xFu) << 8u) | in[4]);
  c.kd = static_cast<std::uint16_t>((unsigned{in[5]} << 4u) | (unsigned{in[6]} >> 4u));
  c.t = static_cast<std::uint16_t>(((unsigned{in[6]} & 0xFu) << 8u) | in[7]);
  return c;
}

std::uint16_t EncodeMitCommand(const MitRange& r, const MitCommand& cmd, std::uint8_t out[8]) noexcept {
  std::uint16_t f = 0;
  MitCommandCodes c{};
  c.p = Code(cmd.q_rad, r.p_min, r.p_max, kMitPositionBits, kMitClampedPosition, kMitNonFinitePosition, &f);
  c.v = Code(cmd.dq_rad_s, r.v_min, r.v_max, kMitVelocityBits, kMitClampedVelocity, kMitNonFiniteVelocity, &f);
  c.kp = Code(cmd.kp_nm_rad, r.kp_min, r.kp_max, kMitGainBits, kMitClampedKp, kMitNonFiniteKp, &f);
  c.kd = Code(cmd.kd_nm_s_rad, r.kd_min, r.kd_max, kMitGainBits, kMitClampedKd, kMitNonFiniteKd, &f);
  c.t = Code(cmd.tau_ff_nm, r.t_min, r.t_max, kMitTorqueBits, kMitClampedTorque, kMitNonFiniteTorque, &f);
  // p, v, kp, kd at their maximum and t at 0xFFC..0xFFE give exactly the bytes of a special frame
  // (FF x7 FC..FE): a driver would switch mode instead. Such a command goes out with t = 0xFFB.
  if (c.p == 0xFFFF && c.v == 0xFFF && c.kp == 0xFFF && c.kd == 0xFFF && c.t >= 0xFFC && c.t <= 0xFFE) {
    c.t = 0xFFB;
    f = static_cast<std::uint16_t>(f | kMitClampedTorque);
  }
  PackMitCommand(c, out);
  return f;
}

bool DecodeMitCommand(const MitRange& r, const std::uint8_t* data, std::uint8_t len, MitCommand* out) noexcept {
  if (len != kMitCommandLen) return false;
  MitSpecial special{};
  if (DecodeMitSpecial(data, len, &special)) return false;
  const MitCommandCodes c = UnpackMitCommand(data);
  out->q_rad = CodeToValue(c.p, r.p_min, r.p_max, kMitPositionBits);
  out->dq_rad_s = CodeToValue(c.v, r.v_min, r.v_max, kMitVelocityBits);
  out->kp_nm_rad = CodeToValue(c.kp, r.kp_min, r.kp_max, kMitGainBits);
  out->kd_nm_s_rad = CodeToValue(c.kd, r.kd_min, r.kd_max, kMitGainBits);
  out->tau_ff_nm = CodeToValue(c.t, r.t_min, r.t_max, kMitTorqueBits);
  return true;
}

void PackMitReply(const MitReplyCodes& c, std::uint8_t out[6]) noexcept {
  out[0] = c.motor_id;
  out[1] = Byte(c.p >> 8u);
  out[2] = Byte(c.p);
  out[3] = Byte(c.v >> 4u);
  out[4] = Byte(((c.v & 0xFu) << 4u) | ((c.t >> 8u) & 0xFu));
  out[5] = Byte(c.t);
}

MitReplyCodes UnpackMitReply(const std::uint8_t in[6]) noexcept {
  MitReplyCodes c{};
  c.motor_id = in[0];
  c.p = static_cast<std::uint16_t>((unsigned{in[1]} << 8u) | in[2]);
  c.v = static_cast<std::uint16_t>((unsigned{in[3]} << 4u) | (unsigned{in[4]} >> 4u));
  c.t = static_cast<std::uint16_t>(((unsigned{in[4]} & 0xFu) << 8u) | in[5]);
  return c;
}

std::uint16_t EncodeMitReply(const MitRange& r, const MitReply& reply, std::uint8_t out[6]) noexcept {
  std::uint16_t f = 0;
  MitReplyCodes c{};
  c.motor_id = reply.motor_id;
  c.p = Code(reply.q_rad, r.p_min, r.p_max, kMitPositionBits, kMitClampedPosition, kMitNonFinitePosition, &f);
  c.v = Code(reply.dq_rad_s, r.v_min, r.v_max, kMitVelocityBits, kMitClampedVelocity, kMitNonFiniteVelocity, &f);
  c.t = Code(reply.tau_nm, r.t_min, r.t_max, kMitTorqueBits, kMitClampedTorque, kMitNonFiniteTorque, &f);
  PackMitReply(c, out);
  return f;
}

bool DecodeMitReply(const MitRange& r, const std::uint8_t* data, std::uint8_t len, MitReply* out) noexcept {
  if (len != kMitReplyLen) return false;
  const MitReplyCodes c = UnpackMitReply(data);
  out->motor_id = c.motor_id;
  out->q_rad = CodeToValue(c.p, r.p_min, r.p_max, kMitPositionBits);
  out->dq_rad_s = CodeToValue(c.v, r.v_min, r.v_max, kMitVelocityBits);
  out->tau_nm = CodeToValue(c.t, r.t_min, r.t_max, kMitTorqueBits);
  return true;
}

void EncodeMitSpecial(MitSpecial kind, std::uint8_t out[8]) noexcept {
  for (int i = 0; i < 7; ++i) out[i] = 0xFF;
  out[7] = static_cast<std::uint8_t>(kind);
}

bool DecodeMitSpecial(const std::uint8_t* data, std::uint8_t len, MitSpecial* kind) noexcept {
  if (len != kMitCommandLen) return false;
  for (int i = 0; i < 7; ++i) {
    if (data[i] != 0xFF) return false;
  }
  if (data[7] < 0xFC || data[7] > 0xFE) return false;
  *kind = static_cast<MitSpecial>(data[7]);
  return true;
}

CanFrame MakeMitCommandFrame(std::uint32_t motor_id, const MitRange& range, const MitCommand& cmd,
                             std::uint16_t* flags) noexcept {
  CanFrame f;
  f.id = motor_id;
  f.len = kMitCommandLen;
  const std::uint16_t fl = EncodeMitCommand(range, cmd, f.data);
  if (flags != nullptr) *flags = fl;
  return f;
}

CanFrame MakeMitReplyFrame(std::uint32_t reply_id, const MitRange& range, const MitReply& reply) noexcept {
  CanFrame f;
  f.id = reply_id;
  f.len = kMitReplyLen;
  EncodeMitReply(range, reply, f.data);
  return f;
}

CanFrame MakeMitSpecialFrame(std::uint32_t motor_id, MitSpecial kind) noexcept {
  CanFrame f;
  f.id = motor_id;
  f.len = kMitCommandLen;
  EncodeMitSpecial(kind, f.data);
  return f;
}

}  // namespace pbppo::can
