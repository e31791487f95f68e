#include <doctest/doctest.h>

#include <cmath>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/transport/can/can_table.hpp"
#include "runtime/transport/can/can_transport.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo::can;

namespace {
pbppo::robot::CanMap Quadruped() {
  auto m = pbppo::robot::LoadCanMap(pbppo::test::SourcePath("models/quadruped/can_map.yaml"));
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  return *m;
}
}  // namespace

TEST_CASE("controller table: replies and IMU frames - per bus - filters are the ids in use") {
  const auto map = Quadruped();
  auto t = BuildCodecTable(map, CanRole::kController);
  REQUIRE_MESSAGE(t.ok(), t.error().message);
  CHECK(t->bus_count == 2);
  CHECK(t->rx_ids[0] == std::vector<std::uint32_t>{0x080, 0x081, 0x082, 0x101, 0x102, 0x103, 0x104, 0x105, 0x106});
  CHECK(t->rx_ids[1] == std::vector<std::uint32_t>{0x107, 0x108, 0x109, 0x10A, 0x10B, 0x10C});
  CanFrame f;
  f.id = 0x103;
  CHECK(t->Lookup(0, f).kind == CodecKind::kMitReply);
  CHECK(t->Lookup(0, f).index == 2);
  CHECK(t->Lookup(1, f).kind == CodecKind::kNone);
  f.id = 0x081;
  CHECK(t->Lookup(0, f).kind == CodecKind::kImuClassic);
  CHECK(t->Lookup(0, f).sub == 1);
  f.flags = kFlagExtended;
  CHECK(t->Lookup(0, f).kind == CodecKind::kNone);
  CHECK(t->Lookup(7, f).kind == CodecKind::kNone);

  auto d = BuildCodecTable(map, CanRole::kDevices);
  REQUIRE(d.ok());
  CHECK(d->rx_ids[1] == std::vector<std::uint32_t>{0x07, 0x08, 0x09, 0x0A, 0x0B, 0x0C});
}

TEST_CASE(
    "dispatch decodes replies - counts and ignores unknown ids - wrong lengths - wrong motor ids - no allocation") {
  const auto map = Quadruped();
  auto t = BuildCodecTable(map, CanRole::kController);
  REQUIRE(t.ok());
  CanRxData data = MakeCanRxData(*t);
  BusStats stats[2];
  CanFrame replies[12];
  for (std::size_t i = 0; i < 12; ++i) {
    MitReply r{static_cast<std::uint8_t>(t->motor_id[i]), 0.1 * static_cast<double>(i), -1.0, 2.0};
    replies[i] = MakeMitReplyFrame(t->reply_id[i], t->range[i], r);
  }
  CanFrame imu[3];
  ImuSample s;
  s.gyro_rad_s[2] = 1.25;
  s.seq = 9;
  MakeImuClassicFrames(0x080, s, imu);
  CanFrame unknown = replies[0];
  unknown.id = 0x555;
  CanFrame short_reply = replies[1];
  short_reply.len = 5;
  CanFrame wrong_motor = replies[2];
  wrong_motor.data[0] = 0x33;

  pbppo::AllocationScope scope;
  for (int tick = 0; tick < 1000; ++tick) {
    for (std::size_t i = 0; i < 12; ++i) {
      REQUIRE(DispatchFrame(*t, t->motor_bus[i], replies[i], data, stats[t->motor_bus[i]]) == DispatchResult::kDecoded);
    }
    CHECK(DispatchFrame(*t, 0, imu[0], data, stats[0]) == DispatchResult::kPartial);
    CHECK(DispatchFrame(*t, 0, imu[1], data, stats[0]) == DispatchResult::kPartial);
    CHECK(DispatchFrame(*t, 0, imu[2], data, stats[0]) == DispatchResult::kDecoded);
    CHECK(DispatchFrame(*t, 1, unknown, data, stats[1]) == DispatchResult::kUnknownId);
    CHECK(DispatchFrame(*t, 0, short_reply, data, stats[0]) == DispatchResult::kWrongLength);
    CHECK(DispatchFrame(*t, 0, wrong_motor, data, stats[0]) == DispatchResult::kWrongMotorId);
    CHECK(DispatchFrame(*t, 1, imu[0], data, stats[1]) == DispatchResult::kUnknownId);  // IMU is on bus 0
  }
  CHECK(scope.count() == 0);
  CHECK(stats[0].decoded == 1000 * (6 + 3));
  CHECK(stats[1].decoded == 1000 * 6);
  CHECK(stats[1].unknown_ids == 2000);
  CHECK(stats[0].wrong_lengths == 1000);
  CHECK(stats[0].wrong_motor_id == 1000);
  CHECK(data.reply_count[11] == 1000);
  CHECK(data.reply[5].q_rad == doctest::Approx(0.5).epsilon(0.01));
  CHECK(data.imu_count[0] == 1000);
  CHECK(data.imu[0].gyro_rad_s[2] == doctest::Approx(1.25));
  CHECK(data.imu[0].seq == 9);
}

TEST_CASE("device table: commands and special frames reach the emulated motor") {
  auto t = BuildCodecTable(Quadruped(), CanRole::kDevices);
  REQUIRE(t.ok());
  CanRxData data = MakeCanRxData(*t);
  BusStats st;
  const CanFrame c = MakeMitCommandFrame(0x08, t->range[7], MitCommand{0.3, 0, 40, 1, -2});
  CHECK(DispatchFrame(*t, 1, c, data, st) == DispatchResult::kDecoded);
  CHECK(std::fabs(data.command[7].kp_nm_rad - 40.0) <= 0.5 * 500.0 / 4095);
  CHECK(DispatchFrame(*t, 1, MakeMitSpecialFrame(0x08, MitSpecial::kEnterMotorMode), data, st) ==
        DispatchResult::kDecoded);
  CHECK(data.last_special[7] == 0xFC);
  CHECK(data.special_count[7] == 1);
  CHECK(data.command_count[7] == 1);
}

TEST_CASE("a command line's CAN interface list: names in bus order, an empty name refused") {
  auto none = ParseInterfaceList("");
  REQUIRE(none);
  CHECK(none->empty());
  auto two = ParseInterfaceList("vcan0,vcan1");
  REQUIRE(two);
  CHECK(*two == std::vector<std::string>{"vcan0", "vcan1"});
  for (const char* bad : {"vcan0,", ",vcan1", "vcan0,,vcan1", ","}) {
    auto r = ParseInterfaceList(bad);
    REQUIRE_FALSE(r);
    CHECK(r.error().message.find(std::string("'") + bad + "'") != std::string::npos);
  }
}
