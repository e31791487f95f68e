// Deploy files (pbppo import-onnx --deploy): unitree_rl_lab's deploy.yaml for our quadruped read
// into an IO layout and a mapping, element by element, and every field the layout cannot express
// refused naming it.
#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "policies/onnx/deploy_file.hpp"
#include "runtime/robot/robot_model.hpp"
#include "tests/policies/onnx/onnx_builder.hpp"
#include "tests/support/test_paths.hpp"
#include "tests/support/text_edit.hpp"

using namespace pbppo;
namespace ox = pbppo::onnx;

namespace {

// The policy's joints breadth first (every HAA, then HFE, then KFE), as Isaac Lab orders them.
const char* kGood = R"(joint_ids_map: [0, 3, 6, 9, 1, 4, 7, 10, 2, 5, 8, 11]
step_dt: 0.02
stiffness: [20.0, 20.0, 20.0, 20.0, 20.0, 20.0, 20.0, 20.0, 20.0, 20.0, 20.0, 20.0]
damping: [0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5]
default_joint_pos: [0.0, 0.0, 0.0, 0.0, 0.4, 0.4, -0.4, -0.4, -0.8, -0.8, 0.8, 0.8]
commands:
  base_velocity:
    ranges: {lin_vel_x: [-1.0, 1.0], lin_vel_y: [-0.5, 0.5], ang_vel_z: [-1.0, 1.0], heading: null}
actions:
  JointPositionAction:
    clip: null
    joint_names: [.*]
    scale: 0.25
    offset: [0.0, 0.0, 0.0, 0.0, 0.4, 0.4, -0.4, -0.4, -0.8, -0.8, 0.8, 0.8]
    joint_ids: null
observations:
  base_ang_vel:
    params: {}
    clip: [-100.0, 100.0]
    scale: [0.25, 0.25, 0.25]
    history_length: 3
  velocity_commands:
    params: {command_name: base_velocity}
    clip: null
    scale: [2.0, 2.0, 0.25]
    history_length: 1
  joint_pos_rel:
    params: {}
    clip: null
    scale: 1.0
    history_length: 1
  last_action:
    params: {}
    clip: null
    scale: null
    history_length: 0
)";
constexpr int kInputs = 3 * 3 + 3 + 12 + 12;

const robot::RobotModel& Quadruped() {
  static const robot::RobotModel m = [] {
    auto r = robot::LoadRobotModel(test::SourcePath("models/quadruped/robot.yaml"));
    REQUIRE_MESSAGE(r.ok(), r.error().message);
    return std::move(*r);
  }();
  return m;
}

ox::Model ModelOf(int inputs) {
  test::OnnxBuilder b(inputs);
  b.Gemm(12);
  const std::string bytes = b.Bytes();
  auto m = ox::ParseModel({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, "m.onnx");
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  return std::move(*m);
}

// The text itself (no file: test cases of this binary run in parallel processes).
Result<ox::DeployImport> Read(const std::string& text, int inputs = kInputs) {
  const ox::Model model = ModelOf(inputs);
  return ox::ParseDeployFile(text, "deploy.yaml", Quadruped(), model, "l.yaml", "m.yaml");
}

std::string Refusal(const std::string& text, int inputs = kInputs) {
  auto r = Read(text, inputs);
  REQUIRE_FALSE(r.ok());
  const std::string prefix = "deploy.yaml: ";
  const std::string& m = r.error().message;
  return m.rfind(prefix, 0) == 0 ? m.substr(prefix.size()) : m;
}

}  // namespace

