// A robot's DDS transport as the robot file declares it, between two real Fast DDS participants of
// one process over loopback (label dds): the controller's side (dds::DdsTransport: samples into
// the robot's fields, commands and status out by the robot file's values) and the peer's side
// (dds::DdsLink, as a simulator or an operator uses it). Samples of another size, encoding or
// byte order, a full queue, a peer that leaves, the tick's calls without allocation, ROS 2 names.
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/robot/robot_data.hpp"
#include "runtime/transport/dds/cdr.hpp"
#include "runtime/transport/dds/dds_transport.hpp"
#include "tests/support/dds_domain.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/text_edit.hpp"

using namespace pbppo;
using dds::DdsLink;
using dds::DdsSample;
using dds::DdsSide;
using dds::DdsTransport;

namespace {

constexpr std::int64_t kSecond = 1'000'000'000;

template <typename Pred>
bool Eventually(Pred p, std::int64_t ns = 5 * kSecond) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::nanoseconds(ns);
  while (std::chrono::steady_clock::now() < end) {
    if (p()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return p();
}

dds::DdsLinkOptions Options(int domain, dds::DdsNaming naming = dds::DdsNaming::kNative) {
  dds::DdsLinkOptions o;
  o.domain_id = domain;
  o.naming = naming;
  return o;
}

std::size_t Message(DdsLink& l, const char* topic) {
  auto i = l.MessageIndex(topic);
  REQUIRE_MESSAGE(i.ok(), i.error().message);
  return *i;
}

std::uint32_t FieldOf(const robot::RobotModel& m, const std::string& name) {
  const int k = m.FieldIndex(name);
  REQUIRE_MESSAGE(k >= 0, name);
  return static_cast<std::uint32_t>(k);
}

// The AUV's controller side and a vehicle (peer) side on one domain, matched.
struct Pair {
  const robot::RobotModel& m = test::AuvRobot();
  std::unique_ptr<DdsTransport> controller;
  std::unique_ptr<DdsLink> vehicle;
  robot::RobotData data = robot::MakeRobotData(m);
  explicit Pair(int domain, dds::DdsLinkOptions o = {}) {
    o.domain_id = domain;
    auto c = DdsTransport::Open(m, "dds", o);
    REQUIRE_MESSAGE(c.ok(), c.error().message);
    controller = std::move(*c);
    auto v = DdsLink::Open(m, "dds", DdsSide::kPeer, Options(domain, o.naming));
    REQUIRE_MESSAGE(v.ok(), v.error().message);
    vehicle = std::move(*v);
    REQUIRE(controller->Connect(10 * kSecond).ok());
    REQUIRE(vehicle->WaitForPeer(10 * kSecond));
  }
  // The sensor stream's fields, each its own value; the sample the vehicle sends of them.
  std::vector<double> Fields(double base) const {
    std::vector<double> f(m.fields.size(), 0.0);
    const robot::StreamSpec& s = m.streams[static_cast<std::size_t>(m.StreamIndex("sensor"))];
    for (std::uint32_t k = 0; k < s.field_count; ++k) f[s.first_field + k] = base + 0.25 * k;
    // The integer and boolean members, whole.
    f[FieldOf(m, "tick")] = 7;
    f[FieldOf(m, "target_index")] = 2;
    f[FieldOf(m, "sonar_beams")] = 16;
    f[FieldOf(m, "mission_complete")] = 1;
    f[FieldOf(m, "episode_end")] = 0;
    return f;
  }
  void Send(const std::vector<double>& fields) {
    const std::size_t i = Message(*vehicle, "sensor_state");
    DdsSample s(vehicle->message(i).type);
    vehicle->FillFromFields(i, fields, &s);
    REQUIRE(vehicle->writer(i)->Write(s.bytes()).ok());
  }
};

// The Go2's controller side and the robot's side of its low-level transport on one domain, matched.
struct Go2Pair {
  const robot::RobotModel& m;
  std::unique_ptr<DdsTransport> controller;
  std::unique_ptr<DdsLink> robot;
  explicit Go2Pair(int domain, const robot::RobotModel& model = test::Go2Robot()) : m(model) {
    auto c = DdsTransport::Open(m, "lowlevel", Options(domain));
    REQUIRE_MESSAGE(c.ok(), c.error().message);
    controller = std::move(*c);
    auto r = DdsLink::Open(m, "lowlevel", DdsSide::kPeer, Options(domain));
    REQUIRE_MESSAGE(r.ok(), r.error().message);
    robot = std::move(*r);
    REQUIRE(controller->Connect(10 * kSecond).ok());
    REQUIRE(robot->WaitForPeer(10 * kSecond));
  }
};

}  // namespace

TEST_CASE("dds transport: a sample fills the stream's fields, commands and status carry the robot file's values") {
  Pair p(test::TestDomain(1));
  const std::vector<double> sent = p.Fields(3.0);
  p.Send(sent);
  std::uint64_t version = 0;
  const auto sensor = static_cast<std::uint32_t>(p.m.StreamIndex("sensor"));
  CHECK(p.controller->Paces(sensor));
  REQUIRE(p.controller->WaitForSample(sensor, &version, 5 * kSecond));
  CHECK(version == 1);
  p.controller->Read(p.m, p.data);
  CHECK(p.data.fresh[sensor] == 1);
  const robot::StreamSpec& s = p.m.streams[sensor];
  for (std::uint32_t f = s.first_field; f < s.first_field + s.field_count; ++f) {
    CAPTURE(p.m.fields[f].name);
    // The IDL's float sonar ranges are the ranges rounded to float; a boolean is 0 or 1.
    const bool sonar = p.m.fields[f].name.rfind("sonar_", 0) == 0 && p.m.fields[f].name != "sonar_beams";
    CHECK(p.data.fields[f] == (sonar ? static_cast<double>(static_cast<float>(sent[f])) : sent[f]));
  }
  // Read again without a new sample: nothing fresh.
  p.data.fresh[sensor] = 0;
  p.controller->Read(p.m, p.data);
  CHECK(p.data.fresh[sensor] == 0);

  p.data.tick = 8;
  p.data.mode = safety::Mode::kSafeStop;
  p.data.command[static_cast<std::size_t>(p.m.CommandIndex("surge_speed"))] = 1.125;
  p.data.command[static_cast<std::size_t>(p.m.CommandIndex("yaw_rate"))] = -0.375;
  p.controller->Write(p.m, p.data);
  const std::size_t ci = Message(*p.vehicle, "command");
  DdsSample got(p.vehicle->message(ci).type);
  REQUIRE(p.vehicle->reader(ci)->WaitPop(got.bytes(), nullptr, 5 * kSecond));
  CHECK(got.Get("tick").value() == 8);
  CHECK(got.Get("answers").value() == 7);  // the tick field of the sample it answers
  CHECK(got.Get("surge_speed_mps").value() == 1.125);
  CHECK(got.Get("yaw_rate_radps").value() == -0.375);
  CHECK(got.Get("mode").value() == 2);
  CHECK(got.Get("stamp_ns").value() > 0);

  robot::ControllerStatus st;
  st.tick = 40;
  st.cause = 0x24;
  st.deadline_misses = 3;
  st.counts[safety::Cause::kInvalidSample] = 4;
  st.counts[safety::Cause::kCommandLimit] = 5;
  st.counts[safety::Cause::kRateLimit] = 6;
  st.tick_max_us = 12.5;
  p.controller->PublishStatus(st);
  const std::size_t si = Message(*p.vehicle, "controller_status");
  DdsSample status(p.vehicle->message(si).type);
  CHECK(Eventually([&] { return p.vehicle->reader(si)->Read(status.bytes(), nullptr) != 0; }));
  CHECK(status.Get("tick").value() == 40);
  CHECK(status.Get("cause").value() == 0x24);
  CHECK(status.Get("deadline_misses").value() == 3);
  CHECK(status.Get("invalid_samples").value() == 4);
  CHECK(status.Get("limited_commands").value() == 11);  // command limit + rate limit
  CHECK(status.Get("tick_max_us").value() == 12.5);
  CHECK(p.data.transports[0].lost == false);
  CHECK(p.data.transports[0].degraded == false);
  const dds::DdsLinkCounters c = p.controller->link().counters();
  CHECK(c.received == 1);
  CHECK(c.malformed == 0);
  CHECK(Eventually([&] { return p.controller->link().counters().written == 2; }));  // the command and the status
  CHECK(p.controller->Summary().find("transport dds (dds): received 1 (malformed 0), sent 2") == 0);
}

TEST_CASE("dds transport: samples of another size or encoding are refused and counted, big-endian ones read") {
  Pair p(test::TestDomain(2));
  const robot::DdsMessageSpec& spec = p.vehicle->message(Message(*p.vehicle, "sensor_state"));
  // A writer of the same topic and type name, but a struct of another size: malformed.
  auto other = robot::ParseIdlMessage("module pbppo_idl { module auv { struct SensorState { double x_m; }; }; };",
                                      "other.idl", "", nullptr);
  REQUIRE(other.ok());
  dds::DdsOptions o;
  o.profile_file = test::DdsProfile();
  o.domain_id = test::TestDomain(2);
  auto participant = dds::DdsParticipant::Create(o);
  REQUIRE(participant.ok());
  auto small = dds::DdsWriter::Create(**participant, "pbppo/auv/sensor_state", *other, {});
  REQUIRE(small.ok());
  REQUIRE(Eventually([&] { return (*small)->matched_readers() > 0; }));
  DdsSample tiny(*other);
  tiny.Set(0, 1.5);
  REQUIRE((*small)->Write(tiny.bytes()).ok());
  REQUIRE(Eventually([&] { return p.controller->link().counters().malformed == 1; }));
  p.controller->Read(p.m, p.data);
  CHECK(p.data.fresh[0] == 0);           // nothing delivered
  CHECK(p.data.transports[0].degraded);  // and the link says so, once
  p.controller->Read(p.m, p.data);
  CHECK_FALSE(p.data.transports[0].degraded);

  // A big-endian sample of the right type (as a big-endian machine writes it) reads the same.
  const std::vector<double> fields = p.Fields(-7.0);
  DdsSample le(spec.type);
  p.vehicle->FillFromFields(Message(*p.vehicle, "sensor_state"), fields, &le);
  std::vector<std::byte> be(le.bytes(), le.bytes() + dds::CdrSampleBytes(spec.type));
  be[1] = std::byte{0x00};  // CDR_BE
  for (const robot::IdlLeaf& l : spec.type.leaves)
    std::reverse(be.begin() + static_cast<long>(4 + l.cdr_offset),
                 be.begin() + static_cast<long>(4 + l.cdr_offset + robot::IdlScalarSize(l.type)));
  REQUIRE(p.vehicle->writer(Message(*p.vehicle, "sensor_state"))->Write(be.data()).ok());
  std::uint64_t version = 0;
  REQUIRE(p.controller->WaitForSample(0, &version, 5 * kSecond));
  p.controller->Read(p.m, p.data);
  CHECK(p.data.fresh[0] == 1);
  CHECK(p.data.fields[FieldOf(p.m, "x_m")] == fields[FieldOf(p.m, "x_m")]);
  CHECK(p.data.fields[FieldOf(p.m, "clearance_m")] == fields[FieldOf(p.m, "clearance_m")]);
  CHECK(p.data.fields[FieldOf(p.m, "sonar_5_m")] ==
        static_cast<double>(static_cast<float>(fields[FieldOf(p.m, "sonar_5_m")])));
  CHECK(p.controller->link().counters().malformed == 1);
}

TEST_CASE("dds transport: ROS 2 naming - both sides on rt/ topics with ROS 2 type names, not heard by native ones") {
  const int domain = test::TestDomain(7);
  dds::DdsLinkOptions ros2;
  ros2.naming = dds::DdsNaming::kRos2;
  Pair p(domain, ros2);
  auto native = DdsTransport::Open(p.m, "dds", Options(domain));
  REQUIRE(native.ok());
  p.Send(p.Fields(5.0));
  std::uint64_t version = 0;
  REQUIRE(p.controller->WaitForSample(0, &version, 10 * kSecond));
  p.controller->Read(p.m, p.data);
  CHECK(p.data.fields[FieldOf(p.m, "x_m")] == p.Fields(5.0)[FieldOf(p.m, "x_m")]);
  CHECK(p.vehicle->wire_topic(0) == "rt/pbppo/auv/sensor_state");
  CHECK_FALSE((*native)->link().WaitForPeer(kSecond / 2));
  CHECK((*native)->link().counters().received == 0);
  CHECK(dds::WireTypeName(dds::DdsNaming::kRos2, "pbppo_idl::auv::Command", "AuvCommand") ==
        "pbppo_msgs::msg::dds_::AuvCommand_");
  CHECK(dds::WireTypeName(dds::DdsNaming::kNative, "pbppo_idl::auv::Command", "AuvCommand") ==
        "pbppo_idl::auv::Command");
  auto bad = dds::ParseDdsNaming("ros");
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("'ros'") != std::string::npos);
}

