// The robot model: both shipped robots load from robot.yaml with every file it names read once,
// the pieces made from the CAN map and the URDF (continuous, velocity-commanded wheels: the diffbot
// of tests/data), per-tick quantities at another tick period, and
// bad robot files refused naming the file, the field and the value.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "runtime/robot/robot_model.hpp"
#include "runtime/robot/text_file.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/test_paths.hpp"
#include "tests/support/text_edit.hpp"

using namespace pbppo;
using namespace pbppo::robot;
using safety::StopKind;

namespace {

RobotModel Load(const std::string& rel) {
  auto m = LoadRobotModel(test::SourcePath(rel));
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  return std::move(*m);
}

const FieldSpec& Field(const RobotModel& m, const char* name) {
  const int k = m.FieldIndex(name);
  REQUIRE_MESSAGE(k >= 0, name);
  return m.fields[static_cast<std::size_t>(k)];
}

const CommandSpec& Command(const RobotModel& m, const char* name) {
  const int k = m.CommandIndex(name);
  REQUIRE_MESSAGE(k >= 0, name);
  return m.commands[static_cast<std::size_t>(k)];
}

}  // namespace

TEST_CASE("robot model: loading a robot reads each file it names exactly once") {
  // robot.yaml, and for the AUV the IO layout, plant, DDS profile, three layouts and its three
  // messages' IDL; for the quadruped the description, its URDF, the IO layout, the CAN map, the
  // stand trajectory, the DDS profile, the walking task and its two messages' IDL; for the diffbot
  // its description, URDF, IO layout, CAN map and trajectory.
  for (const auto& [robot, count] :
       {std::pair{"models/auv/robot.yaml", 10u}, std::pair{"models/quadruped/robot.yaml", 10u},
        std::pair{"tests/data/diffbot/robot.yaml", 6u}}) {
    CAPTURE(robot);
    const auto before = FileReads();
    const RobotModel m = Load(robot);
    const auto after = FileReads();
    std::size_t files = 0;
    for (const auto& [path, n] : after) {
      const auto it = before.find(path);
      const std::uint64_t delta = n - (it == before.end() ? 0 : it->second);
      if (delta == 0) continue;
      CAPTURE(path);
      CHECK(delta == 1);
      ++files;
    }
    CHECK(files == count);
    CHECK(m.hash != 0);
  }
}

TEST_CASE("robot model: the AUV - declared stream, fields with their bounds, commands, signals, documents") {
  const RobotModel m = Load("models/auv/robot.yaml");
  CHECK(m.name == "auv");
  CHECK(m.tick_period_s == 0.1);
  CHECK(m.policy_period_ticks == 1);
  REQUIRE(m.streams.size() == 1);
  CHECK(m.policy_trigger == 0);
  const StreamSpec& s = m.streams[0];
  CHECK(s.name == "sensor");
  CHECK(s.field_count == m.fields.size());
  for (const FieldSpec& f : m.fields) CHECK(f.stream == 0);
  CHECK(s.stale_degraded_ticks == 1);
  CHECK(s.stale_safe_stop_ticks == 2);
  CHECK(s.lost_ticks == 20);
  CHECK(s.invalid_safe_stop == 3);
  CHECK(Field(m, "surge_mps").max == 5.0);
  CHECK(Field(m, "sonar_15_m").max == 15.0015);
  CHECK(m.FieldIndex("sonar_16_m") < 0);
  CHECK(Command(m, "surge_speed").rate == doctest::Approx(0.1));
  CHECK(Command(m, "surge_speed").degraded_max == 0.75);
  CHECK(Command(m, "yaw_rate").stop == StopKind::kRamp);
  CHECK(Command(m, "yaw_rate").stop_rate == doctest::Approx(0.5));
  CHECK(m.signals.size() == 22 + 16);
  CHECK(m.io.has_value());
  CHECK(m.io->robot == "auv");
  CHECK(m.DocumentGroup("layouts") == std::vector<std::string>{"easy", "hard", "medium"});
  REQUIRE(m.Document("plant").ok());
  CHECK((*m.Document("plant"))->yaml["hull"]["mass_kg"].as<double>() == 50.0);
  CHECK(m.Document("nonexistent").error().message.find("no file for 'nonexistent'") != std::string::npos);
  CHECK(*m.Parameter("depth_m") == 5.0);
}