TEST_CASE("unitree_rl_lab's deploy.yaml: each input element is the layout observation and frame it says") {
  auto d = Read(kGood);
  REQUIRE_MESSAGE(d.ok(), d.error().message);
  const robot::IoLayout& l = d->layout;
  REQUIRE(l.observations.size() == 3 + 3 + 12 + 12);
  // Isaac Lab clips, then scales: the layout's clip is the term's times |scale|.
  CHECK(l.observations[0].signal == "base_ang_vel_x");
  CHECK(l.observations[0].scale == 0.25);
  CHECK(l.observations[0].clip == 25.0);
  CHECK(l.observations[0].history == 3);
  CHECK(l.observations[5].signal == "command_yaw_rate");
  CHECK(l.observations[5].scale == 0.25);
  CHECK(l.observations[5].clip == 1e6);  // no clip
  // joint_pos_rel in the policy's joint order, relative to default_joint_pos.
  CHECK(l.observations[6].signal == "q_LF_HAA");
  CHECK(l.observations[7].signal == "q_RF_HAA");
  CHECK(l.observations[10].signal == "q_LF_HFE");
  CHECK(l.observations[10].offset == 0.4);
  CHECK(l.observations[16].signal == "q_LH_KFE");
  CHECK(l.observations[16].offset == 0.8);
  CHECK(l.observations[18].signal == "last_action_LF_HAA");
  CHECK(l.observations[18].history == 1);  // history_length 0 is 1
  // The model's inputs: base_ang_vel's three frames term-major, oldest first, then the rest.
  const std::vector<std::string> names = l.ObservationNames();
  std::vector<std::string> fed;
  for (std::int32_t s : d->mapping.input_source) fed.push_back(s < 0 ? "const" : names[static_cast<std::size_t>(s)]);
  REQUIRE(fed.size() == static_cast<std::size_t>(kInputs));
  CHECK(fed[0] == "base_ang_vel_x@-2");
  CHECK(fed[1] == "base_ang_vel_y@-2");
  CHECK(fed[3] == "base_ang_vel_x@-1");
  CHECK(fed[6] == "base_ang_vel_x");
  CHECK(fed[8] == "base_ang_vel_z");
  CHECK(fed[9] == "command_vx");
  CHECK(fed[12] == "q_LF_HAA");
  CHECK(fed[13] == "q_RF_HAA");
  CHECK(fed[35] == "last_action_RH_KFE");
  // Actions: policy order, the file's scale and offset, the robot's joint limits.
  REQUIRE(l.actions.size() == 12);
  CHECK(l.actions[1].command == "q_des_RF_HAA");
  CHECK(l.actions[4].command == "q_des_LF_HFE");
  CHECK(l.actions[4].scale == 0.25);
  CHECK(l.actions[4].offset == 0.4);
  const robot::RobotModel& q = Quadruped();
  const robot::CommandSpec& lf_hfe = q.commands[static_cast<std::size_t>(q.CommandIndex("q_des_LF_HFE"))];
  CHECK(l.actions[4].low == lf_hfe.min);
  CHECK(l.actions[4].high == lf_hfe.max);
  for (std::size_t k = 0; k < 12; ++k) CHECK(d->mapping.output_of_action[k] == k);
  CHECK(d->mapping_text.find("history: {length: 3, order: term-major, oldest: first}") != std::string::npos);
}

