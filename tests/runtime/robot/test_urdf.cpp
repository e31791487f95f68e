// URDF loader and robot description: the quadruped loads; continuous joints and velocity-commanded
// joints (the diffbot of tests/data); bad files are refused with the field named.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "runtime/robot/urdf.hpp"
#include "tests/support/refusal.hpp"
#include "tests/support/test_paths.hpp"
#include "tests/support/text_edit.hpp"

using pbppo::test::ReadText;
using pbppo::test::ReplaceOnce;

using namespace pbppo::robot;

namespace {

const char* kGood = R"(<?xml version="1.0"?>
<!-- a two-link arm -->
<robot name="arm">
  <link name="base"/>
  <link name="upper">
    <inertial>
      <origin xyz="0 0 -0.1" rpy="0 0 0"/>
      <mass value="1.5"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.002"/>
    </inertial>
    <visual><geometry><box size="0.1 0.1 0.2"/></geometry></visual>
  </link>
  <link name="tip"><collision><geometry><sphere radius="0.02"/></geometry></collision></link>
  <joint name="tip_fixed" type="fixed">
    <parent link="upper"/><child link="tip"/>
    <origin xyz="0 0 -0.2"/>
  </joint>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/>
    <origin xyz="0.1 0 0" rpy="0 0 0"/>
    <axis xyz="0 2 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="5"/>
    <dynamics damping="0.1"/>
  </joint>
</robot>
)";

std::string ErrorOf(const std::string& xml) {
  return pbppo::test::RefusalOf(ParseUrdf(xml, "arm.urdf"));
}

}  // namespace

TEST_CASE("urdf: a small arm parses - joints in topological order - axis normalised") {
  auto r = ParseUrdf(kGood, "arm.urdf");
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  CHECK(r->name == "arm");
  REQUIRE(r->links.size() == 3);
  REQUIRE(r->joints.size() == 2);
  CHECK(r->links[r->root].name == "base");
  CHECK(r->joints[0].name == "shoulder");  // the root's joint first, though listed second
  CHECK(r->joints[1].name == "tip_fixed");
  CHECK(r->joints[0].axis[1] == doctest::Approx(1.0));
  CHECK(r->joints[0].damping_nm_s_rad == doctest::Approx(0.1));
  CHECK(r->joints[1].origin.xyz[2] == doctest::Approx(-0.2));
  CHECK(r->links[2].sphere_radius_m == doctest::Approx(0.02));
  CHECK(r->TotalMassKg() == doctest::Approx(1.5));
}

TEST_CASE("urdf: collision shapes - sphere, box and cylinder with their origins") {
  const std::string xml = ReplaceOnce(kGood, "<link name=\"base\"/>", R"(<link name="base">
    <collision><origin xyz="0 0 0.1" rpy="0 0 0"/><geometry><box size="0.4 0.2 0.1"/></geometry></collision>
    <collision><origin xyz="0 0 -0.1" rpy="1.5707963 0 0"/><geometry><cylinder radius="0.02" length="0.3"/></geometry></collision>
  </link>)");
  auto r = ParseUrdf(xml, "arm.urdf");
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  const UrdfLink& base = r->links[static_cast<std::size_t>(r->FindLink("base"))];
  REQUIRE(base.collisions.size() == 2);
  CHECK(base.collisions[0].shape == UrdfShape::kBox);
  CHECK(base.collisions[0].size[1] == doctest::Approx(0.2));
  CHECK(base.collisions[0].origin.xyz[2] == doctest::Approx(0.1));
  CHECK(base.collisions[1].shape == UrdfShape::kCylinder);
  CHECK(base.collisions[1].size[0] == doctest::Approx(0.02));
  CHECK(base.collisions[1].size[1] == doctest::Approx(0.3));
  CHECK(base.collisions[1].origin.rpy[0] == doctest::Approx(1.5707963));
  CHECK(base.sphere_radius_m == 0.0);
  const UrdfLink& tip = r->links[static_cast<std::size_t>(r->FindLink("tip"))];
  REQUIRE(tip.collisions.size() == 1);
  CHECK(tip.collisions[0].shape == UrdfShape::kSphere);
  CHECK(ErrorOf(ReplaceOnce(xml, "length=\"0.3\"", "length=\"-0.3\"")) ==
        "arm.urdf: link 'base'.collision.geometry.cylinder.length: '-0.3' is not a positive number");
  CHECK(ErrorOf(ReplaceOnce(xml, "<box size=\"0.4 0.2 0.1\"/>", "<mesh filename=\"a.stl\"/>")) ==
        "arm.urdf: link 'base'.collision.geometry: has no sphere, box or cylinder (the shapes supported)");
  CHECK(ErrorOf(ReplaceOnce(xml, "size=\"0.4 0.2 0.1\"", "size=\"0.4 0.2\"")) ==
        "arm.urdf: link 'base'.collision.geometry.box.size: '0.4 0.2' has fewer than 3 numbers");
}

