// `pbppo import-onnx MODEL.onnx --robot models/<robot>/robot.yaml --map MAP.yaml --out BLOB`:
// an ONNX actor into a policy blob for the robot's IO layout, with golden vectors beside it
// (policies/onnx, docs/onnx_import.md). Prints what was recognised and the check against the
// graph's own float64 evaluation. Exit 0: written; 1: the model, the mapping or the robot refused
// (naming the node, the field or the file), nothing written; 2: usage. With --deploy FILE in place
// of --map (a trainer's deploy file: unitree_rl_lab's deploy.yaml, or Isaac Lab's env.yaml with
// --joints, its articulation's joint order), the IO layout and mapping are
// made from it and written beside the blob (BLOB_STEM.io_layout.yaml, BLOB_STEM.map.yaml); the
// blob is for that layout (a copy of the robot file whose files.io_layout names it runs it). The
// run's rsl_rl agent.yaml (--agent FILE, else the agent.yaml beside the deploy file when there is
// one) is checked against the graph's actor (memory, hidden layers, activation, normaliser) and
// its clip_actions applied to the raw actions.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace pbppo::cli {

struct ImportOnnxOptions {
  std::string model, robot, map, deploy, agent, out;
  std::vector<std::string> joints;  // --joints: an Isaac Lab env.yaml's joint order
  std::uint64_t seed = 1;
};

CLI::App* AddImportOnnx(CLI::App& app, ImportOnnxOptions& o);
int ImportOnnx(const ImportOnnxOptions& o);

}  // namespace pbppo::cli
