// The DDS transport's wire format against an independent implementation: the C++ types Fast DDS's
// own generator (fastddsgen) makes from the same IDL files, serialised by Fast CDR. For every
// message of the shipped robots, a sample with a distinct value in every member is the same bytes
// from both, and each reads the other's (little- and big-endian) back to the same values. ROS 2's
// sensor_msgs/Joy (a string and two sequences) as fastddsgen's type writes it, read into the
// robot file's layout, and every malformed form of it refused.
#include <doctest/doctest.h>

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "AuvCommandPubSubTypes.h"
#include "AuvControllerStatusPubSubTypes.h"
#include "AuvSensorStatePubSubTypes.h"
#include "Joy_PubSubTypes.h"
#include "QuadrupedStatusPubSubTypes.h"
#include "VelocityCommandPubSubTypes.h"
#include "runtime/transport/dds/cdr.hpp"
#include "runtime/transport/dds/dds_link.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;

namespace {

const robot::IdlMessage& MessageType(const robot::RobotModel& m, const std::string& topic) {
  for (const robot::TransportSpec& t : m.transports)
    for (const robot::DdsMessageSpec& d : t.dds.messages)
      if (d.topic == topic) return d.type;
  FAIL("no message on topic " << topic);
  std::abort();
}

// A distinct value for each member, exact in its type: leaf k of an integer type k + 1 (within an
// octet), of a float k + 0.25 (or negative), a boolean k % 2.
double Value(const robot::IdlMessage& t, const std::string& path) {
  const int k = t.LeafIndex(path);
  REQUIRE_MESSAGE(k >= 0, path);
  switch (t.leaves[static_cast<std::size_t>(k)].type) {
    case robot::IdlScalar::kBool: return k % 2;
    case robot::IdlScalar::kFloat:
    case robot::IdlScalar::kDouble: return (k % 3 == 0 ? -1.0 : 1.0) * (k + 0.25);
    default: return k + 1;
  }
}

// The bytes a generated type serialises to (DDS_CDR, the header first), in either byte order.
template <typename PubSub, typename Type>
std::vector<std::byte> Generated(Type& value, bool big_endian) {
  PubSub pubsub;
  std::vector<char> buffer(pubsub.m_typeSize);
  eprosima::fastcdr::FastBuffer fb(buffer.data(), buffer.size());
  eprosima::fastcdr::Cdr ser(
      fb, big_endian ? eprosima::fastcdr::Cdr::BIG_ENDIANNESS : eprosima::fastcdr::Cdr::LITTLE_ENDIANNESS,
      eprosima::fastcdr::Cdr::DDS_CDR);
  ser.serialize_encapsulation();
  value.serialize(ser);
  std::vector<std::byte> out(ser.getSerializedDataLength());
  std::memcpy(out.data(), buffer.data(), out.size());
  return out;
}

// Our sample and the generated type's, filled with Value(); compared both ways.
template <typename PubSub, typename Type>
void Check(const robot::IdlMessage& t, const std::function<void(Type&)>& fill,
           const std::function<void(const Type&, dds::DdsSample&)>& read) {
  CAPTURE(t.type_name);
  dds::DdsSample ours(t);
  for (std::uint32_t k = 0; k < t.leaves.size(); ++k) ours.Set(k, Value(t, t.leaves[k].path));
  Type g;
  fill(g);
  const std::vector<std::byte> le = Generated<PubSub>(g, false);
  REQUIRE(le.size() == dds::CdrSampleBytes(t));
  CHECK(std::memcmp(le.data(), ours.bytes(), le.size()) == 0);
  // The generated type's big-endian bytes read the same values here.
  const std::vector<std::byte> be = Generated<PubSub>(g, true);
  REQUIRE(be.size() == le.size());
  bool big = false;
  REQUIRE(dds::ReadCdrHeader(be.data(), &big));
  CHECK(big);
  for (const robot::IdlLeaf& l : t.leaves) {
    CAPTURE(l.path);
    CHECK(dds::DecodeLeaf(l, be.data(), true) == Value(t, l.path));
  }
  // And our bytes deserialise into the generated type with the same values.
  eprosima::fastcdr::FastBuffer fb(reinterpret_cast<char*>(ours.bytes()), le.size());
  eprosima::fastcdr::Cdr des(fb, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
  des.read_encapsulation();
  Type back;
  back.deserialize(des);
  dds::DdsSample again(t);
  read(back, again);
  CHECK(std::memcmp(again.bytes(), ours.bytes(), le.size()) == 0);
}

}  // namespace

TEST_CASE("dds wire: the AUV's sensor sample, command and status are the bytes fastddsgen's types write") {
  const robot::RobotModel& m = test::AuvRobot();
  using pbppo_idl::auv::SensorState;
  const robot::IdlMessage& s = MessageType(m, "sensor_state");
  // Every scalar member of the sensor sample, named alike in the IDL and the generated setters.
  // clang-format off
#define PBPPO_SENSOR(X) \
  X(tick) X(stamp_ns) X(x_m) X(y_m) X(depth_m) X(roll_rad) X(pitch_rad) X(yaw_rad) X(surge_mps) \
  X(sway_mps) X(heave_mps) X(roll_rate_radps) X(pitch_rate_radps) X(yaw_rate_radps) X(sonar_beams) \
  X(target_index) X(target_x_m) X(target_y_m) X(target_distance_m) X(target_bearing_rad) \
  X(route_bearing_rad) X(clearance_m) X(mission_complete) X(episode_end)
// clang-format on
#define PBPPO_SET(f) g.f(static_cast<std::remove_reference_t<decltype(g.f())>>(Value(s, #f)));
#define PBPPO_GET(f) out.Set(#f, static_cast<double>(g.f())).ok();
  Check<pbppo_idl::auv::SensorStatePubSubType, SensorState>(
      s,
      [&](SensorState& g) {
        PBPPO_SENSOR(PBPPO_SET)
        for (std::size_t i = 0; i < g.sonar_m().size(); ++i)
          g.sonar_m()[i] = static_cast<float>(Value(s, "sonar_m[" + std::to_string(i) + "]"));
      },
      [&](const SensorState& g, dds::DdsSample& out) {
        PBPPO_SENSOR(PBPPO_GET)
        for (std::size_t i = 0; i < g.sonar_m().size(); ++i)
          (void)out.Set("sonar_m[" + std::to_string(i) + "]", static_cast<double>(g.sonar_m()[i]));
      });
#undef PBPPO_SENSOR
  const robot::IdlMessage& c = MessageType(m, "command");
#define PBPPO_COMMAND(X) X(tick) X(stamp_ns) X(answers) X(surge_speed_mps) X(yaw_rate_radps) X(mode)
#undef PBPPO_SET
#define PBPPO_SET(f) g.f(static_cast<std::remove_reference_t<decltype(g.f())>>(Value(c, #f)));
  Check<pbppo_idl::auv::CommandPubSubType, pbppo_idl::auv::Command>(
      c, [&](pbppo_idl::auv::Command& g) { PBPPO_COMMAND(PBPPO_SET) },
      [&](const pbppo_idl::auv::Command& g, dds::DdsSample& out) { PBPPO_COMMAND(PBPPO_GET) });
  const robot::IdlMessage& st = MessageType(m, "controller_status");
#define PBPPO_STATUS(X) \
  X(tick)               \
  X(mode)               \
  X(cause) X(deadline_misses) X(stale_samples) X(invalid_samples) X(limited_commands) X(tick_median_us) X(tick_max_us)
#undef PBPPO_SET
#define PBPPO_SET(f) g.f(static_cast<std::remove_reference_t<decltype(g.f())>>(Value(st, #f)));
  Check<pbppo_idl::auv::ControllerStatusPubSubType, pbppo_idl::auv::ControllerStatus>(
      st, [&](pbppo_idl::auv::ControllerStatus& g) { PBPPO_STATUS(PBPPO_SET) },
      [&](const pbppo_idl::auv::ControllerStatus& g, dds::DdsSample& out) { PBPPO_STATUS(PBPPO_GET) });
}

TEST_CASE("dds wire: the quadruped operator's velocity command and status are the bytes fastddsgen's types write") {
  const robot::RobotModel& m = test::QuadrupedRobot();
  const robot::IdlMessage& v = MessageType(m, "velocity_command");
#define PBPPO_VELOCITY(X) X(seq) X(stamp_ns) X(vx_mps) X(vy_mps) X(yaw_rate_radps)
#undef PBPPO_SET
#define PBPPO_SET(f) g.f(static_cast<std::remove_reference_t<decltype(g.f())>>(Value(v, #f)));
  Check<pbppo_idl::quadruped::VelocityCommandPubSubType, pbppo_idl::quadruped::VelocityCommand>(
      v, [&](pbppo_idl::quadruped::VelocityCommand& g) { PBPPO_VELOCITY(PBPPO_SET) },
      [&](const pbppo_idl::quadruped::VelocityCommand& g, dds::DdsSample& out) { PBPPO_VELOCITY(PBPPO_GET) });
  const robot::IdlMessage& s = MessageType(m, "status");
  // clang-format off
#define PBPPO_QSTATUS(X) \
  X(tick) X(phase) X(mode) X(cause) X(commands_received) X(command_vx_mps) X(command_vy_mps) \
  X(command_yaw_rate_radps) X(deadline_misses) X(stale_samples) X(tick_median_us) X(tick_max_us)
  // clang-format on
#undef PBPPO_SET
#define PBPPO_SET(f) g.f(static_cast<std::remove_reference_t<decltype(g.f())>>(Value(s, #f)));
  Check<pbppo_idl::quadruped::QuadrupedStatusPubSubType, pbppo_idl::quadruped::QuadrupedStatus>(
      s, [&](pbppo_idl::quadruped::QuadrupedStatus& g) { PBPPO_QSTATUS(PBPPO_SET) },
      [&](const pbppo_idl::quadruped::QuadrupedStatus& g, dds::DdsSample& out) { PBPPO_QSTATUS(PBPPO_GET) });
}

TEST_CASE("dds wire: integers round to nearest and saturate, NaN writes 0, floats round to nearest") {
  const robot::IdlMessage t = robot::ParseIdlMessage(
                                  "struct T { octet o; short s; unsigned long u; long long ll; unsigned long long ull; "
                                  "float f; boolean b; };",
                                  "t.idl", "", nullptr)
                                  .value();
  dds::DdsSample s(t);
  const struct {
    std::uint32_t leaf;
    double in, out;
  } cases[] = {{0, 2.6, 3},
               {0, -4, 0},
               {0, 300, 255},
               {0, std::nan(""), 0},
               {1, -2.5, -2},
               {1, 1e9, 32767},
               {1, -1e9, -32768},
               {2, 4294967296.0, 4294967295.0},
               {3, -1e300, -9.223372036854775808e18},
               {4, 1e300, 18446744073709551615.0},
               {4, 9007199254740993.0, 9007199254740992.0},
               {5, 0.1, static_cast<double>(0.1f)},
               {6, 0.25, 1},
               {6, 0, 0}};
  for (const auto& c : cases) {
    CAPTURE(c.leaf);
    CAPTURE(c.in);
    s.Set(c.leaf, c.in);
    CHECK(s.Get(c.leaf) == c.out);
  }
}

namespace {

// ROS 2's Joy as models/ros2/idl declares it, with the elements a robot file names: six axes and
// eleven buttons (a game controller's).
robot::IdlMessage JoyLayout() {
  const auto read = [](const std::string& path) -> Result<std::string> {
    std::ifstream f(path);
    if (!f) return MakeError(ErrorCode::kIo, path + " cannot be read");
    std::ostringstream text;
    text << f.rdbuf();
    return text.str();
  };
  const std::string path = test::SourcePath("models/ros2/idl/Joy_.idl");
  robot::IdlMessage m = robot::ParseIdlMessage(read(path).value(), path, "", read).value();
  REQUIRE(m.Element("axes[5]") >= 0);
  REQUIRE(m.Element("buttons[10]") >= 0);
  return m;
}

sensor_msgs::msg::dds_::Joy_ GeneratedJoy(std::size_t axes, std::size_t buttons, const std::string& frame) {
  sensor_msgs::msg::dds_::Joy_ j;
  j.header().stamp().sec(1764400000);
  j.header().stamp().nanosec(123456789u);
  j.header().frame_id(frame);
  for (std::size_t k = 0; k < axes; ++k) j.axes().push_back(static_cast<float>(k) * 0.25f - 0.75f);
  for (std::size_t k = 0; k < buttons; ++k) j.buttons().push_back(static_cast<std::int32_t>(k % 3 == 0));
  return j;
}

}  // namespace

TEST_CASE(
    "dds wire: ROS 2's Joy as fastddsgen's type writes it is read into the robot file's layout, both byte orders") {
  const robot::IdlMessage t = JoyLayout();
  REQUIRE(t.variable());
  // A pad with more axes and buttons than the robot file names, and a frame name: what is named is
  // read, the rest skipped.
  for (const bool big : {false, true}) {
    CAPTURE(big);
    sensor_msgs::msg::dds_::Joy_ g = GeneratedJoy(8, 15, "joy_frame_of_a_long_name");
    const std::vector<std::byte> wire = Generated<sensor_msgs::msg::dds_::Joy_PubSubType>(g, big);
    std::vector<std::byte> ours(dds::CdrSampleBytes(t));
    REQUIRE(dds::NormalizeCdrSample(t, wire.data(), wire.size(), ours.data()));
    bool be = false;
    REQUIRE(dds::ReadCdrHeader(ours.data(), &be));
    CHECK(be == big);
    dds::DdsSample s(t);
    std::memcpy(s.bytes(), ours.data(), ours.size());
    CHECK(s.Get("header.stamp.sec").value() == 1764400000);
    CHECK(s.Get("header.stamp.nanosec").value() == 123456789);
    for (std::size_t k = 0; k < 6; ++k)
      CHECK(s.Get("axes[" + std::to_string(k) + "]").value() == static_cast<double>(g.axes()[k]));
    for (std::size_t k = 0; k < 11; ++k) CHECK(s.Get("buttons[" + std::to_string(k) + "]").value() == g.buttons()[k]);
    // The layout is itself a Joy: fastddsgen's type reads it back (the elements named, no frame).
    eprosima::fastcdr::FastBuffer fb(reinterpret_cast<char*>(ours.data()), ours.size());
    eprosima::fastcdr::Cdr des(fb, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
    des.read_encapsulation();
    sensor_msgs::msg::dds_::Joy_ back;
    back.deserialize(des);
    CHECK(back.header().stamp().sec() == 1764400000);
    CHECK(back.header().frame_id().empty());
    REQUIRE(back.axes().size() == 6);
    REQUIRE(back.buttons().size() == 11);
    CHECK(back.axes()[5] == g.axes()[5]);
    CHECK(back.buttons()[9] == g.buttons()[9]);
  }
  // Exactly as many elements as named, and an empty frame: read.
  sensor_msgs::msg::dds_::Joy_ exact = GeneratedJoy(6, 11, "");
  const std::vector<std::byte> wire = Generated<sensor_msgs::msg::dds_::Joy_PubSubType>(exact, false);
  std::vector<std::byte> out(dds::CdrSampleBytes(t));
  CHECK(dds::NormalizeCdrSample(t, wire.data(), wire.size(), out.data()));
  // Our own sample of the layout is the bytes fastddsgen writes for the same Joy.
  dds::DdsSample ours(t);
  (void)ours.Set("header.stamp.sec", 1764400000);
  (void)ours.Set("header.stamp.nanosec", 123456789);
  for (std::size_t k = 0; k < 6; ++k)
    (void)ours.Set("axes[" + std::to_string(k) + "]", static_cast<double>(exact.axes()[k]));
  for (std::size_t k = 0; k < 11; ++k) (void)ours.Set("buttons[" + std::to_string(k) + "]", exact.buttons()[k]);
  REQUIRE(wire.size() == dds::CdrSampleBytes(t));
  CHECK(std::memcmp(wire.data(), ours.bytes(), wire.size()) == 0);
}

TEST_CASE("dds wire: a Joy with fewer elements than named, cut short, or with a bad string is refused") {
  const robot::IdlMessage t = JoyLayout();
  std::vector<std::byte> out(dds::CdrSampleBytes(t));
  // Fewer axes or buttons than the robot file names.
  for (const auto& [axes, buttons] : {std::pair<std::size_t, std::size_t>{5, 11}, {6, 10}, {0, 0}}) {
    sensor_msgs::msg::dds_::Joy_ g = GeneratedJoy(axes, buttons, "joy");
    const std::vector<std::byte> wire = Generated<sensor_msgs::msg::dds_::Joy_PubSubType>(g, false);
    CHECK_FALSE(dds::NormalizeCdrSample(t, wire.data(), wire.size(), out.data()));
  }
  // Every sample cut short of its end (a length or an element past it) is refused.
  sensor_msgs::msg::dds_::Joy_ g = GeneratedJoy(6, 11, "joy");
  const std::vector<std::byte> wire = Generated<sensor_msgs::msg::dds_::Joy_PubSubType>(g, false);
  CHECK(dds::NormalizeCdrSample(t, wire.data(), wire.size(), out.data()));
  for (std::size_t n = 0; n < wire.size(); ++n) {
    CAPTURE(n);
    std::vector<std::byte> cut(wire.begin(),
                               wire.begin() + static_cast<long>(n));  // its own buffer: ASan sees reads past
    CHECK_FALSE(dds::NormalizeCdrSample(t, cut.data(), cut.size(), out.data()));
  }
  // The frame's length: not terminated by a NUL, or as long as the whole sample; a sequence's count
  // past the end; not plain CDR.
  auto patched = [&](std::size_t at, std::uint32_t value) {
    std::vector<std::byte> w = wire;
    for (std::size_t k = 0; k < 4; ++k) w.at(at + k) = static_cast<std::byte>((value >> (8 * k)) & 0xffu);
    return w;
  };
  const std::size_t frame_length = 4 + 8, axes_count = 4 + 16;  // header, then sec, nanosec; "joy\0" at 12..15
  for (const std::vector<std::byte>& w : {patched(frame_length, 3), patched(frame_length, 0x7fffffffu),
                                          patched(axes_count, 0xffffffffu), patched(axes_count, 1000)}) {
    CHECK_FALSE(dds::NormalizeCdrSample(t, w.data(), w.size(), out.data()));
  }
  std::vector<std::byte> xcdr2 = wire;
  xcdr2[1] = std::byte{0x07};
  CHECK_FALSE(dds::NormalizeCdrSample(t, xcdr2.data(), xcdr2.size(), out.data()));
  // A string over its bound, a sequence over its bound.
  const robot::IdlMessage bounded =
      robot::ParseIdlMessage("struct B { string<3> name; sequence<long, 2> v; };", "b.idl", "", nullptr).value();
  const auto sample = [](std::initializer_list<std::uint8_t> bytes) {
    std::vector<std::byte> v{std::byte{0}, std::byte{1}, std::byte{0}, std::byte{0}};
    for (const std::uint8_t b : bytes) v.push_back(static_cast<std::byte>(b));
    return v;
  };
  std::vector<std::byte> o(dds::CdrSampleBytes(bounded));
  const std::vector<std::byte> fits = sample({4, 0, 0, 0, 'a', 'b', 'c', 0, 2, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0});
  CHECK(dds::NormalizeCdrSample(bounded, fits.data(), fits.size(), o.data()));
  const std::vector<std::byte> long_name = sample({5, 0, 0, 0, 'a', 'b', 'c', 'd', 0, 0, 0, 0, 0, 0, 0, 0});
  CHECK_FALSE(dds::NormalizeCdrSample(bounded, long_name.data(), long_name.size(), o.data()));
  const std::vector<std::byte> three = sample({1, 0, 0, 0, 0, 0, 0, 0, 3, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0});
  CHECK_FALSE(dds::NormalizeCdrSample(bounded, three.data(), three.size(), o.data()));
}