TEST_CASE("urdf: bad files are refused naming the element and field") {
  CHECK(ErrorOf(ReplaceOnce(kGood, "effort=\"10\"", "effort=\"-1\"")) ==
        "arm.urdf: joint 'shoulder'.limit.effort: '-1' is not a positive number");
  CHECK(ErrorOf(ReplaceOnce(kGood, "lower=\"-1\"", "lower=\"2\"")) ==
        "arm.urdf: joint 'shoulder'.limit.lower: '2' is not below upper '1'");
  CHECK(ErrorOf(ReplaceOnce(kGood, " velocity=\"5\"", "")) ==
        "arm.urdf: joint 'shoulder'.limit: missing attribute 'velocity'");
  CHECK(ErrorOf(ReplaceOnce(kGood, "<mass value=\"1.5\"/>", "<mass value=\"abc\"/>")) ==
        "arm.urdf: link 'upper'.inertial.mass.value: 'abc' is not a number");
  CHECK(ErrorOf(ReplaceOnce(kGood, "<mass value=\"1.5\"/>", "<mass value=\"0\"/>")) ==
        "arm.urdf: link 'upper'.inertial.mass.value: '0' is not a positive number");
  CHECK(ErrorOf(ReplaceOnce(kGood, "izz=\"0.002\"", "izz=\"0.5\"")) ==
        "arm.urdf: link 'upper'.inertial.inertia: moments ixx 0.01, iyy 0.01, izz 0.5 violate the triangle inequality");
  CHECK(ErrorOf(ReplaceOnce(kGood, "iyy=\"0.01\"", "iyy=\"nan\"")) ==
        "arm.urdf: link 'upper'.inertial.inertia.iyy: 'nan' is not finite");
  CHECK(ErrorOf(ReplaceOnce(kGood, "type=\"revolute\"", "type=\"prismatic\"")) ==
        "arm.urdf: joint 'shoulder'.type: 'prismatic' is not supported (revolute, continuous, fixed)");
  CHECK(ErrorOf(ReplaceOnce(kGood, "<parent link=\"base\"/>", "<parent link=\"torso\"/>")) ==
        "arm.urdf: joint 'shoulder'.parent.link: 'torso' is not a link of this robot");
  CHECK(ErrorOf(ReplaceOnce(kGood, "axis xyz=\"0 2 0\"", "axis xyz=\"0 0 0\"")) ==
        "arm.urdf: joint 'shoulder'.axis.xyz: is the zero vector");
  CHECK(ErrorOf(ReplaceOnce(kGood, "axis xyz=\"0 2 0\"", "axis xyz=\"0 1\"")) ==
        "arm.urdf: joint 'shoulder'.axis.xyz: '0 1' has fewer than 3 numbers");
  CHECK(ErrorOf(ReplaceOnce(kGood, "<link name=\"tip\">", "<link name=\"upper\">")) ==
        "arm.urdf: link 'upper': name used twice");
  CHECK(ErrorOf(ReplaceOnce(kGood, "<parent link=\"base\"/><child link=\"upper\"/>",
                            "<parent link=\"base\"/><child link=\"tip\"/>")) ==
        "arm.urdf: joint 'shoulder'.child.link: 'tip' is already the child of joint 'tip_fixed'");
  CHECK(ErrorOf(ReplaceOnce(kGood, "<link name=\"base\"/>", "<link name=\"base\"/><link name=\"spare\"/>")) ==
        "arm.urdf: robot 'arm': links 'base' and 'spare' both have no parent joint (one tree expected)");
  CHECK(ErrorOf(ReplaceOnce(kGood, "<parent link=\"base\"/>", "<parent link=\"tip\"/>")) ==
        "arm.urdf: joint 'tip_fixed': is part of a loop, not reachable from the root link");
}