TEST_CASE("robot model: the quadruped - motors and IMU from the CAN map and the URDF") {
  const RobotModel m = Load("models/quadruped/robot.yaml");
  CHECK(m.policy_period_ticks == 20);
  REQUIRE(m.motors.size() == 12);
  CHECK(m.streams.size() == 14);  // the operator's velocity command, 12 motors, the IMU
  CHECK(m.StreamIndex("velocity_command") == 0);
  CHECK_FALSE(m.streams[0].required);
  CHECK(m.commands.size() == 60);
  const MotorSpec& lf = m.motors[2];
  CHECK(lf.joint == "LF_KFE");
  CHECK(m.fields[lf.q_field].name == "q_LF_KFE");
  CHECK(m.fields[lf.q_field].min == doctest::Approx(-2.6 - 0.3));
  CHECK(m.commands[lf.q].name == "q_des_LF_KFE");
  CHECK(m.commands[lf.tau].name == "tau_ff_LF_KFE");
  CHECK(m.commands[lf.q].stop == StopKind::kHoldInput);
  CHECK(m.commands[lf.q].hold_input == static_cast<std::int32_t>(lf.q_field));
  CHECK(m.commands[lf.kd].stop_value == m.body->damping_kd_nm_s_rad);
  CHECK(m.commands[lf.kp].neutral == m.body->kp_nm_rad);
  CHECK(m.commands[lf.q].neutral == -0.8);
  const StreamSpec& motor = m.streams[lf.stream];
  CHECK(motor.stale_degraded_ticks == 1);
  CHECK(motor.stale_safe_stop_ticks == 2);
  CHECK(motor.lost_ticks == 499);
  CHECK(m.StreamIndex("base_imu") == 13);
  CHECK(m.fields[lf.q_field].stream == lf.stream);
  CHECK(m.fields[static_cast<std::size_t>(m.FieldIndex("base_imu_qw"))].stream == 13);
  CHECK(m.motors[2].policy_kp == 20.0);
  CHECK(m.motors[2].policy_kd == 0.5);
  CHECK(m.FieldIndex("base_imu_gyro_z") >= 0);
  CHECK(m.phases.enable_motors);
  CHECK(m.phases.arming_timeout_ticks == 1000);
  CHECK(m.phases.damping_ticks == 500);
  REQUIRE(m.stand_trajectory.has_value());
  CHECK(m.stand_trajectory->path.find("stand_trajectory.yaml") != std::string::npos);
  CHECK(m.dds_profile.has_value());
  CHECK(m.trusted_keys.empty());
  CHECK_FALSE(m.Document("stand_trajectory").ok());  // a file the runtime reads itself is no document
}

TEST_CASE("robot model: another tick period - stale ages, rates and the policy period follow") {
  const RobotModel m = Load("models/auv/robot.yaml");
  auto fast = WithTickPeriod(m, 0.001);
  REQUIRE_MESSAGE(fast.ok(), fast.error().message);
  // 100 ticks per sample: stale after 1.5 and 2.5 sample periods, lost after 20.
  CHECK(fast->streams[0].stale_degraded_ticks == 150);
  CHECK(fast->streams[0].stale_safe_stop_ticks == 250);
  CHECK(fast->streams[0].lost_ticks == 2000);
  CHECK(fast->commands[0].rate == doctest::Approx(0.001));
  CHECK(fast->policy_period_ticks == 100);
  auto odd = WithTickPeriod(m, 0.03);
  REQUIRE_FALSE(odd.ok());
  CHECK(odd.error().message.find("timing.policy_period_s 0.1 is not a whole number of ticks of 0.03 s") !=
        std::string::npos);
}

TEST_CASE("robot model: bad robot files are refused naming the file, the field and the value") {
  const test::RobotFileEdits edits("auv", "robot_model");
  const std::string &dir = edits.dir(), &p = edits.path();
  auto err = [&](const std::string& from, const std::string& to) { return edits.Error(from, to); };
  CHECK(err("io_layout: io_layout.yaml", "io_layout: missing.yaml") == dir + "/missing.yaml: cannot open");
  CHECK(err("tick_period_s: 0.1", "tick_period_s: -1") == p + ": timing.tick_period_s: '-1' is outside [1e-06, 10]");
  CHECK(err("kind: dds", "kind: usb") == p + ": transports[0].kind: 'usb' is not can, dds or evdev");
  CHECK(err("transport: dds", "transport: can") == p + ": streams[0]: unknown transport 'can'");
  CHECK(err("{name: y_m, min: -1.0e5, max: 1.0e5}", "{name: x_m, min: -1.0e5, max: 1.0e5}") ==
        p + ": streams[0].fields[2]: field 'x_m' appears twice");
  CHECK(err("yaw: {wrap: yaw_rad}", "yaw: {wrap: heading_rad}") ==
        p + ": signals.yaw.wrap: 'heading_rad' is not a field of the robot");
  CHECK(err("depth_error: {field: depth_m, minus: depth_m}", "depth_error: {field: depth_m, minus: depth_set}") ==
        p + ": signals.depth_error.minus: 'depth_set' is not a parameter of the robot");
  CHECK(err("policy_trigger: sensor", "policy_trigger: sonar") ==
        p + ": timing.policy_trigger: 'sonar' is not a stream of the robot");
  CHECK(
      err("stale_after: {degraded: 1, safe_stop: 2, lost: 20}", "stale_after: {degraded: 3, safe_stop: 2, lost: 20}") ==
      p + ": streams[0].stale_after: degraded 3, safe_stop 2, lost 20 must increase");
  CHECK(err("command_limit: count", "command_limit: ignore") ==
        p + ": supervisor.command_limit: 'ignore' is not count or degraded");
  CHECK(err("robot: auv", "robot: auv\nwheels: 4") == p + ": wheels: unknown field");
  CHECK(LoadRobotModel(dir + "/none.yaml").error().message == dir + "/none.yaml: cannot open");
}

TEST_CASE("robot model: service.rearm_after_failure - false unless the robot file says true, bad values named") {
  CHECK_FALSE(Load("models/auv/robot.yaml").service.rearm_after_failure);
  CHECK_FALSE(Load("models/quadruped/robot.yaml").service.rearm_after_failure);
  const test::RobotFileEdits edits("auv", "robot_model_service");
  const std::string original = test::ReadText(test::SourcePath("models/auv/robot.yaml"));
  std::ofstream(edits.path()) << test::ReplaceOnce(original, "robot: auv",
                                                   "robot: auv\nservice: {rearm_after_failure: true}");
  auto m = LoadRobotModel(edits.path());
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  CHECK(m->service.rearm_after_failure);
  const std::string& p = edits.path();
  CHECK(edits.Error("robot: auv", "robot: auv\nservice: {rearm_after_failure: yes}") ==
        p + ": service.rearm_after_failure: 'yes' is not true or false");
  CHECK(edits.Error("robot: auv", "robot: auv\nservice: {restart: always}") == p + ": service.restart: unknown field");
}