TEST_CASE("dds transport: a full command queue drops and counts (the link degraded), the rest arrives in order") {
  dds::DdsLinkOptions o;
  o.out_queue_capacity = 2;
  Pair p(test::TestDomain(3), o);
  constexpr std::uint64_t kWrites = 20000;
  for (std::uint64_t i = 1; i <= kWrites; ++i) {
    p.data.tick = i;
    p.controller->Write(p.m, p.data);
  }
  const std::uint64_t dropped = p.controller->send_failures();
  REQUIRE(Eventually([&] {
    const auto c = p.controller->link().counters();
    return c.written + c.write_failed == kWrites - dropped;
  }));
  CHECK(dropped > 0);
  CHECK(p.controller->link().counters().push_dropped == dropped);
  p.controller->Read(p.m, p.data);
  CHECK(p.data.transports[0].degraded);
  const std::size_t ci = Message(*p.vehicle, "command");
  DdsSample got(p.vehicle->message(ci).type);
  double last = 0;
  std::uint64_t disorder = 0, n = 0;
  while (p.vehicle->reader(ci)->WaitPop(got.bytes(), nullptr, kSecond / 2)) {
    if (got.Get("tick").value() <= last) ++disorder;
    last = got.Get("tick").value();
    ++n;
  }
  CHECK(n > 0);
  CHECK(disorder == 0);
}