TEST_CASE("urdf: malformed XML is refused with the line") {
  CHECK(ErrorOf(ReplaceOnce(kGood, "</robot>", "")) == "arm.urdf:3: XML: element <robot> is not closed");
  CHECK(ErrorOf(ReplaceOnce(kGood, "<mass value=\"1.5\"/>", "<mass value=1.5/>")) ==
        "arm.urdf:8: XML: attribute 'value' of <mass> is not quoted");
  CHECK(ErrorOf(ReplaceOnce(kGood, "</inertial>", "</inertia>")) ==
        "arm.urdf:10: XML: <inertial> closed by </inertia>");
  CHECK(ErrorOf("<robot name=\"a\"></robot><robot/>") == "arm.urdf:1: XML: a second root element");
  CHECK(ErrorOf("<robt name=\"a\"/>") == "arm.urdf: root element: <robt> is not <robot>");
}

TEST_CASE("quadruped: URDF and description load - 12 actuated joints - 13 kg - default pose") {
  auto d = LoadRobotDescription(pbppo::test::SourcePath("models/quadruped/quadruped.yaml"));
  REQUIRE_MESSAGE(d.ok(), d.error().message);
  CHECK(d->urdf.TotalMassKg() == doctest::Approx(13.0));
  REQUIRE(d->joint_count() == 12);
  CHECK(d->joint_names[0] == "LF_HAA");
  CHECK(d->joint_names[11] == "RH_KFE");
  const double want[12] = {0, 0.4, -0.8, 0, 0.4, -0.8, 0, -0.4, 0.8, 0, -0.4, 0.8};
  for (std::size_t i = 0; i < 12; ++i) CHECK(d->default_q_rad[i] == want[i]);
  CHECK(d->joint_at(2).effort_nm == 37.5);
  CHECK(d->joint_at(1).effort_nm == 25.0);
  CHECK(d->stand_base_height_m == 0.8);
  CHECK(d->urdf.links[d->urdf.root].name == "base");
}

TEST_CASE("robot description: errors name the field") {
  auto urdf = LoadUrdf(pbppo::test::SourcePath("models/quadruped/quadruped.urdf"));
  REQUIRE(urdf.ok());
  const std::string good = R"(urdf: quadruped.urdf
joints: [LF_HAA, LF_HFE, LF_KFE, RF_HAA, RF_HFE, RF_KFE, LH_HAA, LH_HFE, LH_KFE, RH_HAA, RH_HFE, RH_KFE]
default_pose: {LF_HAA: 0, LF_HFE: 0.4, LF_KFE: -0.8, RF_HAA: 0, RF_HFE: 0.4, RF_KFE: -0.8, LH_HAA: 0, LH_HFE: -0.4, LH_KFE: 0.8, RH_HAA: 0, RH_HFE: -0.4, RH_KFE: 0.8}
stand: {base_height_m: 0.8}
gains: {kp_nm_rad: 60, kd_nm_s_rad: 1.5, damping_kd_nm_s_rad: 2}
)";
  auto err = [&](const std::string& y) {
    auto r = ParseRobotDescription(y, "q.yaml", *urdf, "quadruped.urdf");
    REQUIRE_FALSE(r.ok());
    return r.error().message;
  };
  REQUIRE(ParseRobotDescription(good, "q.yaml", *urdf, "quadruped.urdf").ok());
  CHECK(err(ReplaceOnce(good, "LF_KFE: -0.8", "LF_KFE: 1.0")) ==
        "q.yaml: default_pose.LF_KFE: '1.0' is outside the joint's limits [-2.6, 0.3]");
  CHECK(err(ReplaceOnce(good, "RH_HFE, RH_KFE]", "RH_HFE, RH_KNEE]")) ==
        "q.yaml: joints[11]: 'RH_KNEE' is not a joint of quadruped.urdf");
  CHECK(err(ReplaceOnce(good, "LF_HAA, LF_HFE, LF_KFE, ", "LF_HAA, LF_HFE, ")) ==
        "q.yaml: joints: revolute joint 'LF_KFE' of quadruped.urdf is not listed");
  CHECK(err(ReplaceOnce(good, "LF_HFE, LF_KFE, RF_HAA", "LF_FOOT_FIXED, LF_KFE, RF_HAA")) ==
        "q.yaml: joints[1]: 'LF_FOOT_FIXED' is not a revolute or continuous joint");
  CHECK(err(ReplaceOnce(good, "kp_nm_rad: 60", "kp_nm_rad: x")) == "q.yaml: gains.kp_nm_rad: 'x' is not a number");
  CHECK(err(ReplaceOnce(good, "stand:", "stands:")) == "q.yaml: stands: unknown field");
  CHECK(err(ReplaceOnce(good, "RH_HFE: -0.4, ", "")) == "q.yaml: default_pose: missing field 'RH_HFE'");
}