TEST_CASE("robot model: supervisor.recovery - a person's request unless automatic with its causes, bad values named") {
  const RobotModel& auv = test::AuvRobot();
  CHECK_FALSE(auv.supervisor.recovery.automatic);
  CHECK(auv.supervisor.recovery.healthy_ticks == 20);  // 2 s of 0.1 s ticks
  CHECK(test::QuadrupedRobot().supervisor.recovery.healthy_ticks == 500);
  const test::RobotFileEdits edits("auv", "robot_model_recovery");
  const std::string original = test::ReadText(test::SourcePath("models/auv/robot.yaml"));
  const std::string shipped = "recovery: {rule: request, healthy_s: 2.0}";
  std::ofstream(edits.path()) << test::ReplaceOnce(
      original, shipped,
      "recovery: {rule: automatic, healthy_s: 0.5, causes: [stale sample, lost peer, transport fault], "
      "max_automatic: 7}");
  auto m = LoadRobotModel(edits.path());
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  const robot::RecoverySpec& r = m->supervisor.recovery;
  CHECK(r.automatic);
  CHECK(r.healthy_ticks == 5);
  CHECK(r.max_automatic == 7);
  using safety::Cause;
  CHECK(r.causes ==
        ((1u << static_cast<unsigned>(Cause::kStaleSample)) | (1u << static_cast<unsigned>(Cause::kLostPeer)) |
         (1u << static_cast<unsigned>(Cause::kTransportFault))));
  const std::string& p = edits.path();
  auto err = [&](const std::string& to) { return edits.Error(shipped, to); };
  CHECK(err("recovery: {rule: sometimes}") ==
        p + ": supervisor.recovery.rule: 'sometimes' is not request or automatic");
  CHECK(err("recovery: {rule: request, causes: [lost peer]}") ==
        p + ": supervisor.recovery.causes: only with rule: automatic");
  CHECK(err("recovery: {rule: automatic}") == p + ": supervisor.recovery: missing field 'causes'");
  CHECK(err("recovery: {rule: automatic, causes: []}") ==
        p + ": supervisor.recovery.causes: empty: name the causes that may recover automatically");
  CHECK(
      err("recovery: {rule: automatic, causes: [lost peer, power failure]}")
          .starts_with(p + ": supervisor.recovery.causes[1]: 'power failure' is not a cause (known: command limit, "));
  CHECK(err("recovery: {rule: automatic, causes: [e-stop request]}") ==
        p + ": supervisor.recovery.causes[0]: 'e-stop request' cannot recover automatically (an e-stop request is "
            "released by disarming and a reset)");
  CHECK(err("recovery: {rule: automatic, causes: [lost peer], max_automatic: 0}")
            .starts_with(p + ": supervisor.recovery.max_automatic: '0' is outside"));
  CHECK(err("recovery: {rule: request, healthy_s: -1}").starts_with(p + ": supervisor.recovery.healthy_s: '-1'"));
  CHECK(err("recovery: {rule: request, after: 3}") == p + ": supervisor.recovery.after: unknown field");
}

TEST_CASE("robot model: DDS messages - declared once in IDL, mapped onto fields and commands by the robot file") {
  const RobotModel& auv = test::AuvRobot();
  REQUIRE(auv.transports.size() == 1);
  const TransportSpec& t = auv.transports[0];
  CHECK(t.dds.topic_prefix == "pbppo/auv/");
  CHECK(t.dds.wait_for_peer);
  REQUIRE(t.dds.messages.size() == 3);
  const DdsMessageSpec& sensor = t.dds.messages[0];
  CHECK(sensor.direction == MessageDirection::kIn);
  CHECK(sensor.type.type_name == "pbppo_idl::auv::SensorState");
  CHECK(sensor.type_stem == "AuvSensorState");
  CHECK(sensor.stream == static_cast<std::uint32_t>(auv.StreamIndex("sensor")));
  // Every field of the stream from one member: by name, the sonar's by the robot file's pattern.
  CHECK(sensor.fields.size() == auv.streams[sensor.stream].field_count);
  for (const FieldLeaf& fl : sensor.fields) {
    const std::string &field = auv.fields[fl.field].name, &leaf = sensor.type.leaves[fl.leaf].path;
    if (field.rfind("sonar_", 0) == 0 && field != "sonar_beams")
      CHECK(leaf == "sonar_m[" + field.substr(6, field.size() - 8) + "]");
    else
      CHECK(leaf == field);
  }
  CHECK(sensor.lost_after_s == 2.0);
  const DdsMessageSpec& command = t.dds.messages[1];
  CHECK(command.direction == MessageDirection::kOut);
  REQUIRE(command.values.size() == 6);
  const LeafValue& answers = command.values[2];
  CHECK(command.type.leaves[answers.leaf].path == "answers");
  REQUIRE(answers.terms.size() == 1);
  CHECK(answers.terms[0].kind == ValueTerm::Kind::kField);
  CHECK(answers.terms[0].index == static_cast<std::uint32_t>(auv.FieldIndex("tick")));
  const DdsMessageSpec& status = t.dds.messages[2];
  CHECK(status.direction == MessageDirection::kStatus);
  const LeafValue& limited = status.values[6];
  CHECK(status.type.leaves[limited.leaf].path == "limited_commands");
  REQUIRE(limited.terms.size() == 2);
  CHECK(limited.terms[0].kind == ValueTerm::Kind::kCount);
  CHECK(limited.terms[1].index == static_cast<std::uint32_t>(safety::Cause::kRateLimit));
  CHECK(auv.lockstep_stream == auv.StreamIndex("sensor"));
  CHECK(auv.lockstep_end_field == auv.FieldIndex("episode_end"));
  // The quadruped's operator: only for a policy, volatile, what an operator writes besides.
  const TransportSpec& op = test::QuadrupedRobot().transports[1];
  CHECK(op.policy_only);
  CHECK_FALSE(op.dds.messages[0].transient_local);
  REQUIRE(op.dds.messages[0].peer.size() == 2);
  CHECK(op.dds.messages[0].peer[0].kind == PeerLeaf::Kind::kSequence);
}