TEST_CASE("dds transport: a vehicle that leaves is a lost link, one that never came is not") {
  const robot::RobotModel& m = test::AuvRobot();
  const int domain = test::TestDomain(4);
  auto o = Options(domain);
  o.lost_after_s = 0.2;
  auto controller = DdsTransport::Open(m, "dds", o);
  REQUIRE(controller.ok());
  robot::RobotData d = robot::MakeRobotData(m);
  (*controller)->Read(m, d);
  CHECK_FALSE(d.transports[0].lost);  // nothing received yet: the stream's age tells
  {
    auto vehicle = DdsLink::Open(m, "dds", DdsSide::kPeer, Options(domain));
    REQUIRE(vehicle.ok());
    REQUIRE((*controller)->Connect(10 * kSecond).ok());
    REQUIRE((*vehicle)->WaitForPeer(10 * kSecond));
    DdsSample s((*vehicle)->message(0).type);
    REQUIRE((*vehicle)->writer(0)->Write(s.bytes()).ok());
    std::uint64_t version = 0;
    REQUIRE((*controller)->WaitForSample(0, &version, 5 * kSecond));
    (*controller)->Read(m, d);
    CHECK_FALSE(d.transports[0].lost);
  }
  CHECK(Eventually([&] {
    (*controller)->Read(m, d);
    return d.transports[0].lost;
  }));
  // Without a peer the robot file's wait_for_peer fails, naming the transport and the domain.
  auto alone = DdsTransport::Open(m, "dds", Options(test::TestDomain(40)));
  REQUIRE(alone.ok());
  const Status st = (*alone)->Connect(kSecond / 5);
  REQUIRE_FALSE(st.ok());
  CHECK(st.error().message.find("transport 'dds': no peer on DDS domain " + std::to_string(test::TestDomain(40))) == 0);
}

