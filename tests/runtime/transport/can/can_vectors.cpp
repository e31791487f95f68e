// Writes frames made by the C++ encoders for every device of a CAN map, with the values the C++
// decoders read back, one frame a line:  KIND NAME ID HEXDATA signal=value ...
// check_dbc.py decodes the same bytes with the DBC and compares. With a second argument, also
// writes every frame through CandumpLogger to that file (check_candump.py reads it back with
// python-can). usage: can_vectors CAN_MAP.yaml [CANDUMP_LOG]
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "runtime/robot/can_map.hpp"
#include "runtime/transport/can/candump_log.hpp"
#include "runtime/transport/can/imu_codec.hpp"
#include "runtime/transport/can/mit_codec.hpp"

using namespace pbppo::can;

namespace {
pbppo::can::CandumpLogger* g_log = nullptr;
std::uint64_t g_time_ns = 1700000000000000000ull;

void Hex(const CanFrame& f) {
  for (int i = 0; i < f.len; ++i) std::printf("%02X", f.data[i]);
  if (g_log != nullptr) {
    CanFrame c = f;
    c.timestamp_ns = (g_time_ns += 1000);
    while (!g_log->Push(0, c)) {
    }  // not real-time: wait for room rather than drop
  }
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 && argc != 3) {
    std::fprintf(stderr, "usage: can_vectors CAN_MAP.yaml [CANDUMP_LOG]\n");
    return 2;
  }
  std::unique_ptr<CandumpLogger> log;
  if (argc == 3) {
    auto l = CandumpLogger::Open(argv[2], {"vcan0"}, 256);
    if (!l) {
      std::fprintf(stderr, "%s\n", l.error().message.c_str());
      return 1;
    }
    log = std::move(*l);
    g_log = log.get();
  }
  auto map = pbppo::robot::LoadCanMap(argv[1]);
  if (!map) {
    std::fprintf(stderr, "%s\n", map.error().message.c_str());
    return 1;
  }
  const int kSteps = 37;
  for (const auto& m : map->motors) {
    const MitRange& r = map->range_of(m);
    for (int s = -2; s <= kSteps + 2; ++s) {  // beyond both ends: clamped
      const double a = static_cast<double>(s) / kSteps;
      const double b = std::fmod(a * 7.3, 1.0);
      MitCommand c{r.p_min + a * (r.p_max - r.p_min), r.v_max - a * (r.v_max - r.v_min),
                   r.kp_min + b * (r.kp_max - r.kp_min), r.kd_min + (1 - b) * (r.kd_max - r.kd_min),
                   r.t_min + a * a * (r.t_max - r.t_min)};
      const CanFrame f = MakeMitCommandFrame(m.id, r, c);
      MitCommand d;
      if (!DecodeMitCommand(r, f.data, f.len, &d)) return 1;
      std::printf("CMD CMD_%s %u ", m.joint.c_str(), f.id);
      Hex(f);
      std::printf(" p_des=%.17g v_des=%.17g kp=%.17g kd=%.17g t_ff=%.17g\n", d.q_rad, d.dq_rad_s, d.kp_nm_rad,
                  d.kd_nm_s_rad, d.tau_ff_nm);
      MitReply rep{static_cast<std::uint8_t>(m.id), c.q_rad, c.dq_rad_s, c.tau_ff_nm};
      const CanFrame g = MakeMitReplyFrame(m.reply_id, r, rep);
      MitReply e;
      if (!DecodeMitReply(r, g.data, g.len, &e)) return 1;
      std::printf("RPL RPL_%s %u ", m.joint.c_str(), g.id);
      Hex(g);
      std::printf(" motor_id=%u p=%.17g v=%.17g t=%.17g\n", e.motor_id, e.q_rad, e.dq_rad_s, e.tau_nm);
    }
  }
  for (const auto& u : map->imus) {
    for (int s = 0; s < 25; ++s) {
      ImuSample x;
      const double a = 0.3 * s;
      x.quat_wxyz[0] = std::cos(a);
      x.quat_wxyz[1] = std::sin(a) * 0.48;
      x.quat_wxyz[2] = -std::sin(a) * 0.6;
      x.quat_wxyz[3] = std::sin(a) * 0.64;
      for (int k = 0; k < 3; ++k) {
        x.gyro_rad_s[k] = std::sin(a + k) * (s == 24 ? 40.0 : 30.0);
        x.accel_m_s2[k] = std::cos(a * 1.7 + k) * 150.0;
      }
      x.seq = static_cast<std::uint8_t>(s * 11);
      x.status = kImuOrientationValid;
      CanFrame f[3];
      MakeImuClassicFrames(u.id, x, f);
      ImuSample d;
      for (unsigned k = 0; k < 3; ++k) DecodeImuClassicFrame(k, f[k].data, f[k].len, &d);
      std::printf("IMU IMU_%s_Q %u ", u.name.c_str(), f[0].id);
      Hex(f[0]);
      std::printf(" qw=%.17g qx=%.17g qy=%.17g qz=%.17g\n", d.quat_wxyz[0], d.quat_wxyz[1], d.quat_wxyz[2],
                  d.quat_wxyz[3]);
      std::printf("IMU IMU_%s_W %u ", u.name.c_str(), f[1].id);
      Hex(f[1]);
      std::printf(" wx=%.17g wy=%.17g wz=%.17g seq=%u status=%u\n", d.gyro_rad_s[0], d.gyro_rad_s[1], d.gyro_rad_s[2],
                  d.seq, d.status);
      std::printf("IMU IMU_%s_A %u ", u.name.c_str(), f[2].id);
      Hex(f[2]);
      std::printf(" ax=%.17g ay=%.17g az=%.17g seq=%u status=%u\n", d.accel_m_s2[0], d.accel_m_s2[1], d.accel_m_s2[2],
                  d.seq, d.status);
      const CanFrame g = MakeImuFdFrame(u.id, x);
      ImuSample e;
      if (!DecodeImuFd(g.data, g.len, &e)) return 1;
      std::printf("IMUFD IMU_%s_FD - ", u.name.c_str());
      Hex(g);
      std::printf(
          " qw=%.17g qx=%.17g qy=%.17g qz=%.17g wx=%.17g wy=%.17g wz=%.17g ax=%.17g ay=%.17g az=%.17g "
          "seq=%u status=%u\n",
          e.quat_wxyz[0], e.quat_wxyz[1], e.quat_wxyz[2], e.quat_wxyz[3], e.gyro_rad_s[0], e.gyro_rad_s[1],
          e.gyro_rad_s[2], e.accel_m_s2[0], e.accel_m_s2[1], e.accel_m_s2[2], e.seq, e.status);
    }
  }
  if (log) {
    log->Stop();
    if (log->write_errors() != 0) return 1;
  }
  return 0;
}
