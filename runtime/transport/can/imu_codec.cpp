#include "runtime/transport/can/imu_codec.hpp"

#include <cmath>

namespace pbppo::can {
namespace {

// Round to the nearest int16 code of x / scale; clamps to [-lim, lim]. Returns false if clamped
// or not finite (then the code is the clamp value, or 0 for non-finite input).
bool ToI16(double x, double scale, std::int16_t lim, std::int16_t* out) noexcept {
  if (!std::isfinite(x)) {
    *out = 0;
    return false;
  }
  const double c = std::floor(x / scale + 0.5);
  if (c > lim) {
    *out = lim;
    return false;
  }
  if (c < -lim) {
    *out = static_cast<std::int16_t>(-lim);
    return false;
  }
  *out = static_cast<std::int16_t>(c);
  return true;
}

void PutI16(std::uint8_t* p, std::int16_t v) noexcept {
  const auto u = static_cast<std::uint16_t>(v);
  p[0] = static_cast<std::uint8_t>(u & 0xFFu);
  p[1] = static_cast<std::uint8_t>(u >> 8u);
}

std::int16_t GetI16(const std::uint8_t* p) noexcept {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(p[0] | (unsigned{p[1]} << 8u)));
}

// Packs the 10 int16 values and returns the status with saturation bits added.
std::uint8_t Quantize(const ImuSample& s, std::int16_t q[4], std::int16_t w[3], std::int16_t a[3]) noexcept {
  std::uint8_t status = s.status;
  bool quat_ok = true;
  for (int i = 0; i < 4; ++i) quat_ok &= ToI16(s.quat_wxyz[i], kImuQuatScale, 32767, &q[i]);
  if (!quat_ok) status = static_cast<std::uint8_t>(status & ~kImuOrientationValid);
  bool gyro_ok = true;
  for (int i = 0; i < 3; ++i) gyro_ok &= ToI16(s.gyro_rad_s[i], kImuGyroScale, 32767, &w[i]);
  if (!gyro_ok) status = static_cast<std::uint8_t>(status | kImuGyroSaturated);
  bool accel_ok = true;
  for (int i = 0; i < 3; ++i) accel_ok &= ToI16(s.accel_m_s2[i], kImuAccelScale, 32767, &a[i]);
  if (!accel_ok) status = static_cast<std::uint8_t>(status | kImuAccelSaturated);
  return status;
}

}  // namespace

void EncodeImuClassic(const ImuSample& s, std::uint8_t f0[8], std::uint8_t f1[8], std::uint8_t f2[8]) noexcept {
  std::int16_t q[4], w[3], a[3];
  const std::uint8_t status = Quantize(s, q, w, a);
  for (int i = 0; i < 4; ++i) PutI16(f0 + 2 * i, q[i]);
  for (int i = 0; i < 3; ++i) PutI16(f1 + 2 * i, w[i]);
  for (int i = 0; i < 3; ++i) PutI16(f2 + 2 * i, a[i]);
  f1[6] = f2[6] = s.seq;
  f1[7] = f2[7] = status;
}

void EncodeImuFd(const ImuSample& s, std::uint8_t out[24]) noexcept {
  std::int16_t q[4], w[3], a[3];
  const std::uint8_t status = Quantize(s, q, w, a);
  for (int i = 0; i < 4; ++i) PutI16(out + 2 * i, q[i]);
  for (int i = 0; i < 3; ++i) PutI16(out + 8 + 2 * i, w[i]);
  for (int i = 0; i < 3; ++i) PutI16(out + 14 + 2 * i, a[i]);
  out[20] = s.seq;
  out[21] = status;
  out[22] = out[23] = 0;
}

bool DecodeImuClassicFrame(unsigned index, const std::uint8_t* d, std::uint8_t len, ImuSample* p) noexcept {
  if (len != kImuClassicLen) return false;
  switch (index) {
    case 0:
      for (int i = 0; i < 4; ++i) p->quat_wxyz[i] = GetI16(d + 2 * i) * kImuQuatScale;
      return true;
    case 1:
      for (int i = 0; i < 3; ++i) p->gyro_rad_s[i] = GetI16(d + 2 * i) * kImuGyroScale;
      p->seq = d[6];
      p->status = d[7];
      return true;
    case 2:
      for (int i = 0; i < 3; ++i) p->accel_m_s2[i] = GetI16(d + 2 * i) * kImuAccelScale;
      p->seq = d[6];
      p->status = d[7];
      return true;
    default: return false;
  }
}

bool DecodeImuFd(const std::uint8_t* d, std::uint8_t len, ImuSample* out) noexcept {
  if (len != kImuFdLen) return false;
  for (int i = 0; i < 4; ++i) out->quat_wxyz[i] = GetI16(d + 2 * i) * kImuQuatScale;
  for (int i = 0; i < 3; ++i) out->gyro_rad_s[i] = GetI16(d + 8 + 2 * i) * kImuGyroScale;
  for (int i = 0; i < 3; ++i) out->accel_m_s2[i] = GetI16(d + 14 + 2 * i) * kImuAccelScale;
  out->seq = d[20];
  out->status = d[21];
  return true;
}

bool FeedImuClassic(ImuAssembler& a, unsigned index, const std::uint8_t* data, std::uint8_t len,
                    ImuSample* out) noexcept {
  if (index > 2 || len != kImuClassicLen) return false;
  const auto expected = static_cast<std::uint8_t>(index == 0 ? 0u : (1u << index) - 1u);
  if (a.have != expected) {
    // A frame out of order: the sample under way is lost; frame 0 starts a new one.
    if (a.have != 0) ++a.broken;
    a.have = 0;
    if (index != 0) return false;
  }
  const std::uint8_t seq_before = a.partial.seq;
  DecodeImuClassicFrame(index, data, len, &a.partial);
  if (index == 2 && a.partial.seq != seq_before) {
    ++a.broken;
    a.have = 0;
    return false;
  }
  a.have = static_cast<std::uint8_t>(a.have | (1u << index));
  if (a.have != 7) return false;
  a.have = 0;
  ++a.completed;
  *out = a.partial;
  return true;
}

CanFrame MakeImuFdFrame(std::uint32_t id, const ImuSample& s) noexcept {
  CanFrame f;
  f.id = id;
  f.len = kImuFdLen;
  f.flags = kFlagFd | kFlagBrs;
  EncodeImuFd(s, f.data);
  return f;
}

void MakeImuClassicFrames(std::uint32_t base_id, const ImuSample& s, CanFrame out[3]) noexcept {
  for (std::uint32_t k = 0; k < 3; ++k) {
    out[k] = CanFrame{};
    out[k].id = base_id + k;
    out[k].len = kImuClassicLen;
  }
  EncodeImuClassic(s, out[0].data, out[1].data, out[2].data);
}

}  // namespace pbppo::can