TEST_CASE("urdf: a continuous joint - no position limits (lower and upper ignored), <limit> optional") {
  const std::string wheel = ReplaceOnce(kGood, "type=\"revolute\"", "type=\"continuous\"");
  auto r = ParseUrdf(wheel, "arm.urdf");
  REQUIRE_MESSAGE(r.ok(), r.error().message);
  const UrdfJoint& j = r->joints[0];
  CHECK(j.type == UrdfJointType::kContinuous);
  CHECK(j.continuous());
  CHECK(j.moves());
  CHECK(j.lower_rad == -HUGE_VAL);  // lower="-1" upper="1" were ignored
  CHECK(j.upper_rad == HUGE_VAL);
  CHECK(j.effort_nm == 10.0);
  CHECK(j.velocity_rad_s == 5.0);
  CHECK(std::string(ToString(j.type)) == "continuous");
  // Without <limit>: no effort or velocity limit (an actuated joint is refused by the description).
  auto bare =
      ParseUrdf(ReplaceOnce(wheel, "<limit lower=\"-1\" upper=\"1\" effort=\"10\" velocity=\"5\"/>", ""), "arm.urdf");
  REQUIRE_MESSAGE(bare.ok(), bare.error().message);
  CHECK(bare->joints[0].velocity_rad_s == 0.0);
  CHECK(bare->joints[0].effort_nm == 0.0);
  // A <limit> given must be complete and positive.
  CHECK(ErrorOf(ReplaceOnce(wheel, " velocity=\"5\"", "")) ==
        "arm.urdf: joint 'shoulder'.limit: missing attribute 'velocity'");
  CHECK(ErrorOf(ReplaceOnce(wheel, "effort=\"10\"", "effort=\"0\"")) ==
        "arm.urdf: joint 'shoulder'.limit.effort: '0' is not a positive number");
}

TEST_CASE("robot description: the diffbot - continuous wheels velocity-commanded, the head by position") {
  auto d = LoadRobotDescription(pbppo::test::SourcePath("tests/data/diffbot/diffbot.yaml"));
  REQUIRE_MESSAGE(d.ok(), d.error().message);
  REQUIRE(d->joint_count() == 3);
  CHECK(d->joint_names == std::vector<std::string>{"left_wheel", "right_wheel", "head_pan"});
  CHECK(d->velocity_commanded(0));
  CHECK(d->velocity_commanded(1));
  CHECK_FALSE(d->velocity_commanded(2));
  CHECK(d->joint_at(0).continuous());
  CHECK(d->velocity_kd_nm_s_rad[0] == 0.3);
  CHECK(d->velocity_kd_nm_s_rad[2] == 0.0);
  CHECK(d->default_q_rad == std::vector<double>{0.0, 0.0, 0.3});
}

