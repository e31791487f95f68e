// libFuzzer target: IMU decoders. Input: one byte choosing the decoder (0..2 classic frame index,
// 3 FD), then the payload; the whole input also drives a classic-frame assembler. Decoded values
// stay inside the int16 ranges and re-encode to the same bytes.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "runtime/transport/can/imu_codec.hpp"

namespace {
void Require(bool ok) {
  if (!ok) std::abort();
}
void CheckRanges(const pbppo::can::ImuSample& s) {
  for (double q : s.quat_wxyz) Require(std::fabs(q) <= 32768.0 / 32767.0);
  for (double w : s.gyro_rad_s) Require(std::fabs(w) <= 32.768 + 1e-9);
  for (double a : s.accel_m_s2) Require(std::fabs(a) <= 163.84 + 1e-9);
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pbppo::can;
  if (size < 1 || size > 1 + kFdMaxLen) return 0;
  const unsigned which = data[0] % 4u;
  const auto len = static_cast<std::uint8_t>(size - 1);
  std::uint8_t p[kFdMaxLen] = {};
  std::memcpy(p, data + 1, len);
  ImuSample s;
  if (which == 3) {
    const bool ok = DecodeImuFd(p, len, &s);
    Require(ok == (len == kImuFdLen));
    if (!ok) return 0;
    CheckRanges(s);
    // -32768 has no encoding (the encoder is symmetric); every other code round-trips.
    bool has_min = false;
    for (int i = 0; i < 10; ++i) has_min |= p[2 * i] == 0x00 && p[2 * i + 1] == 0x80;
    if (has_min || p[22] != 0 || p[23] != 0) return 0;
    std::uint8_t again[24];
    ImuSample t = s;
    t.status = static_cast<std::uint8_t>(s.status);
    EncodeImuFd(t, again);
    Require(std::memcmp(again, p, 24) == 0);
    return 0;
  }
  const bool ok = DecodeImuClassicFrame(which, p, len, &s);
  Require(ok == (len == kImuClassicLen));
  if (ok) CheckRanges(s);
  // Drive the assembler with the payload split into 8-byte frames, indexes from the bytes.
  ImuAssembler a;
  ImuSample out;
  for (std::size_t off = 0; off + 8 <= len; off += 8) {
    const unsigned idx = p[off] % 4u;
    if (FeedImuClassic(a, idx, p + off, 8, &out)) CheckRanges(out);
  }
  Require(a.completed <= len / 24u + 1u);
  return 0;
}