TEST_CASE("dds transport: bad options and robot files name the option, the transport and the value") {
  const robot::RobotModel& m = test::AuvRobot();
  auto o = Options(300);
  auto r = DdsTransport::Open(m, "dds", o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("domain_id 300") != std::string::npos);
  o.domain_id = test::TestDomain(5);
  o.out_queue_capacity = 0;
  r = DdsTransport::Open(m, "dds", o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("out_queue_capacity 0") != std::string::npos);
  o.out_queue_capacity = 16;
  o.profile_file = "/nonexistent/profile.xml";
  r = DdsTransport::Open(m, "dds", o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("/nonexistent/profile.xml") != std::string::npos);
  o.profile_file.clear();
  r = DdsTransport::Open(m, "can", o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("no transport 'can' of kind dds") != std::string::npos);
  // A participant profile the robot's profiles lack.
  const test::RobotFileEdits edits("auv", "dds_transport_profile");
  const std::string text = test::ReplaceOnce(test::ReadText(edits.path()), "participant_profile: pbppo_loopback",
                                             "participant_profile: no_such_profile");
  std::ofstream(edits.path()) << text;
  auto edited = robot::LoadRobotModel(edits.path());
  REQUIRE(edited.ok());
  r = DdsTransport::Open(*edited, "dds", Options(test::TestDomain(5)));
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("no_such_profile") != std::string::npos);
}

