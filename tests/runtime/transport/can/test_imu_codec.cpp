#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "runtime/transport/can/imu_codec.hpp"

using namespace pbppo::can;

namespace {
ImuSample Sample(int i) {
  ImuSample s;
  const double a = 0.01 * i;
  s.quat_wxyz[0] = std::cos(a);
  s.quat_wxyz[1] = std::sin(a) * 0.6;
  s.quat_wxyz[2] = -std::sin(a) * 0.8;
  s.quat_wxyz[3] = 0.0;
  for (int k = 0; k < 3; ++k) {
    s.gyro_rad_s[k] = std::sin(0.37 * i + k) * 30.0;
    s.accel_m_s2[k] = std::cos(0.11 * i + k) * 150.0;
  }
  s.seq = static_cast<std::uint8_t>(i);
  s.status = kImuOrientationValid;
  return s;
}

void CheckClose(const ImuSample& a, const ImuSample& b) {
  for (int k = 0; k < 4; ++k) CHECK(std::fabs(a.quat_wxyz[k] - b.quat_wxyz[k]) <= 0.5 * kImuQuatScale + 1e-12);
  for (int k = 0; k < 3; ++k) {
    CHECK(std::fabs(a.gyro_rad_s[k] - b.gyro_rad_s[k]) <= 0.5 * kImuGyroScale + 1e-12);
    CHECK(std::fabs(a.accel_m_s2[k] - b.accel_m_s2[k]) <= 0.5 * kImuAccelScale + 1e-12);
  }
  CHECK(a.seq == b.seq);
  CHECK(a.status == b.status);
}
}  // namespace

TEST_CASE("FD frame: one 24-byte frame round-trips within half a step - decode then encode is exact") {
  for (int i = 0; i < 700; ++i) {
    const ImuSample s = Sample(i);
    const CanFrame f = MakeImuFdFrame(0x88, s);
    CHECK(f.len == 24);
    CHECK(f.fd());
    ImuSample d;
    REQUIRE(DecodeImuFd(f.data, f.len, &d));
    CheckClose(s, d);
    std::uint8_t again[24];
    EncodeImuFd(d, again);
    CHECK(std::memcmp(again, f.data, 24) == 0);
  }
}

TEST_CASE("FD layout: little-endian int16 at the documented offsets") {
  ImuSample s;
  s.quat_wxyz[0] = 1.0;
  s.gyro_rad_s[0] = -0.001;
  s.accel_m_s2[2] = 9.81;
  s.seq = 0x42;
  s.status = 0x01;
  std::uint8_t b[24];
  EncodeImuFd(s, b);
  CHECK(b[0] == 0xFF);  // 32767
  CHECK(b[1] == 0x7F);
  CHECK(b[8] == 0xFF);  // -1
  CHECK(b[9] == 0xFF);
  CHECK((b[18] | (b[19] << 8)) == 1962);  // 9.81 * 200
  CHECK(b[20] == 0x42);
  CHECK(b[21] == 0x01);
}

TEST_CASE("classic frames: three frames reassemble into the sample") {
  ImuAssembler a;
  for (int i = 0; i < 300; ++i) {
    const ImuSample s = Sample(i);
    CanFrame f[3];
    MakeImuClassicFrames(0x80, s, f);
    CHECK(f[2].id == 0x82);
    ImuSample out;
    CHECK_FALSE(FeedImuClassic(a, 0, f[0].data, f[0].len, &out));
    CHECK_FALSE(FeedImuClassic(a, 1, f[1].data, f[1].len, &out));
    REQUIRE(FeedImuClassic(a, 2, f[2].data, f[2].len, &out));
    CheckClose(s, out);
  }
  CHECK(a.completed == 300);
  CHECK(a.broken == 0);
}

TEST_CASE("classic frames: a lost or mismatched frame breaks only that sample") {
  ImuAssembler a;
  ImuSample out;
  CanFrame f[3], g[3];
  MakeImuClassicFrames(0x80, Sample(1), f);
  MakeImuClassicFrames(0x80, Sample(2), g);
  // frame 1 lost
  CHECK_FALSE(FeedImuClassic(a, 0, f[0].data, 8, &out));
  CHECK_FALSE(FeedImuClassic(a, 2, f[2].data, 8, &out));
  CHECK(a.broken == 1);
  // seq mismatch between frames 1 and 2
  CHECK_FALSE(FeedImuClassic(a, 0, f[0].data, 8, &out));
  CHECK_FALSE(FeedImuClassic(a, 1, f[1].data, 8, &out));
  CHECK_FALSE(FeedImuClassic(a, 2, g[2].data, 8, &out));
  CHECK(a.broken == 2);
  // a whole sample afterwards is fine
  CHECK_FALSE(FeedImuClassic(a, 0, g[0].data, 8, &out));
  CHECK_FALSE(FeedImuClassic(a, 1, g[1].data, 8, &out));
  CHECK(FeedImuClassic(a, 2, g[2].data, 8, &out));
  CHECK(out.seq == 2);
  CHECK(a.completed == 1);
  // wrong lengths and indexes are refused
  CHECK_FALSE(FeedImuClassic(a, 0, g[0].data, 7, &out));
  CHECK_FALSE(FeedImuClassic(a, 3, g[0].data, 8, &out));
}

TEST_CASE("saturation and non-finite values set the status bits") {
  ImuSample s;
  s.status = kImuOrientationValid;
  s.gyro_rad_s[1] = 100.0;  // beyond 32.767
  s.accel_m_s2[0] = std::numeric_limits<double>::quiet_NaN();
  s.quat_wxyz[2] = 1.5;
  std::uint8_t b[24];
  EncodeImuFd(s, b);
  ImuSample d;
  REQUIRE(DecodeImuFd(b, 24, &d));
  CHECK(d.gyro_rad_s[1] == doctest::Approx(32.767));
  CHECK(d.accel_m_s2[0] == 0.0);
  CHECK(d.quat_wxyz[2] == doctest::Approx(1.0));
  CHECK((d.status & kImuGyroSaturated) != 0);
  CHECK((d.status & kImuAccelSaturated) != 0);
  CHECK((d.status & kImuOrientationValid) == 0);
  CHECK_FALSE(DecodeImuFd(b, 20, &d));
}