TEST_CASE("robot model: bad DDS message declarations are refused naming the message, the member and the field") {
  const test::RobotFileEdits edits("auv", "robot_model_dds");
  const std::string& p = edits.path();
  auto err = [&](const std::string& from, const std::string& to) { return edits.Error(from, to); };
  const std::string m0 = p + ": transports[0].messages[0]", m1 = p + ": transports[0].messages[1]";
  CHECK(err("\"sonar_m[{i}]\"", "\"sonar[{i}]\"") ==
        m0 + ".fields.sonar_{i}_m: 'sonar[0]' is not a member of pbppo_idl::auv::SensorState");
  CHECK(err("{\"sonar_{i}_m\": \"sonar_m[{i}]\"}", "{}") ==
        m0 + ": field 'sonar_0_m' of stream 'sensor' is filled by no member of pbppo_idl::auv::SensorState (name it "
             "under fields)");
  CHECK(err("{\"sonar_{i}_m\": \"sonar_m[{i}]\"}", "{\"sonar_{i}_m\": \"sonar_m[{i}]\", sonar_0_m: x_m}") ==
        m0 + ".fields.sonar_0_m: field 'sonar_0_m' is filled twice");
  CHECK(err("stream: sensor                 #", "stream: sonar                 #") ==
        m0 + ".stream: 'sonar' is not a stream of the robot");
  CHECK(err("direction: in", "direction: sideways") == m0 + ".direction: 'sideways' is not in, out or status");
  CHECK(err("idl: idl/AuvSensorState.idl", "idl: idl/Gone.idl") ==
        m0 + ".idl: " + edits.dir() + "/idl/Gone.idl: cannot open");
  CHECK(err("idl: idl/AuvSensorState.idl", "idl: idl/AuvSensorState.idl\n        type: pbppo_idl::auv::Nothing")
            .find(m0 + ".idl: AuvSensorState.idl: no struct 'pbppo_idl::auv::Nothing' (known: ") == 0);
  CHECK(err("answers: field.tick", "answers: field.tock") ==
        m1 + ".values.answers: 'field.tock' is not a value (a number, tick, mode, clock_ns, sequence, command.<name>, "
             "field.<name>, samples.<stream>; in out messages also motor.<joint>; in status messages also phase, "
             "cause, count.<cause>, deadline_misses, tick_median_us, tick_max_us)");
  CHECK(err("answers: field.tick", "answers: deadline_misses") ==
        m1 + ".values.answers: 'deadline_misses' is the controller's status: only status messages carry it");
  CHECK(err("answers: field.tick", "answer: field.tick") ==
        m1 + ".values.answer: 'answer' is not a member of pbppo_idl::auv::Command");
  CHECK(err("        lost_after_s: 2.0", "        lost_after_s: 2.0\n        values: {tick: tick}") ==
        m0 + ".values: only out and status messages have it");
  CHECK(err("        lost_after_s: 2.0", "        durability: forever") ==
        m0 + ".durability: 'forever' is not transient_local or volatile");
  CHECK(err("      - topic: command ", "      - topic: sensor_state ") ==
        m1 + ".topic: topic 'sensor_state' appears twice");
  CHECK(err("      - topic: command ",
            "      - topic: sensor_copy\n        idl: idl/AuvSensorState.idl\n        direction: in\n        stream: "
            "sensor\n        fields: {\"sonar_{i}_m\": \"sonar_m[{i}]\"}\n      - topic: command ") ==
        p + ": streams: stream 'sensor' arrives in 2 messages of transport 'dds' (one expected)");
  CHECK(err("    wait_for_peer: true ", "    wait_for_peer: true\n    ports: 3 ") ==
        p + ": transports[0].ports: unknown field");
  CHECK(err("lockstep: {stream: sensor, end_field: episode_end}", "lockstep: {stream: sensor, end_field: x_mm}") ==
        p + ": timing.lockstep.end_field: 'x_mm' is not a field of stream 'sensor'");
}