TEST_CASE("robot description: continuous and velocity-commanded joints - errors name the file, field and value") {
  const std::string urdf_path = pbppo::test::SourcePath("tests/data/diffbot/diffbot.urdf");
  auto urdf = LoadUrdf(urdf_path);
  REQUIRE(urdf.ok());
  const std::string good = pbppo::test::ReadText(pbppo::test::SourcePath("tests/data/diffbot/diffbot.yaml"));
  auto parse = [&](const std::string& y, const UrdfModel& u) {
    return ParseRobotDescription(y, "diffbot.yaml", u, urdf_path);
  };
  auto err = [&](const std::string& y) {
    auto r = parse(y, *urdf);
    REQUIRE_FALSE(r.ok());
    return r.error().message;
  };
  REQUIRE(parse(good, *urdf).ok());
  // A continuous joint given a position target, or not velocity-commanded.
  CHECK(err(ReplaceOnce(good, "  head_pan: 0.3", "  head_pan: 0.3\n  left_wheel: 1.0")) ==
        "diffbot.yaml: default_pose.left_wheel: '1.0': joint 'left_wheel' is continuous and velocity-commanded: it "
        "takes no position target (it holds zero speed where others hold their default pose)");
  CHECK(err(ReplaceOnce(good, "  right_wheel: {kd_nm_s_rad: 0.3}\n", "")) ==
        "diffbot.yaml: joints[1]: 'right_wheel' is a continuous joint of diffbot.urdf: it takes no position target "
        "(give it velocity_control.right_wheel)");
  // A velocity-commanded joint without a velocity limit (a continuous joint without <limit>).
  auto no_limit =
      ParseUrdf(ReplaceOnce(ReadText(urdf_path), "<limit effort=\"3.0\" velocity=\"20.0\"/>", ""), "diffbot.urdf");
  REQUIRE_MESSAGE(no_limit.ok(), no_limit.error().message);
  auto r = parse(good, *no_limit);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message ==
        "diffbot.yaml: velocity_control.left_wheel: joint 'left_wheel' of diffbot.urdf has no velocity limit (<limit "
        "velocity=...>): a velocity-commanded joint's speed limit comes from it");
  CHECK(err(ReplaceOnce(good, "left_wheel: {kd_nm_s_rad: 0.3}", "left_wheel: {kd_nm_s_rad: -0.3}")) ==
        "diffbot.yaml: velocity_control.left_wheel.kd_nm_s_rad: '-0.3' is outside [1e-09, inf]");
  CHECK(err(ReplaceOnce(good, "left_wheel: {kd_nm_s_rad: 0.3}", "left_wheel: {kd: 0.3}")) ==
        "diffbot.yaml: velocity_control.left_wheel.kd: unknown field");
  CHECK(err(ReplaceOnce(good, "  left_wheel: {kd_nm_s_rad: 0.3}", "  caster: {kd_nm_s_rad: 0.3}")) ==
        "diffbot.yaml: velocity_control.caster: is not an actuated joint (joints)");
  CHECK(err(ReplaceOnce(good, "joints: [left_wheel, right_wheel, head_pan]", "joints: [left_wheel, head_pan]")) ==
        "diffbot.yaml: joints: continuous joint 'right_wheel' of diffbot.urdf is not listed");
  // A revolute joint may be velocity-commanded too; it then has no default pose either.
  auto head = parse(ReplaceOnce(ReplaceOnce(good, "  head_pan: 0.3", ""),
                                "velocity_control:", "velocity_control:\n  head_pan: {kd_nm_s_rad: 0.05}"),
                    *urdf);
  REQUIRE_MESSAGE(head.ok(), head.error().message);
  CHECK(head->velocity_commanded(2));
  CHECK(err(ReplaceOnce(good, "velocity_control:", "velocity_control:\n  head_pan: {kd_nm_s_rad: 0.05}")) ==
        "diffbot.yaml: default_pose.head_pan: '0.3': joint 'head_pan' is velocity-commanded: it takes no position "
        "target (it holds zero speed where others hold their default pose)");
  // The sit pose (optional): the position-commanded joints, as the default pose.
  auto sits = parse(good + "\nsit_pose: {head_pan: 0.1}\n", *urdf);
  REQUIRE_MESSAGE(sits.ok(), sits.error().message);
  CHECK(sits->sit_q_rad == std::vector<double>{0.0, 0.0, 0.1});
  CHECK(parse(good, *urdf)->sit_q_rad.empty());
  CHECK(err(good + "\nsit_pose: {head_pan: 0.1, left_wheel: 1.0}\n") ==
        "diffbot.yaml: sit_pose.left_wheel: '1.0': joint 'left_wheel' is continuous and velocity-commanded: it "
        "takes no position target (it holds zero speed where others hold their sit pose)");
  CHECK(err(good + "\nsit_pose: {head_pan: 0.1, neck: 0}\n") ==
        "diffbot.yaml: sit_pose.neck: is not an actuated joint");
  CHECK(err(good + "\nsit_pose: {left_wheel: 0}\n").find("diffbot.yaml: sit_pose.left_wheel: '0'") == 0);
  CHECK(err(good + "\nsit_pose: {}\n") == "diffbot.yaml: sit_pose: missing field 'head_pan'");
  CHECK(err(good + "\nsit_pose: {head_pan: 9}\n")
            .find("diffbot.yaml: sit_pose.head_pan: '9' is outside the joint's limits [") == 0);
  CHECK(err(good + "\nsit_pose: [0.1]\n").find("diffbot.yaml: sit_pose") == 0);
}