TEST_CASE("deploy files: the run's clip_actions (agent.yaml) narrows each target to offset -+ clip x scale") {
  const ox::Model model = ModelOf(kInputs);
  ox::AgentFile agent;
  agent.origin = "agent.yaml";
  agent.clip_actions = 1.0;
  auto d = ox::ParseDeployFile(kGood, "deploy.yaml", Quadruped(), model, "l.yaml", "m.yaml", {}, &agent);
  REQUIRE_MESSAGE(d.ok(), d.error().message);
  const robot::IoLayout& l = d->layout;
  CHECK(l.actions[4].command == "q_des_LF_HFE");  // scale 0.25, offset 0.4: [0.15, 0.65]
  CHECK(l.actions[4].low == doctest::Approx(0.15).epsilon(1e-12));
  CHECK(l.actions[4].high == doctest::Approx(0.65).epsilon(1e-12));
  bool said = false;
  for (const std::string& n : d->notes)
    said = said || n.find("actions:     agent.yaml clip_actions 1: each raw action within [-1, 1]") == 0;
  CHECK(said);
  // A clip wide enough changes nothing; one that leaves no target inside a joint's limits is refused.
  agent.clip_actions = 100.0;
  auto wide = ox::ParseDeployFile(kGood, "deploy.yaml", Quadruped(), model, "l.yaml", "m.yaml", {}, &agent);
  REQUIRE(wide.ok());
  auto plain = Read(kGood);
  REQUIRE(plain.ok());
  CHECK(wide->layout_text == plain->layout_text);
  const std::string far =
      test::ReplaceOnce(kGood, "offset: [0.0, 0.0, 0.0, 0.0, 0.4,", "offset: [0.0, 0.0, 0.0, 0.0, 9.4,");
  agent.clip_actions = 1.0;
  auto refused = ox::ParseDeployFile(far, "deploy.yaml", Quadruped(), model, "l.yaml", "m.yaml", {}, &agent);
  REQUIRE_FALSE(refused.ok());
  CHECK_MESSAGE(refused.error().message.find("agent.yaml: clip_actions: 1 bounds joint LF_HFE's targets to [9.15, "
                                             "9.65], outside its limits") == 0,
                refused.error().message);
}

TEST_CASE("deploy files: what the layout cannot express is refused naming the field") {
  using test::ReplaceOnce;
  const std::string g = kGood;
  CHECK(Refusal(g + "gait: {period: 0.5}\n").find("gait") != std::string::npos);
  CHECK(Refusal(ReplaceOnce(g, "step_dt: 0.02", "step_dt: 0.01")) ==
        "step_dt: 0.01 s, but robot 'quadruped' runs its policy every 0.02 s (robot.yaml timing.policy_period_s)");
  CHECK(Refusal(ReplaceOnce(g, "[0, 3, 6, 9,", "[0, 0, 6, 9,")) ==
        "joint_ids_map[1]: motor 0 (LF_HAA) is already policy joint 0");
  // The joints in the robot's order instead of the policy's: the default pose gives it away.
  CHECK(Refusal(ReplaceOnce(g, "[0, 3, 6, 9, 1, 4, 7, 10, 2, 5, 8, 11]", "[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11]")) ==
        "default_joint_pos[1]: 0 rad for policy joint 1 (motor 1, LF_HFE), but the robot's default pose is 0.4 rad "
        "there: a deploy file for another robot, or a joint_ids_map in another joint order?");
  CHECK(Refusal(ReplaceOnce(g, "[0, 3, 6, 9,", "[12, 3, 6, 9,")) ==
        "joint_ids_map[0]: 12 is not a motor index of robot 'quadruped' (0..11)");
  CHECK(Refusal(ReplaceOnce(g, "stiffness: [20.0,", "stiffness: [40.0,")) ==
        "stiffness[0]: 40 for joint LF_HAA, but robot 'quadruped' tracks a policy's targets with kp 20 "
        "(robot.yaml motors.policy_gains): the policy would run with other gains than it was trained with");
  CHECK(Refusal(ReplaceOnce(g, "damping: [0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5]",
                            "damping: [0.5, 0.5, 0.5]"))
            .find("damping: 3 values, but joint_ids_map names motor 3") == 0);
  CHECK(Refusal(ReplaceOnce(g, "  base_ang_vel:", "  height_scan:")) ==
        "observations.height_scan: an observation term no signal of robot 'quadruped' gives (the importer knows "
        "base_ang_vel, projected_gravity, velocity_commands, joint_pos_rel, joint_pos, joint_vel_rel, joint_vel, "
        "last_action)");
  CHECK(Refusal(ReplaceOnce(g, "  base_ang_vel:", "  base_lin_vel:")).find("observations.base_lin_vel: ") == 0);
  CHECK(Refusal(ReplaceOnce(g, "clip: [-100.0, 100.0]", "clip: [-1.0, 2.0]")) ==
        "observations.base_ang_vel.clip: [-1, 2] is not symmetric about 0: the layout clips symmetrically");
  CHECK(Refusal(ReplaceOnce(g, "JointPositionAction:", "JointVelocityAction:")) ==
        "actions.JointVelocityAction: an action term the layout cannot express (only JointPositionAction: joint "
        "position targets)");
  CHECK(Refusal(ReplaceOnce(g, "joint_names: [.*]", "joint_names: [.*_HFE]")) ==
        "actions.JointPositionAction.joint_names: '[.*_HFE]': only [.*] (every joint of joint_ids_map)");
  CHECK(Refusal(ReplaceOnce(g, "scale: 0.25", "scale: [0.25, 0.25]")) ==
        "actions.JointPositionAction.scale: 2 values, expected 12 (one per element of actions.JointPositionAction)");
  CHECK(Refusal(ReplaceOnce(g, "  joint_pos_rel:\n    params: {}", "  joint_pos_rel:\n    params: {asset_cfg: legs}"))
            .find("observations.joint_pos_rel.params: ") == 0);
  CHECK(Refusal(ReplaceOnce(g, "{command_name: base_velocity}", "{command_name: pose}"))
            .find("observations.velocity_commands.params: ") == 0);
  CHECK(Refusal(ReplaceOnce(g, "    params: {command_name: base_velocity}\n", "")) ==
        "observations.velocity_commands: missing field 'params': the robot's operator gives base_velocity only "
        "({command_name: base_velocity})");
  CHECK(Refusal(ReplaceOnce(g, "history_length: 3", "history_length: 2.5")) ==
        "observations.base_ang_vel.history_length: 2.5 is not a whole number");
  // The model against what the deploy file says: its input size.
  CHECK(Refusal(g, kInputs + 1).find("input.size is 37") != std::string::npos);
}

