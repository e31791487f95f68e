#include "policies/cli/import_onnx.hpp"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <span>

#include "policies/onnx/deploy_file.hpp"
#include "policies/onnx/onnx_import.hpp"
#include "policies/trainer/exporter.hpp"
#include "runtime/core/cli_checks.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/reference.hpp"
#include "runtime/policy/signature.hpp"
#include "runtime/robot/robot_model.hpp"

namespace pbppo::cli {

CLI::App* AddImportOnnx(CLI::App& app, ImportOnnxOptions& o) {
  auto* c =
      app.add_subcommand("import-onnx", "Import an ONNX actor (rsl_rl, stable-baselines3, ...) into a policy blob");
  c->add_option("model", o.model, "ONNX model file")->required();
  c->add_option("--robot", o.robot, "The robot file (models/<robot>/robot.yaml): its IO layout")->required();
  auto* map = c->add_option("--map", o.map, "Mapping file: the model's input and output elements in layout names");
  auto* deploy = c->add_option("--deploy", o.deploy,
                               "A trainer's deploy file (unitree_rl_lab deploy.yaml) in place of --map: the IO layout "
                               "and mapping are made from it and written beside the blob");
  map->excludes(deploy);
  c->add_option("--joints", o.joints,
                "--deploy with an Isaac Lab env.yaml: the articulation's joint order (env.scene['robot'].joint_names), "
                "in the robot's joint names")
      ->delimiter(',')
      ->needs(deploy);
  c->add_option("--agent", o.agent,
                "--deploy: the run's rsl_rl agent.yaml, checked against the graph's actor and its clip_actions "
                "applied (default: the agent.yaml beside the deploy file, when there is one)")
      ->check(CLI::ExistingFile)
      ->needs(deploy);
  c->add_option("--out", o.out, "Output blob path (golden vectors go beside it)")->required();
  c->add_option("--seed", o.seed, "Seed of the golden-vector observations")->check(cli_checks::NonNegativeInteger());
  return c;
}

int ImportOnnx(const ImportOnnxOptions& o) {
  auto fail = [](const std::string& m) {
    std::fprintf(stderr, "pbppo import-onnx: %s\n", m.c_str());
    return 1;
  };
  auto robot = robot::LoadRobotModel(o.robot);
  if (!robot) return fail(robot.error().message);
  if (!robot->io) return fail(o.robot + ": files: no io_layout (the layout a policy runs on)");
  auto bytes = policy::ReadFileBytes(o.model, onnx::ReadLimits{}.max_file_bytes);
  if (!bytes) return fail(bytes.error().message);
  auto model = onnx::ParseModel(*bytes, o.model);
  if (!model) return fail(model.error().message);
  if (o.map.empty() == o.deploy.empty()) return fail("give the mapping with --map or a deploy file with --deploy");
  const robot::IoLayout* layout = &*robot->io;
  std::optional<onnx::Mapping> mapping;
  std::optional<onnx::DeployImport> deployed;
  const std::string stem = policy::PathBeside(o.out, "");
  const std::string layout_path = stem + ".io_layout.yaml", mapping_path = stem + ".map.yaml";
  std::optional<onnx::AgentFile> agent;
  if (!o.deploy.empty()) {
    if (const std::string a = o.agent.empty() ? onnx::AgentFileBeside(o.deploy) : o.agent; !a.empty()) {
      auto read = onnx::ReadAgentFile(a);
      if (!read) return fail(read.error().message);
      agent = std::move(*read);
    }
    auto d =
        onnx::ReadDeployFile(o.deploy, *robot, *model, layout_path, mapping_path, o.joints, agent ? &*agent : nullptr);
    if (!d) return fail(d.error().message);
    deployed = std::move(*d);
    layout = &deployed->layout;
    mapping = deployed->mapping;
  } else {
    auto m = onnx::LoadMapping(o.map, *robot->io);
    if (!m) return fail(m.error().message);
    mapping = std::move(*m);
  }
  onnx::ImportOptions io;
  io.source_name = std::filesystem::path(o.model).filename().string();
  io.source_sha256 = policy::Sha256Hex(*bytes);
  io.importer = std::string("pbppo-rt ") + PBPPO_VERSION + " " + trainer::BuildGitRevision();
  io.golden_seed = o.seed;
  auto imported = onnx::Import(*model, *mapping, *layout, io);
  if (!imported) return fail(imported.error().message);
  const policy::PolicySpec& s = imported->spec;
  std::vector<std::string> agent_notes;
  if (agent) {
    auto checked = onnx::CheckActor(*agent, s, imported->graph_normaliser);
    if (!checked) return fail(checked.error().message);
    agent_notes = std::move(*checked);
  }
  std::printf("model        %s (%s %s, opset %lld, ir %lld)\n  sha256     %s\n", o.model.c_str(),
              model->producer_name.c_str(), model->producer_version.c_str(), static_cast<long long>(model->opset),
              static_cast<long long>(model->ir_version), io.source_sha256.c_str());
  std::printf("robot        %s (layout '%s': %u observations, %u actions)\n", o.robot.c_str(), layout->robot.c_str(),
              s.input_size, s.output_size);
  if (deployed)
    for (const std::string& n : deployed->notes) std::printf("  %s\n", n.c_str());
  for (const std::string& n : imported->notes) std::printf("  %s\n", n.c_str());
  if (agent) std::printf("  agent:       %s (%s)\n", agent->origin.c_str(), agent->section.c_str());
  for (const std::string& n : agent_notes) std::printf("  %s\n", n.c_str());
  std::printf(
      "check        the blob's float64 reference against the graph's own evaluation on %zu rows: max |diff| "
      "%.3g (%.2g of the tolerance)\n",
      imported->golden.observations.size(), imported->check_max_abs, imported->check_max_ratio);
  // The layout and mapping a deploy file made, then the blob and the same golden rows the check
  // ran on (32 from --seed), beside it.
  if (deployed) {
    auto as_bytes = [](const std::string& t) {
      return std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(t.data()), t.size());
    };
    const policy::FileBytes files[] = {{layout_path, as_bytes(deployed->layout_text)},
                                       {mapping_path, as_bytes(deployed->mapping_text)}};
    if (auto st = policy::WriteFilesAtomic(files); !st) return fail(st.error().message);
  }
  if (auto st = policy::WritePolicyFiles(o.out, s, imported->golden); !st) return fail(st.error().message);
  std::printf("wrote        %s (%llu parameters) and %s\n", o.out.c_str(),
              static_cast<unsigned long long>(s.ParameterCount()), policy::GoldenPathFor(o.out).c_str());
  if (deployed)
    std::printf(
        "wrote        %s (layout hash 0x%016llx) and %s: the blob runs on a robot file whose files.io_layout "
        "names this layout\n",
        layout_path.c_str(), static_cast<unsigned long long>(layout->Hash()), mapping_path.c_str());
  return 0;
}

}  // namespace pbppo::cli