TEST_CASE("robot model: the diffbot - continuous wheels are velocity-commanded motors with no position bound") {
  const RobotModel m = Load("tests/data/diffbot/robot.yaml");
  REQUIRE(m.motors.size() == 3);
  CHECK(m.streams.size() == 4);           // three motors, the IMU
  CHECK(m.commands.size() == 3 + 3 + 5);  // the wheels: dq_des_, kd_, tau_ff_; the head: all five
  const MotorSpec& wheel = m.motors[0];
  const MotorSpec& head = m.motors[2];
  CHECK(wheel.joint == "left_wheel");
  CHECK(wheel.velocity_commanded());
  CHECK(wheel.continuous);
  CHECK(wheel.q == kNoCommand);
  CHECK(wheel.kp == kNoCommand);
  CHECK(wheel.policy_kp < 0);
  CHECK(m.CommandIndex("q_des_left_wheel") < 0);
  CHECK(m.CommandIndex("kp_left_wheel") < 0);
  // No position bound: the sample check only asks for a finite number.
  CHECK(Field(m, "q_left_wheel").min == -HUGE_VAL);
  CHECK(Field(m, "q_left_wheel").max == HUGE_VAL);
  // Speed limits from the URDF's velocity limit (20 rad/s, inside the MIT range of 30).
  CHECK(Field(m, "dq_left_wheel").max == 1.5 * 20.0);
  CHECK(Command(m, "dq_des_left_wheel").min == -20.0);
  CHECK(Command(m, "dq_des_left_wheel").max == 20.0);
  CHECK(Command(m, "dq_des_left_wheel").neutral == 0.0);  // stand-up and hold: zero speed
  CHECK(Command(m, "dq_des_left_wheel").stop == StopKind::kValue);
  CHECK(Command(m, "dq_des_left_wheel").stop_value == 0.0);  // safe-stop: brake to zero speed ...
  CHECK(Command(m, "kd_left_wheel").neutral == 0.3);         // ... with the velocity gain in force,
  CHECK(Command(m, "kd_left_wheel").stop_value == 0.1);      // the damping gain in safe-stop
  CHECK(Command(m, "tau_ff_left_wheel").max == 3.0);         // min(URDF effort 3, MIT 4)
  // The head keeps its position bound and target.
  CHECK_FALSE(head.velocity_commanded());
  CHECK_FALSE(head.continuous);
  CHECK(Field(m, "q_head_pan").max == doctest::Approx(1.5 + 0.2));
  CHECK(m.commands[head.q].name == "q_des_head_pan");
  CHECK(m.commands[head.q].neutral == 0.3);
  CHECK(m.commands[head.q].stop == StopKind::kHoldInput);
  CHECK(m.commands[head.kp].neutral == 4.0);
  CHECK(m.motors[1].velocity_commanded());
}

TEST_CASE("robot model: continuous joints and velocity-commanded motors - bad data refused naming file, field, value") {
  const test::RobotFileEdits edits("diffbot", "robot_model_diffbot", "tests/data/diffbot");
  const std::string& p = edits.path();
  // The wheels' position must be unwrapped between replies: lost may not let a wheel turn half its range.
  CHECK(edits.Error("stale_after: {degraded: 1, safe_stop: 2, lost: 50}",
                    "stale_after: {degraded: 1, safe_stop: 2, lost: 200}") ==
        p + ": motors.stale_after.lost: 200 periods without a reply let continuous joint 'left_wheel' turn up to 6.03 "
            "rad (1.5 x 20 rad/s for 0.201 s) between two replies, not less than half its MIT position range "
            "[-3.14159265, 3.14159265]: its multi-turn angle could not be unwrapped");
  // A velocity-commanded motor needs kp 0 exactly.
  CHECK(edits.ErrorIn("can_map.yaml", "kp_min: 0.0      #", "kp_min: 1.0      #") ==
        p + ": files.can_map: motors[0] 'left_wheel': actuator 'wheel_drive' has kp_min 1: velocity-commanded joint "
            "'left_wheel' needs kp 0 exactly");
  // A gain the actuator cannot carry.
  CHECK(edits.ErrorIn("diffbot.yaml", "left_wheel: {kd_nm_s_rad: 0.3}", "left_wheel: {kd_nm_s_rad: 3}") ==
        p + ": files.can_map: motors[0] 'left_wheel': command 'kd_left_wheel': its neutral value 3 (the "
            "description's default pose or gains) is outside [0, 2] (the joint's and the actuator's limits)");
  // A continuous joint given a position target (the description refuses it, naming its file).
  CHECK(edits.ErrorIn("diffbot.yaml", "  head_pan: 0.3", "  head_pan: 0.3\n  right_wheel: 0") ==
        "diffbot.yaml: default_pose.right_wheel: '0': joint 'right_wheel' is continuous and velocity-commanded: it "
        "takes no position target (it holds zero speed where others hold their default pose)");
  // A robot that sits needs its description's sit pose.
  CHECK(edits.Error("  motor_off_timeout_s: 0.1", "  motor_off_timeout_s: 0.1\n  sit_down_s: 1.0") ==
        p + ": phases.sit_down_s: the robot's description gives no sit_pose (joint head_pan) to sit down to");
  CHECK(edits.Error("  motor_off_timeout_s: 0.1", "  motor_off_timeout_s: 0.1\n  sit_down_s: -1") ==
        p + ": phases.sit_down_s: '-1' is outside [0, 3600]");
  CHECK(edits.Error("  motor_off_timeout_s: 0.1", "  motor_off_timeout_s: 0.1\n  sit_down_s: 0.0001") ==
        p + ": phases.sit_down_s: 0.0001 s is shorter than half a tick (0.001 s): a sit-down takes at least one");
}