namespace {

// An Isaac Lab env.yaml of the same policy as kGood (abridged; PyYAML's tuple tags included).
const char* kEnv = R"(sim:
  dt: 0.005
  gravity: !!python/tuple
  - 0.0
  - 0.0
  - -9.81
decimation: 4
scene:
  robot:
    init_state:
      joint_pos:
        .*_HAA: 0.0
        (LF|RF)_HFE: 0.4
        (LH|RH)_HFE: -0.4
        (LF|RF)_KFE: -0.8
        (LH|RH)_KFE: 0.8
    actuators:
      legs:
        joint_names_expr: [.*_HAA, .*_HFE, .*_KFE]
        stiffness: 20.0
        damping: {.*: 0.5}
observations:
  policy:
    concatenate_terms: true
    history_length: null
    base_ang_vel:
      func: isaaclab.envs.mdp.observations:base_ang_vel
      params: {}
      modifiers: null
      noise: {func: isaaclab.utils.noise.noise_model:uniform_noise, n_min: -0.2, n_max: 0.2}
      clip: !!python/tuple [-100.0, 100.0]
      scale: 0.25
      history_length: 3
    velocity_commands:
      func: isaaclab.envs.mdp.observations:generated_commands
      params: {command_name: base_velocity}
      clip: null
      scale: !!python/tuple [2.0, 2.0, 0.25]
      history_length: 0
    joint_pos_rel:
      func: isaaclab.envs.mdp.observations:joint_pos_rel
      params: {}
      clip: null
      scale: null
      history_length: 0
    last_action:
      func: isaaclab.envs.mdp.observations:last_action
      params: {}
      clip: null
      scale: null
      history_length: 0
actions:
  joint_pos:
    class_type: isaaclab.envs.mdp.actions.joint_actions:JointPositionAction
    clip: null
    joint_names: [.*]
    scale: 0.25
    offset: 0.0
    use_default_offset: true
)";
const std::vector<std::string> kIsaacJoints = {"LF_HAA", "RF_HAA", "LH_HAA", "RH_HAA", "LF_HFE", "RF_HFE",
                                               "LH_HFE", "RH_HFE", "LF_KFE", "RF_KFE", "LH_KFE", "RH_KFE"};