TEST_CASE("dds transport: the tick's calls (Read, Write) do not allocate in the calling thread") {
  Pair p(test::TestDomain(6));
  p.Send(p.Fields(1.0));
  std::uint64_t version = 0;
  REQUIRE(p.controller->WaitForSample(0, &version, 5 * kSecond));
  std::uint64_t allocations = 0, fresh = 0;
  {
    AllocationScope scope;
    for (std::uint64_t k = 0; k < 2000; ++k) {
      p.data.fresh[0] = 0;
      p.controller->Read(p.m, p.data);
      fresh += p.data.fresh[0];
      p.data.tick = k;
      p.controller->Write(p.m, p.data);
    }
    allocations = scope.count();
  }
  CHECK(allocations == 0);
  CHECK(fresh == 1);  // one sample, taken once
  CHECK(Eventually([&] {
    const auto c = p.controller->link().counters();
    return c.written == 2000 - p.controller->send_failures();
  }));
}

TEST_CASE("dds transport: the Go2's LowState_ fills the state, motor and IMU streams, and its CRC is checked") {
  const Go2Pair pair(test::TestDomain(9));
  const robot::RobotModel& m = pair.m;
  DdsTransport& controller = *pair.controller;
  DdsLink& go2 = *pair.robot;
  robot::RobotData d = robot::MakeRobotData(m);
  const std::size_t si = Message(go2, "lowstate"), ci = Message(go2, "lowcmd");
  const robot::DdsMessageSpec& spec = go2.message(si);
  std::vector<double> fields(m.fields.size(), 0.0);
  for (std::size_t k = 0; k < m.motors.size(); ++k) {
    fields[m.motors[k].q_field] = 0.125 * static_cast<double>(k) - 0.5;
    fields[m.motors[k].dq_field] = 0.5;
    fields[m.motors[k].tau_field] = -1.25;
  }
  fields[FieldOf(m, "imu_qw")] = 1.0;
  fields[FieldOf(m, "tick")] = 41;
  fields[FieldOf(m, "foot_force_2")] = 37;
  fields[FieldOf(m, "remote_5")] = 200;
  DdsSample s(spec.type);
  go2.FillFromFields(si, fields, &s);
  CHECK(go2.ChecksumMatches(si, s));
  std::uint64_t version = 0;
  const auto state = FieldOf(m, "crc_ok");
  const std::uint32_t state_stream = m.fields[state].stream;
  REQUIRE(go2.writer(si)->Write(s.bytes()).ok());
  REQUIRE(controller.WaitForSample(state_stream, &version, 5 * kSecond));
  controller.Read(m, d);
  for (const std::uint32_t st : spec.streams) CHECK(d.fresh[st] == 1);
  CHECK(d.fields[state] == 1.0);
  CHECK(d.fields[FieldOf(m, "tick")] == 41);
  CHECK(d.fields[FieldOf(m, "foot_force_2")] == 37);
  CHECK(d.fields[FieldOf(m, "remote_5")] == 200);
  CHECK(d.fields[m.motors[7].q_field] == 0.375);
  CHECK(d.fields[m.motors[7].tau_field] == -1.25);

  // One bit of the CRC wrong: crc_ok says 0 (the sample check names it), the state stream alone is
  // fresh and no other field takes the sample's values.
  std::fill(d.fresh.begin(), d.fresh.end(), std::uint8_t{0});
  fields[m.motors[7].q_field] = 1.0;
  go2.FillFromFields(si, fields, &s);
  const auto crc = static_cast<std::uint32_t>(s.Get("crc").value());
  REQUIRE(s.Set("crc", static_cast<double>(crc ^ 0x80000000u)).ok());
  CHECK_FALSE(go2.ChecksumMatches(si, s));
  REQUIRE(go2.writer(si)->Write(s.bytes()).ok());
  REQUIRE(controller.WaitForSample(state_stream, &version, 5 * kSecond));
  controller.Read(m, d);
  CHECK(d.fields[state] == 0.0);
  CHECK(d.fresh[state_stream] == 1);
  CHECK(d.fresh[m.motors[7].stream] == 0);
  CHECK(d.fields[m.motors[7].q_field] == 0.375);
  CHECK(controller.checksum_mismatches() == 1);
  CHECK(controller.Summary().find("checksum mismatches 1") != std::string::npos);

  // LowCmd_: passive (mode 0, every command 0) while the loop does not command a motor; its mode
  // and commands once it does; a CRC the robot accepts either way.
  for (std::size_t k = 0; k < d.command.size(); ++k) d.command[k] = 0.5 + static_cast<double>(k % 7);
  d.motors.assign(m.motors.size(), robot::MotorCommand::kNone);
  d.motors[3] = robot::MotorCommand::kEnable;
  d.motors[4] = robot::MotorCommand::kCommand;
  controller.Write(m, d);
  DdsSample cmd(go2.message(ci).type);
  REQUIRE(go2.reader(ci)->WaitPop(cmd.bytes(), nullptr, 5 * kSecond));
  CHECK(go2.ChecksumMatches(ci, cmd));
  CHECK(cmd.Get("head[0]").value() == 0xFE);
  CHECK(cmd.Get("head[1]").value() == 0xEF);
  CHECK(cmd.Get("level_flag").value() == 0xFF);
  CHECK(cmd.Get("motor_cmd[0].mode").value() == 0);
  CHECK(cmd.Get("motor_cmd[0].kp").value() == 0);
  CHECK(cmd.Get("motor_cmd[3].mode").value() == 1);  // switched on: servo mode, no gains yet
  CHECK(cmd.Get("motor_cmd[3].kd").value() == 0);
  CHECK(cmd.Get("motor_cmd[4].mode").value() == 1);
  const robot::MotorSpec& mo = m.motors[4];
  CHECK(cmd.Get("motor_cmd[4].q").value() == static_cast<float>(d.command[mo.q]));
  CHECK(cmd.Get("motor_cmd[4].kp").value() == static_cast<float>(d.command[mo.kp]));
  CHECK(cmd.Get("motor_cmd[4].kd").value() == static_cast<float>(d.command[mo.kd]));
  CHECK(cmd.Get("motor_cmd[4].tau").value() == static_cast<float>(d.command[mo.tau]));
  CHECK(cmd.Get("motor_cmd[12].mode").value() == 0);  // the robot's 8 motors beyond the legs: untouched
  // The tick's calls allocate nothing.
  {
    AllocationScope scope;
    controller.Read(m, d);
    controller.Write(m, d);
    CHECK(scope.count() == 0);
  }
}