TEST_CASE("robot model: the Go2 - motors of the description over DDS, one message fills several streams") {
  const RobotModel m = Load("models/go2/robot.yaml");
  CHECK(m.tick_period_s == 0.002);
  CHECK(m.policy_period_ticks == 10);
  CHECK_FALSE(m.can.has_value());
  REQUIRE(m.motors.size() == 12);
  CHECK(m.motors[0].joint == "FR_hip");
  CHECK(m.motors[11].joint == "RL_calf");
  const MotorSpec& calf = m.motors[2];
  CHECK(m.streams[calf.stream].transport == "lowlevel");
  CHECK(m.streams[calf.stream].kind == StreamKind::kMotor);
  CHECK(Command(m, "kp_FR_calf").max == 100.0);
  CHECK(Command(m, "kd_FR_calf").max == 10.0);
  const UrdfJoint& uj = m.body->joint_at(2);
  CHECK(Command(m, "tau_ff_FR_calf").max == uj.effort_nm);
  CHECK(Command(m, "q_des_FR_calf").min == uj.lower_rad);
  CHECK(Field(m, "tau_FR_calf").max == doctest::Approx(1.5 * uj.effort_nm));
  CHECK(Field(m, "q_FR_calf").min == doctest::Approx(uj.lower_rad - 0.2));
  CHECK(m.streams[static_cast<std::size_t>(m.StreamIndex("imu"))].kind == StreamKind::kImu);
  CHECK(Field(m, "imu_gyro_x").max == 35.0);
  // rt/lowstate fills the state stream, every motor's and the IMU's; its CRC's verdict is crc_ok.
  const TransportSpec& t = m.transports[static_cast<std::size_t>(m.TransportIndex("lowlevel"))];
  CHECK(t.dds.topic_prefix == "rt/");
  REQUIRE(t.dds.messages.size() == 2);
  const DdsMessageSpec& state = t.dds.messages[0];
  CHECK(state.type.type_name == "unitree_go::msg::dds_::LowState_");
  CHECK(state.streams.size() == 14);
  CHECK(state.stream == static_cast<std::uint32_t>(m.StreamIndex("state")));
  REQUIRE(state.checksum.present);
  CHECK(state.checksum.field == m.FieldIndex("crc_ok"));
  CHECK(state.type.leaves[state.checksum.leaf].path == "crc");
  bool mapped = false;
  for (const FieldLeaf& fl : state.fields) {
    CHECK(static_cast<int>(fl.field) != m.FieldIndex("crc_ok"));  // the checksum's field is no leaf's
    if (m.fields[fl.field].name == "dq_RR_thigh") mapped = state.type.leaves[fl.leaf].path == "motor_state[7].dq";
  }
  CHECK(mapped);
  CHECK(state.fields.size() == m.fields.size() - 3 - 1);  // all but the operator's three and crc_ok
  // Each motor's count of lost frames arrives as its growth per sample, none allowed.
  REQUIRE(m.motors[7].lost_field >= 0);
  CHECK(m.fields[static_cast<std::size_t>(m.motors[7].lost_field)].name == "lost_RR_thigh");
  CHECK(Field(m, "lost_RR_thigh").min == 0.0);
  CHECK(Field(m, "lost_RR_thigh").max == 0.0);
  const auto lost = std::find_if(state.fields.begin(), state.fields.end(), [&](const FieldLeaf& fl) {
    return static_cast<int>(fl.field) == m.motors[7].lost_field;
  });
  REQUIRE(lost != state.fields.end());
  CHECK(lost->increase());
  CHECK(state.type.leaves[lost->leaf].path == "motor_state[7].lost");
  CHECK(std::count_if(state.fields.begin(), state.fields.end(), [](const FieldLeaf& fl) { return fl.increase(); }) ==
        12);
  // rt/lowcmd: per motor its mode and five commands, and the CRC.
  const DdsMessageSpec& cmd = t.dds.messages[1];
  CHECK(cmd.checksum.present);
  CHECK(cmd.type.leaves[cmd.checksum.leaf].path == "crc");
  int modes = 0;
  for (const LeafValue& v : cmd.values)
    if (v.terms.size() == 1 && v.terms[0].kind == ValueTerm::Kind::kMotorOn) {
      CHECK(cmd.type.leaves[v.leaf].path == "motor_cmd[" + std::to_string(v.terms[0].index) + "].mode");
      ++modes;
    }
  CHECK(modes == 12);
  CHECK(cmd.values.size() == 3 + 12 * 6);
}

