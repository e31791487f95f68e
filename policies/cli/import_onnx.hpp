// `pbppo import-onnx MODEL.onnx --robot models/<robot>/robot.yaml --map MAP.yaml --out BLOB`:
// an ONNX actor into a policy blob for the robot's IO layout, with golden vectors beside it
// (policies/onnx, docs/onnx_import.md). Prints what was recognised and the check against the
// graph's own float64 evaluation. Exit 0: written; 1: the model, the mapping or the robot refused
// (naming the node, the field or the file), nothing written; 2: usage.
#pragma once

#include <cstdint>
#include <string>

namespace CLI {
class App;
}

namespace pbppo::cli {

struct ImportOnnxOptions {
  std::string model, robot, map, out;
  std::uint64_t seed = 1;
};

CLI::App* AddImportOnnx(CLI::App& app, ImportOnnxOptions& o);
int ImportOnnx(const ImportOnnxOptions& o);

}  // namespace pbppo::cli
