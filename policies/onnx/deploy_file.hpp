// Deploy files: what a trainer exported beside its ONNX policy to say what the policy's numbers
// mean (joint order, default pose, action scale and offset, gains, observation terms with scales,
// clips and history, policy period), read into the IO layout and mapping of one of our robots
// (pbppo import-onnx --deploy). The layout and mapping are written as text in their own formats
// and read back by their own readers (io_layout.hpp, onnx_map.hpp), so a deploy file can give
// nothing those files could not say. Formats (docs/onnx_import.md):
//
//   unitree_rl_lab's deploy.yaml: joint_ids_map (the robot's motor index of each policy joint),
//   step_dt, stiffness and damping (motor order), default_joint_pos (policy order), commands,
//   actions.JointPositionAction {scale, offset, clip, joint_names, joint_ids}, observations (in
//   order) {params, scale, clip, history_length};
//
//   Isaac Lab's params/env.yaml: sim.dt x decimation, scene.robot.init_state.joint_pos and the
//   actuators' stiffness and damping (by joint-name patterns), the one JointPositionAction term,
//   the observation group policy's terms (by their func) with the group's history; its joint order
//   is the articulation's, which the file does not hold: given with the import (--joints). It is
//   turned into the deploy.yaml it implies (isaac_env.hpp) and read by the same reader (whose messages then name
//   that file's fields).
//
// Observation terms the robot's signals give: base_ang_vel, projected_gravity, velocity_commands
// (generated_commands of base_velocity), joint_pos_rel, joint_pos, joint_vel_rel, joint_vel,
// last_action (actions). Anything else is refused naming the term; so is a gain, policy period or
// clip the robot's files would not reproduce. Set-up time only.
#pragma once

#include <string>
#include <vector>

#include "policies/onnx/onnx_graph.hpp"
#include "policies/onnx/onnx_map.hpp"
#include "policies/onnx/rsl_rl_agent.hpp"
#include "runtime/core/result.hpp"
#include "runtime/robot/io_layout.hpp"
#include "runtime/robot/robot_model.hpp"

namespace pbppo::onnx {

struct DeployImport {
  std::string layout_text;         // an io_layout.yaml for the robot
  std::string mapping_text;        // the mapping of the model onto it
  robot::IoLayout layout;          // layout_text, read back
  Mapping mapping;                 // mapping_text, read back against layout
  std::vector<std::string> notes;  // what was read, and what was assumed
};

// Reads a deploy file for `robot` and the model's graph input and output (and its state inputs,
// paired with outputs by rsl_rl's names: X_in -> X_out). `layout_path` and `mapping_path` are the
// names the texts will be written under (messages name them).
// `joints`: an Isaac Lab env.yaml's joint order (the articulation's, in the robot's joint names),
// which that file does not hold; empty for a deploy.yaml, which orders them itself.
// `agent`: the run's agent.yaml (rsl_rl_agent.hpp), whose clip_actions bounds the raw actions
// before the action term (the targets' limits narrowed to offset -+ clip x |scale|); may be null.
Result<DeployImport> ReadDeployFile(const std::string& path, const robot::RobotModel& robot, const Model& model,
                                    const std::string& layout_path, const std::string& mapping_path,
                                    const std::vector<std::string>& joints = {}, const AgentFile* agent = nullptr);
// The same from the file's text; `origin` starts every error.
Result<DeployImport> ParseDeployFile(const std::string& text, const std::string& origin, const robot::RobotModel& robot,
                                     const Model& model, const std::string& layout_path,
                                     const std::string& mapping_path, const std::vector<std::string>& joints = {},
                                     const AgentFile* agent = nullptr);

}  // namespace pbppo::onnx
