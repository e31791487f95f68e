// The AUV DDS link with two real Fast DDS participants in one process (controller side and
// vehicle side) on the loopback interface, configured by models/dds_profile.xml.
#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <thread>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/transport/dds/auv_dds_link.hpp"
#include "runtime/transport/dds/auv_message_check.hpp"
#include "tests/support/dds_domain.hpp"

using namespace pbppo;
using dds::AuvDdsLink;
using dds::AuvDdsRole;

namespace {

constexpr std::int64_t kSecond = 1'000'000'000;

std::unique_ptr<AuvDdsLink> Make(AuvDdsRole role, int domain, std::size_t queue = 16,
                                 dds::DdsNaming naming = dds::DdsNaming::kNative) {
  dds::AuvDdsOptions o;
  o.profile_file = test::DdsProfile();
  o.domain_id = domain;
  o.command_queue_capacity = queue;
  o.naming = naming;
  auto r = AuvDdsLink::Create(role, o);
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  return std::move(*r);
}

struct Pair {
  std::unique_ptr<AuvDdsLink> vehicle, controller;
  explicit Pair(int domain, std::size_t queue = 16)
      : vehicle(Make(AuvDdsRole::kVehicle, domain)), controller(Make(AuvDdsRole::kController, domain, queue)) {
    REQUIRE(vehicle->WaitForPeer(10 * kSecond));
    REQUIRE(controller->WaitForPeer(10 * kSecond));
  }
};

robot::AuvSensorSample Distinct(std::uint64_t tick) {
  robot::AuvSensorSample s;
  s.tick = tick;
  s.stamp_ns = 123'456'789;
  s.x_m = 1.5;
  s.y_m = -2.25;
  s.depth_m = 5.125;
  s.roll_rad = 0.01;
  s.pitch_rad = -0.02;
  s.yaw_rad = 3.0;
  s.surge_mps = 1.25;
  s.sway_mps = -0.125;
  s.heave_mps = 0.0625;
  s.roll_rate_radps = 0.5;
  s.pitch_rate_radps = -0.25;
  s.yaw_rate_radps = 0.375;
  s.sonar_beams = 16;
  for (std::size_t i = 0; i < s.sonar_m.size(); ++i) s.sonar_m[i] = 0.5f + static_cast<float>(i);
  s.target_index = 2;
  s.target_x_m = 34.0;
  s.target_y_m = 20.0;
  s.target_distance_m = 12.5;
  s.target_bearing_rad = -1.0;
  s.route_bearing_rad = 0.75;
  s.clearance_m = 3.75;
  s.mission_complete = true;
  s.episode_end = true;
  return s;
}

void CheckSame(const robot::AuvSensorSample& a, const robot::AuvSensorSample& b) {
  CHECK(a.tick == b.tick);
  CHECK(a.stamp_ns == b.stamp_ns);
  CHECK(a.x_m == b.x_m);
  CHECK(a.y_m == b.y_m);
  CHECK(a.depth_m == b.depth_m);
  CHECK(a.roll_rad == b.roll_rad);
  CHECK(a.pitch_rad == b.pitch_rad);
  CHECK(a.yaw_rad == b.yaw_rad);
  CHECK(a.surge_mps == b.surge_mps);
  CHECK(a.sway_mps == b.sway_mps);
  CHECK(a.heave_mps == b.heave_mps);
  CHECK(a.roll_rate_radps == b.roll_rate_radps);
  CHECK(a.pitch_rate_radps == b.pitch_rate_radps);
  CHECK(a.yaw_rate_radps == b.yaw_rate_radps);
  CHECK(a.sonar_beams == b.sonar_beams);
  CHECK(a.sonar_m == b.sonar_m);
  CHECK(a.target_index == b.target_index);
  CHECK(a.target_x_m == b.target_x_m);
  CHECK(a.target_y_m == b.target_y_m);
  CHECK(a.target_distance_m == b.target_distance_m);
  CHECK(a.target_bearing_rad == b.target_bearing_rad);
  CHECK(a.route_bearing_rad == b.route_bearing_rad);
  CHECK(a.clearance_m == b.clearance_m);
  CHECK(a.mission_complete == b.mission_complete);
  CHECK(a.episode_end == b.episode_end);
}

// Polls `pred` until it holds or `timeout_ns` passes.
template <typename F>
bool Eventually(F pred, std::int64_t timeout_ns = 5 * kSecond) {
  const std::int64_t end = MonotonicNs() + timeout_ns;
  while (!pred()) {
    if (MonotonicNs() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

}  // namespace

TEST_CASE("dds link: samples, commands and status arrive intact") {
  Pair p(test::TestDomain(1));
  const robot::AuvSensorSample sent = Distinct(7);
  REQUIRE(p.vehicle->PublishSample(sent).ok());
  REQUIRE(p.controller->WaitForSample(0, 5 * kSecond));
  dds::AuvSensorInput in;
  REQUIRE(p.controller->ReadSample(&in) == 1);
  CheckSame(in.value, sent);
  CHECK(in.flags == 0);
  CHECK(in.received_ns > 0);

  robot::AuvCommand c;
  c.tick = 8;
  c.stamp_ns = 99;
  c.answers = 7;
  c.surge_speed_mps = 1.125;
  c.yaw_rate_radps = -0.375;
  c.mode = 2;
  REQUIRE(p.controller->PushCommand(c));
  dds::AuvCommandInput got;
  REQUIRE(p.vehicle->WaitForCommand(&got, 5 * kSecond));
  CHECK(got.value.tick == 8);
  CHECK(got.value.stamp_ns == 99);
  CHECK(got.value.answers == 7);
  CHECK(got.value.surge_speed_mps == 1.125);
  CHECK(got.value.yaw_rate_radps == -0.375);
  CHECK(got.value.mode == 2);
  CHECK(got.flags == 0);

  robot::AuvControllerStatus st;
  st.tick = 8;
  st.mode = 1;
  st.cause = 0x24;
  st.deadline_misses = 3;
  st.invalid_samples = 4;
  st.tick_max_us = 12.5;
  REQUIRE(p.controller->PublishStatus(st).ok());
  robot::AuvControllerStatus rs;
  CHECK(Eventually([&] { return p.vehicle->ReadStatus(&rs) != 0; }));
  CHECK(rs.cause == 0x24);
  CHECK(rs.deadline_misses == 3);
  CHECK(rs.invalid_samples == 4);
  CHECK(rs.tick_max_us == 12.5);

  // The writer thread counts its write after write() returns.
  CHECK(Eventually([&] { return p.controller->counters().written == 2; }));  // the command and the status
  const auto vc = p.vehicle->counters();
  const auto cc = p.controller->counters();
  CHECK(vc.written == 1);
  CHECK(vc.received == 1);
  CHECK(cc.received == 1);
  CHECK(cc.invalid == 0);
  CHECK(cc.rejected == 0);
  CHECK(p.controller->Peer().matched_writers == 1);
  CHECK(p.controller->Peer().matched_readers == 1);
  CHECK(p.controller->Peer().last_receive_age_ns >= 0);
}

TEST_CASE(
    "dds link: samples are delivered as they came (the controller's sample check judges them), too many beams "
    "rejected - implausible commands flagged and counted") {
  Pair p(test::TestDomain(2));
  robot::AuvSensorSample bad = Distinct(1);
  bad.x_m = std::numeric_limits<double>::quiet_NaN();
  bad.sonar_m[3] = -1.0f;
  REQUIRE(p.vehicle->PublishSample(bad).ok());
  REQUIRE(p.controller->WaitForSample(0, 5 * kSecond));
  dds::AuvSensorInput in;
  REQUIRE(p.controller->ReadSample(&in) == 1);
  CHECK(std::isnan(in.value.x_m));
  CHECK(in.value.sonar_m[3] == -1.0f);
  CHECK(in.flags == 0);
  CHECK(p.controller->counters().invalid == 0);

  robot::AuvSensorSample too_many = Distinct(2);
  too_many.sonar_beams = robot::kAuvMaxSonarBeams + 1;
  REQUIRE(p.vehicle->PublishSample(too_many).ok());
  REQUIRE(Eventually([&] { return p.controller->counters().received == 2; }));
  CHECK(p.controller->counters().rejected == 1);
  CHECK(p.controller->ReadSample(&in) == 1);  // still the first sample: the rejected one is not delivered
  CHECK(in.value.tick == 1);

  REQUIRE(p.vehicle->PublishSample(Distinct(3)).ok());
  REQUIRE(p.controller->WaitForSample(1, 5 * kSecond));
  CHECK(p.controller->ReadSample(&in) == 2);
  CHECK(in.value.tick == 3);
  CHECK(in.flags == 0);
  CHECK(p.controller->counters().invalid == 0);

  robot::AuvCommand c;
  c.surge_speed_mps = std::numeric_limits<double>::infinity();
  c.mode = 7;
  REQUIRE(p.controller->PushCommand(c));
  dds::AuvCommandInput got;
  REQUIRE(p.vehicle->WaitForCommand(&got, 5 * kSecond));
  CHECK((got.flags & dds::kCommandNonFinite) != 0);
  CHECK((got.flags & dds::kCommandModeOutOfRange) != 0);
  CHECK(p.vehicle->counters().invalid == 1);
}

TEST_CASE("dds link: ROS 2 naming - both sides talk on rt/ topics, and not to a side with the native names") {
  const int domain = test::TestDomain(7);
  auto vehicle = Make(AuvDdsRole::kVehicle, domain, 16, dds::DdsNaming::kRos2);
  auto controller = Make(AuvDdsRole::kController, domain, 16, dds::DdsNaming::kRos2);
  auto native = Make(AuvDdsRole::kController, domain);  // same domain, the project's own names
  REQUIRE(vehicle->WaitForPeer(10 * kSecond));
  REQUIRE(controller->WaitForPeer(10 * kSecond));
  REQUIRE(vehicle->PublishSample(Distinct(5)).ok());
  REQUIRE(controller->WaitForSample(0, 10 * kSecond));
  dds::AuvSensorInput in;
  REQUIRE(controller->ReadSample(&in) == 1);
  CHECK(in.value.tick == 5);
  CHECK(in.value.x_m == 1.5);
  // Other topic names: the native controller never matched the ROS 2 vehicle.
  CHECK(native->Peer().matched_writers == 0);
  CHECK(native->Peer().matched_readers == 0);
  CHECK(native->ReadSample(&in) == 0);
  // The names themselves, as ROS 2 tools expect them.
  CHECK(dds::WireTopic(dds::DdsNaming::kRos2, "pbppo/auv/command") == "rt/pbppo/auv/command");
  CHECK(dds::WireTypeName(dds::DdsNaming::kRos2, "AuvCommand") == "pbppo_msgs::msg::dds_::AuvCommand_");
  CHECK(dds::WireTypeName(dds::DdsNaming::kNative, "AuvCommand").empty());
  auto bad = dds::ParseDdsNaming("ros");
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("'ros'") != std::string::npos);
}

TEST_CASE("dds link: a full command queue drops and counts, the rest is written in order") {
  Pair p(test::TestDomain(3), /*queue=*/2);
  constexpr std::uint64_t kPushes = 20000;
  std::uint64_t accepted = 0;
  for (std::uint64_t i = 1; i <= kPushes; ++i) {
    robot::AuvCommand c;
    c.tick = i;
    if (p.controller->PushCommand(c)) ++accepted;
  }
  REQUIRE(Eventually([&] {
    const auto cc = p.controller->counters();
    return cc.written + cc.write_failed == accepted;
  }));
  const auto cc = p.controller->counters();
  CHECK(cc.dropped_full > 0);
  CHECK(cc.dropped_full + accepted == kPushes);
  CHECK(cc.write_failed == 0);
  // What arrives arrives in order.
  std::uint64_t last = 0, disorder = 0, n = 0;
  dds::AuvCommandInput got;
  while (p.vehicle->WaitForCommand(&got, kSecond / 2)) {
    if (got.value.tick <= last) ++disorder;
    last = got.value.tick;
    ++n;
  }
  CHECK(n > 0);
  CHECK(disorder == 0);
}

TEST_CASE("dds link: a vehicle that goes away is seen as lost, its last sample ages") {
  const int domain = test::TestDomain(4);
  auto controller = Make(AuvDdsRole::kController, domain);
  {
    auto vehicle = Make(AuvDdsRole::kVehicle, domain);
    REQUIRE(controller->WaitForPeer(10 * kSecond));
    REQUIRE(vehicle->WaitForPeer(10 * kSecond));
    REQUIRE(vehicle->PublishSample(Distinct(0)).ok());
    REQUIRE(controller->WaitForSample(0, 5 * kSecond));
  }
  CHECK(Eventually([&] { return controller->Peer().matched_writers == 0; }));
  const std::int64_t age = controller->Peer().last_receive_age_ns;
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  CHECK(controller->Peer().last_receive_age_ns >= age + 50'000'000);
}

TEST_CASE("dds link: bad options name the option and the value") {
  dds::AuvDdsOptions o;
  o.profile_file = test::DdsProfile();
  o.domain_id = 300;
  auto r = AuvDdsLink::Create(AuvDdsRole::kController, o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("domain_id 300") != std::string::npos);

  o.domain_id = test::TestDomain(5);
  o.command_queue_capacity = 0;
  r = AuvDdsLink::Create(AuvDdsRole::kController, o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("command_queue_capacity 0") != std::string::npos);

  o.command_queue_capacity = 16;
  o.profile_file = "/nonexistent/profile.xml";
  r = AuvDdsLink::Create(AuvDdsRole::kController, o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("/nonexistent/profile.xml") != std::string::npos);

  o.profile_file = test::DdsProfile();
  o.participant_profile = "no_such_profile";
  r = AuvDdsLink::Create(AuvDdsRole::kVehicle, o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.find("no_such_profile") != std::string::npos);
}

TEST_CASE("dds link: the tick's calls (ReadSample, PushCommand) do not allocate in the calling thread") {
  Pair p(test::TestDomain(6), /*queue=*/64);
  REQUIRE(p.vehicle->PublishSample(Distinct(1)).ok());
  REQUIRE(p.controller->WaitForSample(0, 5 * kSecond));
  dds::AuvSensorInput in;
  robot::AuvCommand c;
  std::uint64_t allocations = 0, seen = 0, pushed = 0;
  {
    AllocationScope scope;
    for (std::uint64_t k = 0; k < 2000; ++k) {
      if (p.controller->ReadSample(&in) != 0) ++seen;
      c.tick = k;
      c.answers = in.value.tick;
      if (p.controller->PushCommand(c)) ++pushed;
    }
    allocations = scope.count();
  }
  CHECK(allocations == 0);
  CHECK(seen == 2000);
  CHECK(pushed > 0);
  // Meanwhile the writer thread did the DDS writes.
  CHECK(Eventually([&] { return p.controller->counters().written == pushed; }));
}