TEST_CASE("dds transport: a motor's count of lost frames arrives as its growth per sample, a wrap one step") {
  const Go2Pair pair(test::TestDomain(10));
  const robot::RobotModel& m = pair.m;
  DdsTransport& controller = *pair.controller;
  DdsLink& go2 = *pair.robot;
  robot::RobotData d = robot::MakeRobotData(m);
  const std::size_t si = Message(go2, "lowstate");
  const std::uint32_t state_stream = m.fields[FieldOf(m, "crc_ok")].stream;
  REQUIRE(m.motors[7].lost_field >= 0);
  const auto lost = static_cast<std::size_t>(m.motors[7].lost_field);
  std::vector<double> fields(m.fields.size(), 0.0);
  fields[FieldOf(m, "imu_qw")] = 1.0;
  DdsSample s(go2.message(si).type);
  std::uint64_t version = 0;
  // The robot's counter says COUNT (a correct CRC unless `corrupt`); what the controller reads.
  auto send = [&](double count, bool corrupt = false) {
    REQUIRE(s.Set("motor_state[7].lost", count).ok());
    go2.FillFromFields(si, fields, &s);  // adds 0 to the count, computes the CRC
    if (corrupt) REQUIRE(s.Set("crc", static_cast<double>(static_cast<std::uint32_t>(s.Get("crc").value()) ^ 1u)).ok());
    REQUIRE(go2.writer(si)->Write(s.bytes()).ok());
    REQUIRE(controller.WaitForSample(state_stream, &version, 5 * kSecond));
    controller.Read(m, d);
    return d.fields[lost];
  };
  CHECK(send(5) == 0.0);  // the first sample: the baseline, no growth yet
  CHECK(send(5) == 0.0);
  CHECK(send(7) == 2.0);
  CHECK(send(7) == 0.0);
  // A sample whose CRC does not match moves neither the field nor the baseline.
  CHECK(send(100, true) == 0.0);
  CHECK(d.fields[FieldOf(m, "crc_ok")] == 0.0);
  CHECK(send(8) == 1.0);
  // The counter wraps at 2^32: one step, not a huge one; a counter that restarts from 0 is a large
  // growth (the sample is then outside its bounds).
  CHECK(send(4294967295.0) == 4294967287.0);
  CHECK(send(0) == 1.0);
  CHECK(send(0) == 0.0);
  // The simulator's side: the field is how much to add to the count the sample holds.
  fields[lost] = 3;
  REQUIRE(s.Set("motor_state[7].lost", 4294967294.0).ok());
  go2.FillFromFields(si, fields, &s);
  CHECK(s.Get("motor_state[7].lost").value() == 4294967294.0 + 3 - 4294967296.0);
  CHECK(go2.ChecksumMatches(si, s));
  // Other motors' counters stay where they were.
  CHECK(s.Get("motor_state[6].lost").value() == 0.0);
}

