// IMU frames of our own design (docs/can.md): orientation quaternion, angular rate and linear
// acceleration as little-endian int16 with fixed scales, plus a sample counter and status bits.
// Two variants: classic CAN (three 8-byte frames on id, id+1, id+2) and CAN FD (one 24-byte
// frame on id, the whole sample at once). Pure and allocation-free; no OS headers.
//
//   classic frame 0 (id)    qw qx qy qz            int16 each, 1/32767 per LSB
//   classic frame 1 (id+1)  wx wy wz seq status    int16 rad/s, 1/1000 rad/s per LSB; u8; u8
//   classic frame 2 (id+2)  ax ay az seq status    int16 m/s^2, 1/200 m/s^2 per LSB; u8; u8
//   fd frame (id, 24 bytes) qw qx qy qz wx wy wz ax ay az seq status 0 0
#pragma once

#include <cstdint>

#include "runtime/transport/can/can_frame.hpp"

namespace pbppo::can {

inline constexpr double kImuQuatScale = 1.0 / 32767.0;  // per LSB
inline constexpr double kImuGyroScale = 1.0 / 1000.0;   // rad/s per LSB: +-32.767 rad/s
inline constexpr double kImuAccelScale = 1.0 / 200.0;   // m/s^2 per LSB: +-163.835 m/s^2
inline constexpr std::uint8_t kImuClassicLen = 8;
inline constexpr std::uint8_t kImuFdLen = 24;

// Status bits (sent by the IMU; the encoder adds the saturation bits when it clamps).
enum ImuStatus : std::uint8_t {
  kImuOrientationValid = 1u << 0,  // the IMU's attitude filter has converged
  kImuGyroSaturated = 1u << 1,
  kImuAccelSaturated = 1u << 2,
  kImuSelfTestFailed = 1u << 3,
};

struct ImuSample {
  double quat_wxyz[4] = {1, 0, 0, 0};  // orientation of the IMU in the world frame (not renormalised)
  double gyro_rad_s[3] = {0, 0, 0};
  double accel_m_s2[3] = {0, 0, 0};
  std::uint8_t seq = 0;
  std::uint8_t status = 0;
};

// Encoding clamps each value to the int16 range (and the quaternion to [-1, 1]); non-finite
// values become 0 and set the matching saturation bit (the quaternion: clears kImuOrientationValid).
void EncodeImuClassic(const ImuSample& s, std::uint8_t frame0[8], std::uint8_t frame1[8],
                      std::uint8_t frame2[8]) noexcept;
void EncodeImuFd(const ImuSample& s, std::uint8_t out[24]) noexcept;

// Classic: one frame at a time (index 0, 1, 2 = id - base id) into a partial sample.
bool DecodeImuClassicFrame(unsigned index, const std::uint8_t* data, std::uint8_t len, ImuSample* partial) noexcept;
bool DecodeImuFd(const std::uint8_t* data, std::uint8_t len, ImuSample* out) noexcept;

// Reassembles classic frames into whole samples: a sample is complete when frames 0, 1, 2 have
// arrived in that order and frames 1 and 2 carry the same seq. Anything else restarts it.
struct ImuAssembler {
  ImuSample partial;
  std::uint8_t have = 0;  // bit k: frame k of the current sample seen
  std::uint64_t completed = 0;
  std::uint64_t broken = 0;  // samples abandoned (frame lost, reordered or seq mismatch)
};
// Returns true when `index` completed a sample (then *out holds it).
bool FeedImuClassic(ImuAssembler& a, unsigned index, const std::uint8_t* data, std::uint8_t len,
                    ImuSample* out) noexcept;

CanFrame MakeImuFdFrame(std::uint32_t id, const ImuSample& s) noexcept;
void MakeImuClassicFrames(std::uint32_t base_id, const ImuSample& s, CanFrame out[3]) noexcept;

}  // namespace pbppo::can
