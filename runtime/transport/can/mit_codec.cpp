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

// The frames hold their fields big-endian, most significant first, packed without gaps: a frame
// is one word of 8 x `bytes` bits, a field `bits` wide ends `shift` bits above the word's end.
constexpr std::uint64_t Field(unsigned v, unsigned bits, unsigned shift) noexcept {
  return (std::uint64_t{v} & ((std::uint64_t{1} << bits) - 1u)) << shift;
}
constexpr std::uint16_t FieldOf(std::uint64_t word, unsigned bits, unsigned shift) noexcept {
  return static_cast<std::uint16_t>((word >> shift) & ((std::uint64_t{1} << bits) - 1u));
}
void Store(std::uint64_t word, std::uint8_t* out, unsigned bytes) noexcept {
  for (unsigned i = 0; i < bytes; ++i) out[i] = static_cast<std::uint8_t>(word >> (8u * (bytes - 1u - i)));
}
std::uint64_t Load(const std::uint8_t* in, unsigned bytes) noexcept {
  std::uint64_t word = 0;
  for (unsigned i = 0; i < bytes; ++i) word = (word << 8u) | in[i];
  return word;
}

}  // namespace

// Command: p 16 | v 12 | kp 12 | kd 12 | t 12.
void PackMitCommand(const MitCommandCodes& c, std::uint8_t out[8]) noexcept {
  Store(Field(c.p, 16, 48) | Field(c.v, 12, 36) | Field(c.kp, 12, 24) | Field(c.kd, 12, 12) | Field(c.t, 12, 0), out,
        8);
}

MitCommandCodes UnpackMitCommand(const std::uint8_t in[8]) noexcept {
  const std::uint64_t w = Load(in, 8);
  return {FieldOf(w, 16, 48), FieldOf(w, 12, 36), FieldOf(w, 12, 24), FieldOf(w, 12, 12), FieldOf(w, 12, 0)};
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

// Reply: motor id 8 | p 16 | v 12 | t 12.
void PackMitReply(const MitReplyCodes& c, std::uint8_t out[6]) noexcept {
  Store(Field(c.motor_id, 8, 40) | Field(c.p, 16, 24) | Field(c.v, 12, 12) | Field(c.t, 12, 0), out, 6);
}

MitReplyCodes UnpackMitReply(const std::uint8_t in[6]) noexcept {
  const std::uint64_t w = Load(in, 6);
  return {static_cast<std::uint8_t>(FieldOf(w, 8, 40)), FieldOf(w, 16, 24), FieldOf(w, 12, 12), FieldOf(w, 12, 0)};
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