TEST_CASE("robot model: motors over DDS, several streams per message, checksums - bad data refused naming it") {
  const test::RobotFileEdits edits("go2", "robot_model_go2");
  const std::string& p = edits.path();
  auto err = [&](const std::string& from, const std::string& to) { return edits.Error(from, to); };
  const std::string m0 = p + ": transports[0].messages[0]", m1 = p + ": transports[0].messages[1]";
  CHECK(err("checksum: {leaf: crc, field: crc_ok}", "checksum: {leaf: tick, field: crc_ok}") ==
        m0 + ".checksum.leaf: 'tick' is not a uint32 in the last word of unitree_go::msg::dds_::LowState_ (a uint32 "
             "at byte 1100 of 1180)");
  CHECK(err("checksum: {leaf: crc, field: crc_ok}", "checksum: {leaf: crc, field: tick}") ==
        m0 + ".checksum.field: 'tick' must accept 1 and refuse 0 (min 1, max 1), not [0, 4.2949673e+09]");
  CHECK(err("checksum: {leaf: crc, field: crc_ok}", "checksum: {leaf: crc, field: crc_ok, algorithm: crc16}") ==
        m0 + ".checksum.algorithm: 'crc16' is not crc32_mpeg2_words");
  CHECK(err("checksum: {leaf: crc, field: crc_ok}", "checksum: {leaf: crcc, field: crc_ok}") ==
        m0 + ".checksum.leaf: 'crcc' is not a member of unitree_go::msg::dds_::LowState_");
  CHECK(err("checksum: {leaf: crc}", "checksum: {leaf: crc, field: crc_ok}") == m1 + ".checksum.field: unknown field");
  CHECK(err("\"q_{joint}\": \"motor_state[{motor}].q\"", "\"q_{joint}\": \"motor_state[{motor}].qq\"") ==
        m0 + ".fields.q_FR_hip: 'motor_state[0].qq' is not a member of unitree_go::msg::dds_::LowState_");
  CHECK(err("          \"dq_{joint}\": \"motor_state[{motor}].dq\"\n", "") ==
        m0 + ": field 'dq_FR_hip' of stream 'FR_hip' is filled by no member of unitree_go::msg::dds_::LowState_ (name "
             "it under fields)");
  CHECK(err("stream: [state, motors, imu]", "stream: [state, motors, imu, state]") ==
        m0 + ".stream: stream 'state' is named twice");
  CHECK(err("stream: [state, motors, imu]", "stream: [state, motors, imu, velocity_command]") ==
        m0 + ".stream: stream 'velocity_command' is delivered by transport 'operator'");
  CHECK(err("stream: [state, motors, imu]", "stream: [state, imu]") ==
        m0 + ".fields.q_FR_hip: 'q_FR_hip' is not a field of the message's streams");
  CHECK(err("\"motor_cmd[{motor}].mode\": \"motor.{joint}\"", "\"motor_cmd[{motor}].mode\": \"motor.knee\"") ==
        m1 + ".values.motor_cmd[0].mode: 'motor.knee' is not a value (a number, tick, mode, clock_ns, sequence, "
             "command.<name>, field.<name>, samples.<stream>; in out messages also motor.<joint>; in status messages "
             "also phase, cause, count.<cause>, deadline_misses, tick_median_us, tick_max_us)");
  CHECK(err("        \"head[0]\": 254", "        crc: 254") == m1 + ".values.crc: 'crc' carries the checksum");
  CHECK(err("  transport: lowlevel\n  stale_after", "  transport: operators\n  stale_after") ==
        p + ": motors.transport: 'operators' is not a transport of the robot");
  CHECK(err("gain_limits: {kp_max: 100.0, kd_max: 10.0}", "gain_limits: {kp_max: 10.0, kd_max: 10.0}")
            .find("command 'kp_FR_hip': its neutral value") != std::string::npos);
  CHECK(err("  names: [imu]", "  names: [imu, imu]") == p + ": imus.names[1]: stream 'imu' appears twice");
  // A counter's increase: of an unsigned leaf only; an allowance that is a count.
  CHECK(err("\"increase(motor_state[{motor}].lost)\"", "\"increase(motor_state[{motor}].q)\"") ==
        m0 + ".fields.lost_FR_hip: 'increase(motor_state[0].q)': motor_state[0].q is a float, not a counter "
             "(uint8, uint16 or uint32)");
  CHECK(err("\"increase(motor_state[{motor}].lost)\"", "\"increase(motor_state[{motor}].lostt)\"") ==
        m0 + ".fields.lost_FR_hip: 'motor_state[0].lostt' is not a member of unitree_go::msg::dds_::LowState_");
  CHECK(err("lost_per_sample_max: 0", "lost_per_sample_max: -1") ==
        p + ": motors.lost_per_sample_max: '-1' is outside [0, 4.2949673e+09]");
  CHECK(err("lost_per_sample_max: 0", "lost_per_sample_max: many") ==
        p + ": motors.lost_per_sample_max: 'many' is not a number");
  CHECK(err("  lost_per_sample_max: 0\n", "") ==
        m0 + ".fields.lost_FR_hip: 'lost_FR_hip' is not a field of the message's streams");
}

TEST_CASE("robot model: zero_after - a command source whose silence stops the command, no fault, bad data named") {
  const test::RobotFileEdits edits("quadruped", "robot_model_zero_after");
  const std::string& p = edits.path();
  const std::string stale = "    required: false\n    stale_after: {degraded: 3, safe_stop: 5, lost: 20}\n";
  const std::string original = test::ReadText(test::SourcePath("models/quadruped/robot.yaml"));
  std::ofstream(p) << test::ReplaceOnce(original, stale, "    zero_after: 5\n");
  auto m = LoadRobotModel(p);
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  const auto s = static_cast<std::size_t>(m->StreamIndex("velocity_command"));
  CHECK(m->streams[s].zero_after == 5.0);
  CHECK(m->streams[s].zero_after_ticks == 550);  // older than 5.5 periods of 0.1 s at 1 kHz
  CHECK_FALSE(m->streams[s].required);
  CHECK_FALSE(m->supervisor_model.streams[s].silence_faults);
  CHECK(m->supervisor_model.streams[0].silence_faults == (s != 0));
  auto slow = WithTickPeriod(*m, 0.002);
  REQUIRE(slow.ok());
  CHECK(slow->streams[s].zero_after_ticks == 275);
  // The shipped quadruped's operator: stale limits, faults.
  CHECK(test::QuadrupedRobot().streams[s].zero_after_ticks == 0);
  CHECK(test::QuadrupedRobot().supervisor_model.streams[s].silence_faults);

  CHECK(edits.Error(stale, "    required: false\n    zero_after: 5\n") ==
        p + ": streams[0].required: goes with stale limits; with zero_after the stream's silence is no fault (its "
            "fields read 0)");
  CHECK(edits.Error(stale, stale + "    zero_after: 5\n") ==
        p + ": streams[0].stale_after: goes with stale limits; with zero_after the stream's silence is no fault (its "
            "fields read 0)");
  CHECK(edits.Error(stale, "    zero_after: 0\n").find(p + ": streams[0].zero_after: ") == 0);
  CHECK(edits.Error(stale, "    zero_after: -1\n").find(p + ": streams[0].zero_after: ") == 0);
  CHECK(edits.Error(stale + "    invalid_safe_stop: 1\n    fields:\n      - {name: command_vx, min: -1.0, max: 1.0}",
                    "    zero_after: 5\n    invalid_safe_stop: 1\n    fields:\n      - {name: command_vx, min: 0.1, "
                    "max: 1.0}") ==
        p + ": streams[0].fields[0]: 'command_vx': [0.1, 1] does not hold 0, what the stream's fields read after "
            "zero_after");
}