TEST_CASE(
    "dds transport: the Go2's wireless remote inside LowState_ - keys as bits, sticks as float32 shaped, a NaN stick "
    "is invalid") {
  // models/go2_remote: the 40-byte record's keys (uint16 from byte 2: bit 1 L1, 2 START, 14 DOWN)
  // and sticks (float32: lx from byte 4, rx from 8, ly from 20) onto the remote stream's fields.
  const Go2Pair pair(test::TestDomain(11), test::Go2RemoteRobot());
  const robot::RobotModel& m = pair.m;
  DdsTransport& controller = *pair.controller;
  DdsLink& go2 = *pair.robot;
  robot::RobotData d = robot::MakeRobotData(m);
  const std::size_t si = Message(go2, "lowstate");
  const std::uint32_t remote = m.fields[FieldOf(m, "deadman")].stream;
  std::vector<double> fields(m.fields.size(), 0.0);
  fields[FieldOf(m, "imu_qw")] = 1.0;
  fields[FieldOf(m, "arm")] = 1;
  fields[FieldOf(m, "deadman")] = 1;
  fields[FieldOf(m, "sit")] = 1;
  fields[FieldOf(m, "command_vy")] = -0.25;      // lx 0.55: right, past the 0.1 dead zone, x -0.5
  fields[FieldOf(m, "command_yaw_rate")] = 0.5;  // rx -0.55: left
  DdsSample s(go2.message(si).type);
  go2.FillFromFields(si, fields, &s);
  // The record as the robot lays it out.
  CHECK(s.Get("wireless_remote[2]").value() == 6);   // L1 | START
  CHECK(s.Get("wireless_remote[3]").value() == 64);  // DOWN (bit 14)
  const auto float_at = [&](int at) {
    std::uint32_t bits = 0;
    for (int k = 0; k < 4; ++k)
      bits |= static_cast<std::uint32_t>(s.Get("wireless_remote[" + std::to_string(at + k) + "]").value()) << (8 * k);
    float f = 0;
    std::memcpy(&f, &bits, sizeof f);
    return f;
  };
  CHECK(float_at(4) == 0.55f);
  CHECK(float_at(8) == -0.55f);
  CHECK(float_at(20) == 0.0f);
  std::uint64_t version = 0;
  const auto send = [&] {
    REQUIRE(go2.writer(si)->Write(s.bytes()).ok());
    REQUIRE(controller.WaitForSample(remote, &version, 5 * kSecond));
    controller.Read(m, d);
    loop::CheckSample(m, d);
  };
  send();
  CHECK(d.fields[FieldOf(m, "arm")] == 1.0);
  CHECK(d.fields[FieldOf(m, "deadman")] == 1.0);
  CHECK(d.fields[FieldOf(m, "sit")] == 1.0);
  CHECK(d.fields[FieldOf(m, "walk")] == 0.0);
  CHECK(d.fields[FieldOf(m, "estop")] == 0.0);
  CHECK(d.fields[FieldOf(m, "command_vy")] == doctest::Approx(-0.25).epsilon(1e-6));
  CHECK(d.fields[FieldOf(m, "command_yaw_rate")] == doctest::Approx(0.5).epsilon(1e-6));
  CHECK(d.fields[FieldOf(m, "command_vx")] == 0.0);
  CHECK(d.streams[remote].invalid_input < 0);
  // Written by hand: ly 0.05 (inside the dead zone: 0) and 1.0 (full forward: 1 m/s); the other
  // keys' bits untouched by a field's.
  const auto put_float = [&](int at, float f) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &f, sizeof bits);
    for (int k = 0; k < 4; ++k)
      REQUIRE(s.Set("wireless_remote[" + std::to_string(at + k) + "]", static_cast<double>((bits >> (8 * k)) & 0xffu))
                  .ok());
    go2.Seal(si, &s);
  };
  put_float(20, 0.05f);
  send();
  CHECK(d.fields[FieldOf(m, "command_vx")] == 0.0);
  put_float(20, 1.0f);
  send();
  CHECK(d.fields[FieldOf(m, "command_vx")] == 1.0);
  // A stick that is no number, or outside [-1, 1]: NaN, and the sample check names the field.
  put_float(20, std::nanf(""));
  send();
  CHECK(std::isnan(d.fields[FieldOf(m, "command_vx")]));
  CHECK(d.streams[remote].invalid_input == static_cast<std::int32_t>(FieldOf(m, "command_vx")));
  put_float(20, 0.0f);
  put_float(8, 1.5f);
  send();
  CHECK(d.streams[remote].invalid_input == static_cast<std::int32_t>(FieldOf(m, "command_yaw_rate")));
  // A key released: its bit clears, the others stay.
  fields[FieldOf(m, "sit")] = 0;
  go2.FillFromFields(si, fields, &s);
  CHECK(s.Get("wireless_remote[3]").value() == 0);
  CHECK(s.Get("wireless_remote[2]").value() == 6);
  send();
  CHECK(d.fields[FieldOf(m, "sit")] == 0.0);
  CHECK(d.fields[FieldOf(m, "arm")] == 1.0);
  CHECK(d.streams[remote].invalid_input < 0);

  // In the loop: START arms (the motors answering: stand-up), SELECT is the e-stop at its sample's
  // tick, the motors then switched off.
  std::fill(fields.begin(), fields.end(), 0.0);
  fields[FieldOf(m, "imu_qw")] = 1.0;
  for (const robot::MotorSpec& mo : m.motors) fields[mo.q_field] = mo.default_q_rad;
  robot::RobotData ld = robot::MakeRobotData(m);
  auto l = loop::MakeLoopData(m, nullptr);
  robot::Transport* ts[] = {&controller};
  const auto tick = [&](std::uint64_t k) {
    go2.FillFromFields(si, fields, &s);
    REQUIRE(go2.writer(si)->Write(s.bytes()).ok());
    REQUIRE(controller.WaitForSample(remote, &version, 5 * kSecond));
    rt::TickTiming t;
    t.tick = k;
    (void)loop::Tick(m, ld, *l, ts, t);
  };
  tick(0);
  CHECK(l->phase() == loop::Phase::kDisarmed);
  fields[FieldOf(m, "arm")] = 1;
  tick(1);
  CHECK(l->phase() == loop::Phase::kArming);
  tick(2);
  CHECK(l->phase() == loop::Phase::kStandUp);
  fields[FieldOf(m, "estop")] = 1;
  tick(3);
  CHECK(l->supervisor().mode == safety::Mode::kEStop);
  // The robot file's e-stop damps (supervisor.estop: damping): motors on, no stiffness.
  REQUIRE(m.supervisor_model.estop_damps);
  CHECK(ld.motors[0] == robot::MotorCommand::kCommand);
  CHECK(ld.command[m.motors[0].kp] == 0.0);
  CHECK(ld.command[m.motors[0].kd] > 0.0);
  CHECK(l->operator_status().requests == 2);
}
