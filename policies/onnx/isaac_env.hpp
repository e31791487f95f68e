// Isaac Lab's params/env.yaml (the ManagerBasedRLEnvCfg a run dumps) as the unitree_rl_lab
// deploy.yaml it implies, for deploy_file.hpp's one reader to check: sim.dt x decimation,
// scene.robot.init_state.joint_pos and the actuator groups' stiffness and damping (joint-name
// patterns matched against the whole name, as Isaac Lab does), the one JointPositionAction term,
// the observation group policy's terms by their func, the group's history standing for each
// term's. The articulation's joint order, which the file does not hold, is `joints` (the robot's
// joint names). Set-up time only.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/robot_model.hpp"

namespace pbppo::onnx {

// `origin` starts every error; what was assumed goes to `notes`.
Result<YAML::Node> IsaacEnvAsDeploy(const YAML::Node& env, const std::string& origin, const robot::RobotModel& robot,
                                    const std::vector<std::string>& joints, std::vector<std::string>* notes);

// A map key as text ("" for a key that is not a scalar: refused by the name checks that follow).
inline std::string YamlKey(const YAML::Node& k) {
  return k.IsScalar() ? k.Scalar() : std::string();
}

}  // namespace pbppo::onnx