TEST_CASE(
    "robot model: the Go2's remote - keys as bits, sticks as float32 inside the record, shaped, bad mappings named") {
  const RobotModel m = Load("models/go2_remote/robot.yaml");
  const DdsMessageSpec& state = m.transports[0].dds.messages[0];
  const auto leaf_of = [&](const char* field) -> const FieldLeaf& {
    const auto at = std::find_if(state.fields.begin(), state.fields.end(), [&](const FieldLeaf& fl) {
      return fl.field == static_cast<std::uint32_t>(m.FieldIndex(field));
    });
    REQUIRE(at != state.fields.end());
    return *at;
  };
  const FieldLeaf& sit = leaf_of("sit");
  CHECK(sit.read == FieldLeaf::Read::kBit);
  CHECK(sit.bit == 6);
  CHECK(state.type.leaves[sit.leaf].path == "wireless_remote[3]");
  const FieldLeaf& vy = leaf_of("command_vy");
  CHECK(vy.read == FieldLeaf::Read::kFloat32);
  CHECK(state.type.leaves[vy.leaf].path == "wireless_remote[4]");
  CHECK(vy.shaped);
  CHECK(vy.axis.scale == -0.5);
  CHECK(vy.axis.dead_zone == 0.1);
  CHECK(vy.axis.raw_min == -1.0);
  CHECK(ShapeAxis(vy.axis, 0.55) == doctest::Approx(-0.25));
  CHECK(ShapeAxis(vy.axis, UnshapeAxis(vy.axis, 0.3)) == doctest::Approx(0.3));
  CHECK(std::isnan(ShapeAxis(vy.axis, 1.01)));
  CHECK(m.op.sit >= 0);
  CHECK(m.phases.sit_down_ticks == 1000);
  CHECK(m.motors[1].sit_q_rad == 1.2);

  const test::RobotFileEdits edits("go2_remote", "robot_model_go2_remote");
  const std::string& p = edits.path();
  const std::string w = p + ": transports[0].messages[0]";
  CHECK(
      edits.Error("bit(wireless_remote[3], 6)", "bit(wireless_remote[3], 8)") ==
      w + ".fields.sit: 'bit(wireless_remote[3], 8)': bit '8' is not one of the 8 bits of wireless_remote[3] (0 to 7)");
  CHECK(edits.Error("bit(wireless_remote[3], 6)", "bit(wireless_remote[3], x)").find("bit 'x' is not one of") !=
        std::string::npos);
  CHECK(edits.Error("bit(wireless_remote[3], 6)", "bit(wireless_remote[3])") ==
        w + ".fields.sit: 'bit(wireless_remote[3])': expected bit(LEAF, N)");
  CHECK(edits.Error("bit(wireless_remote[3], 6)", "bit(imu_state.gyroscope[0], 1)") ==
        w + ".fields.sit: 'bit(imu_state.gyroscope[0], 1)': imu_state.gyroscope[0] is a float, not an unsigned "
            "integer (uint8, uint16 or uint32) to take a bit of");
  CHECK(edits.Error("float32(wireless_remote[20])", "float32(wireless_remote[37])") ==
        w + ".fields.command_vx: 'float32(wireless_remote[37])': wireless_remote[37] does not begin four octets of "
            "one array (a uint8 leaf; float32() reads a float inside a byte array)");
  CHECK(edits.Error("float32(wireless_remote[20])", "float32(tick)").find("tick does not begin four octets") !=
        std::string::npos);
  CHECK(edits.Error("float32(wireless_remote[20])", "float32(wireless_remote[40])") ==
        w + ".fields.command_vx: 'wireless_remote[40]' is not a member of unitree_go::msg::dds_::LowState_");
  CHECK(edits.Error("command_vx: {scale: 1.0, dead_zone: 0.1}", "deadman: {scale: 1.0, dead_zone: 0.1}") ==
        w + ".axes.deadman: field 'deadman' is a count, a bit or a checksum's verdict, not a stick");
  CHECK(edits.Error("command_vy: {scale: -0.5,", "command_vy: {scale: -2.5,") ==
        w + ".axes.command_vy.scale: field 'command_vy' has range [-1, 1], which does not hold [-2.5, 2.5] that it can "
            "take");
  CHECK(edits.Error("command_vx: {scale: 1.0, dead_zone: 0.1}", "command_vx: {scale: 1.0, range: [1, -1]}") ==
        w + ".axes.command_vx.range: low 1 is above high -1");
  CHECK(edits.Error("command_vx: {scale: 1.0, dead_zone: 0.1}", "command_vx: {scale: 1.0, dead_zone: 0.95}")
            .find(w + ".axes.command_vx.dead_zone: '0.95' is outside") == 0);
  CHECK(edits.Error("command_vx: {scale: 1.0, dead_zone: 0.1}", "speed: {scale: 1.0}") ==
        w + ".axes.speed: 'speed' is not a field of the message's streams");
  CHECK(edits.Error("command_vx: {scale: 1.0, dead_zone: 0.1}", "command_vx: {scale: 1.0, rate_per_s: 1}") ==
        w + ".axes.command_vx.rate_per_s: unknown field");
}