Result<ox::DeployImport> ReadEnv(const std::string& text, const std::vector<std::string>& joints = kIsaacJoints) {
  const ox::Model model = ModelOf(kInputs);
  return ox::ParseDeployFile(text, "env.yaml", Quadruped(), model, "l.yaml", "m.yaml", joints);
}

std::string EnvRefusal(const std::string& text, const std::vector<std::string>& joints = kIsaacJoints) {
  auto r = ReadEnv(text, joints);
  REQUIRE_FALSE(r.ok());
  return r.error().message;
}

}  // namespace

TEST_CASE("Isaac Lab's env.yaml with its joint order: the layout and mapping the same deploy.yaml gives") {
  auto env = ReadEnv(kEnv);
  REQUIRE_MESSAGE(env.ok(), env.error().message);
  auto deploy = Read(kGood);
  REQUIRE_MESSAGE(deploy.ok(), deploy.error().message);
  CHECK(env->layout.Hash() == deploy->layout.Hash());
  CHECK(env->mapping.input_source == deploy->mapping.input_source);
  CHECK(env->mapping.output_of_action == deploy->mapping.output_of_action);
}

TEST_CASE("Isaac Lab's env.yaml: no joint order, unknown joints, patterns and terms it cannot express are refused") {
  using test::ReplaceOnce;
  const std::string e = kEnv;
  CHECK(EnvRefusal(e, {}) ==
        "env.yaml: top level: an Isaac Lab env.yaml does not hold the articulation's joint order: give it with "
        "--joints (Isaac Lab prints it as env.scene['robot'].joint_names), in the robot's joint names");
  std::vector<std::string> wrong = kIsaacJoints;
  wrong[3] = "RH_hip";
  CHECK(EnvRefusal(e, wrong).rfind("--joints: 'RH_hip' is not a joint of robot 'quadruped' (LF_HAA, ", 0) == 0);
  CHECK(EnvRefusal(ReplaceOnce(e, ".*_HAA: 0.0", ".*_HAA: 0.0\n        LF_.*: 0.1")) ==
        "env.yaml: scene.robot.init_state.joint_pos: joint LF_HAA matches both '.*_HAA' and 'LF_.*'");
  CHECK(EnvRefusal(ReplaceOnce(e, "[.*_HAA, .*_HFE, .*_KFE]", "[.*_HAA, .*_HFE]")) ==
        "env.yaml: scene.robot.actuators: joint LF_KFE is in no actuator group");
  CHECK(EnvRefusal(
            ReplaceOnce(e, "actions.joint_actions:JointPositionAction", "actions.joint_actions:JointEffortAction")) ==
        "env.yaml: actions.joint_pos.class_type: 'isaaclab.envs.mdp.actions.joint_actions:JointEffortAction': the "
        "layout expresses JointPositionAction only");
  CHECK(EnvRefusal(ReplaceOnce(e, "      modifiers: null", "      modifiers: [{func: scale}]")) ==
        "env.yaml: observations.policy.base_ang_vel.modifiers: the layout cannot express a term's modifiers");
  // What the deploy.yaml reader refuses, named in the deploy.yaml the env.yaml implies.
  CHECK(EnvRefusal(ReplaceOnce(e, "stiffness: 20.0", "stiffness: 25.0"))
            .rfind("env.yaml (as deploy.yaml): stiffness[0]: 25 for joint LF_HAA, but robot 'quadruped' tracks", 0) ==
        0);
  CHECK(EnvRefusal(ReplaceOnce(e, "dt: 0.005", "dt: 0.0025")).rfind("env.yaml (as deploy.yaml): step_dt: 0.01 s", 0) ==
        0);
  // A deploy.yaml orders its joints itself.
  const ox::Model model = ModelOf(kInputs);
  auto r = ox::ParseDeployFile(kGood, "d.yaml", Quadruped(), model, "l.yaml", "m.yaml", kIsaacJoints);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.rfind("--joints: a deploy.yaml orders the joints itself", 0) == 0);
}
