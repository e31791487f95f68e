// The imported blobs against ONNX Runtime (label onnx): the models tools/onnx/make_models.py built
// (the onnx.models fixture) are imported, then run by the runtime engine and by ONNX Runtime
// (tools/onnx/ort_eval.js, onnxruntime-node) on random observations and on observations recorded
// from the training environments, and the commands compared. A recurrent model's rows are one
// sequence on every side: the engine's state, ONNX Runtime's state inputs fed from its outputs,
// the float64 graph's and reference's state, all zero at the first row.
//
// Tolerance: both sides compute in float32 from the same float32 weights, so each lies within the
// float64 reference's first-order float32 bound (docs/policy_blob.md, golden vectors); two sides:
// twice the bound. Added: 1e-5 relative for what the importer rounds once more to float32 (folded
// normalisers, constants and output maps) and for ONNX Runtime's tanh and exp approximations.
// That is onnx::CheckTolerance, the same figure pbppo import-onnx checks its blob against. Because
// that first-order bound is loose for wide layers, the largest difference must also stay below
// 1e-5 (measured: at most 1.6e-6), which a reduced-precision path would not meet.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "policies/envs/env.hpp"
#include "policies/onnx/onnx_eval.hpp"
#include "policies/onnx/onnx_import.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/policy/reference.hpp"
#include "runtime/robot/observation_builder.hpp"
#include "runtime/robot/robot_model.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;
namespace ox = pbppo::onnx;

namespace {

const std::string kModels = PBPPO_ONNX_MODELS_DIR;

// Observations from the environment, acting with the shipped blob (the runtime engine).
std::vector<std::vector<float>> Recorded(const std::string& env_name, const std::string& blob, int steps) {
  envs::EnvOptions o;
  o.name = env_name;
  o.purpose = envs::EnvPurpose::kEval;  // quadruped-walk: the nominal robot
  if (env_name == "auv-nav") o.flags["layout"] = "hard";
  auto env = envs::MakeEnv(o);
  REQUIRE_MESSAGE(env.ok(), env.error().message);
  auto pm = policy::PolicyModel::FromFile(test::SourcePath(blob));
  REQUIRE(pm.ok());
  auto pd = policy::MakePolicyData(*pm);
  REQUIRE(pd.ok());
  envs::Env& e = **env;
  const robot::IoLayout& layout = e.layout();
  Rng rng(11);
  std::vector<float> obs(e.observation_size()), act(e.action_size());
  std::vector<std::vector<float>> rows;
  e.Reset(rng, obs);
  for (int s = 0; s < steps; ++s) {
    rows.push_back(obs);
    std::copy(obs.begin(), obs.end(), pd->observation().begin());
    (void)policy::Forward(*pm, *pd);
    robot::ToPolicyUnits(layout, pd->action(), act);
    const envs::StepResult r = e.Step(act, obs);
    if (r.terminated || r.truncated) e.Reset(rng, obs);
  }
  return rows;
}

struct Compared {
  double max_abs = 0, max_ratio = 0, graph_ratio = 0;
  double stateless_abs = 0;  // a recurrent policy run with its state reset at every step, against ONNX Runtime
  std::size_t rows = 0;
  std::vector<std::vector<double>> engine;  // the engine's commands per row
};

Compared AgainstOrt(const std::string& name, const std::string& onnx_file, const robot::IoLayout& layout,
                    const ox::Mapping& map, const std::vector<std::vector<float>>& observations) {
  auto model = ox::ReadModelFile(onnx_file);
  REQUIRE_MESSAGE(model.ok(), model.error().message);
  auto imp = ox::Import(*model, map, layout, {});
  REQUIRE_MESSAGE(imp.ok(), imp.error().message);
  auto pm = policy::PolicyModel::FromSpec(imp->spec);
  REQUIRE_MESSAGE(pm.ok(), pm.error().message);
  auto pd = policy::MakePolicyData(*pm);
  REQUIRE(pd.ok());
  const std::string dir = test::ScratchDir("onnx_ort_" + name);
  const std::string in = dir + "/in.f32", out = dir + "/out.f32";
  {
    std::ofstream f(in, std::ios::binary);
    for (const auto& obs : observations)
      for (double v : ox::InputRow(map, obs)) {
        const float x = static_cast<float>(v);
        f.write(reinterpret_cast<const char*>(&x), 4);
      }
  }
  std::string cmd = "node " + test::SourcePath("tools/onnx/ort_eval.js") + " " + onnx_file + " " + in + " " +
                    std::to_string(observations.size()) + " " + out;
  for (const ox::StatePair& q : map.state) cmd += " " + q.input + "=" + q.output;  // the rows are one sequence
  REQUIRE_MESSAGE(std::system(cmd.c_str()) == 0, cmd);
  std::ifstream f(out, std::ios::binary);
  std::vector<float> y(observations.size() * map.output_size);
  f.read(reinterpret_cast<char*>(y.data()), static_cast<std::streamsize>(y.size() * 4));
  REQUIRE(f.gcount() == static_cast<std::streamsize>(y.size() * 4));
  Compared c;
  c.rows = observations.size();
  // The float64 graph and reference over the rows in order, a recurrent state carried from one
  // row to the next (as the engine's data and ONNX Runtime's state inputs carry it).
  auto graph = ox::GraphCommands(*model, map, layout, observations);
  REQUIRE_MESSAGE(graph.ok(), graph.error().message);
  policy::ReferenceState ref_state = policy::MakeReferenceState(imp->spec);
  auto stateless = policy::MakePolicyData(*pm);
  REQUIRE(stateless.ok());
  for (std::size_t r = 0; r < observations.size(); ++r) {
    const std::vector<double> ort_row(y.begin() + static_cast<long>(r * map.output_size),
                                      y.begin() + static_cast<long>((r + 1) * map.output_size));
    const std::vector<double> ort_cmd = ox::CommandsOf(map, layout, ort_row);
    std::copy(observations[r].begin(), observations[r].end(), pd->observation().begin());
    REQUIRE(policy::Forward(*pm, *pd) == policy::ForwardStatus::kOk);
    const policy::ReferenceOutput ref = policy::ReferenceForward(imp->spec, observations[r].data(), &ref_state);
    const std::vector<double>& graph_cmd = (*graph)[r];
    stateless->ResetState();
    std::copy(observations[r].begin(), observations[r].end(), stateless->observation().begin());
    REQUIRE(policy::Forward(*pm, *stateless) == policy::ForwardStatus::kOk);
    c.engine.emplace_back(pd->action().begin(), pd->action().end());
    for (std::size_t k = 0; k < ort_cmd.size(); ++k) {
      const double engine = static_cast<double>(pd->action()[k]);
      const double tol = ox::CheckTolerance(ref.error_bound[k], ort_cmd[k]);
      c.max_abs = std::max(c.max_abs, std::fabs(engine - ort_cmd[k]));
      c.max_ratio = std::max(c.max_ratio, std::fabs(engine - ort_cmd[k]) / tol);
      c.graph_ratio = std::max(c.graph_ratio, std::fabs(graph_cmd[k] - ort_cmd[k]) / tol);
      c.stateless_abs = std::max(c.stateless_abs, std::fabs(static_cast<double>(stateless->action()[k]) - ort_cmd[k]));
    }
  }
  MESSAGE(name << ": " << c.rows << " rows, engine vs ONNX Runtime max |diff| " << c.max_abs << " (" << c.max_ratio
               << " of the tolerance); float64 graph vs ONNX Runtime " << c.graph_ratio
               << (map.state.empty() ? "" : "; with the state reset at every step " + std::to_string(c.stateless_abs)));
  return c;
}

std::vector<std::vector<float>> RandomRows(std::size_t n, std::size_t width, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> nd(0.0f, 1.5f);
  std::vector<std::vector<float>> rows(n, std::vector<float>(width));
  for (auto& r : rows)
    for (float& x : r) x = nd(rng);
  return rows;
}

void CheckRobotModel(const std::string& name, const std::string& robot_yaml, const std::string& env,
                     const std::string& blob) {
  auto robot = robot::LoadRobotModel(test::SourcePath(robot_yaml));
  REQUIRE_MESSAGE(robot.ok(), robot.error().message);
  const robot::IoLayout& layout = *robot->io;
  auto map = ox::LoadMapping(kModels + "/" + name + ".yaml", layout);
  REQUIRE_MESSAGE(map.ok(), map.error().message);
  auto rows = RandomRows(256, layout.observation_size(), 5);
  const auto recorded = Recorded(env, blob, 400);
  rows.insert(rows.end(), recorded.begin(), recorded.end());
  const Compared c = AgainstOrt(name, kModels + "/" + name + ".onnx", layout, *map, rows);
  CHECK(c.max_ratio <= 1.0);
  CHECK(c.max_abs < 1e-5);
  CHECK(c.graph_ratio <= 1.0);
  // A recurrent model's state matters: without it the engine would be far off ONNX Runtime.
  if (!map->state.empty()) CHECK(c.stateless_abs > 1e-3);
}

}  // namespace

TEST_CASE("rsl_rl-style walking actor (48-512-256-128-12 ELU): the engine matches ONNX Runtime") {
  CheckRobotModel("rsl_rl_walk", "models/quadruped/robot.yaml", "quadruped-walk",
                  "policies/frozen/quadruped_walk/flat.blob");
}

TEST_CASE("walking actor with its normaliser in the graph, inputs and outputs reordered: matches ONNX Runtime") {
  CheckRobotModel("normalised_walk", "models/quadruped/robot.yaml", "quadruped-walk",
                  "policies/frozen/quadruped_walk/flat.blob");
}

TEST_CASE("stable-baselines3-style AUV actor (64-64 tanh, MatMul+Add, output clip): matches ONNX Runtime") {
  CheckRobotModel("sb3_auv", "models/auv/robot.yaml", "auv-nav", "policies/frozen/auv_nav/auv_nav.blob");
}

TEST_CASE("recurrent actors over 656-step sequences, the state carried: the engine matches ONNX Runtime") {
  // 256 random rows, then 400 recorded from the walking environment, as one sequence from a zero
  // state: the LSTM built from flat.blob, a GRU as torch exports it (linear_before_reset 1), a GRU
  // with ONNX's default (0) behind a Sub/Div normaliser, two stacked LSTM layers (Slice, Concat).
  for (const char* name : {"lstm_walk", "gru_actor", "gru_lbr0", "lstm_stacked"}) {
    CAPTURE(name);
    CheckRobotModel(name, "models/quadruped/robot.yaml", "quadruped-walk", "policies/frozen/quadruped_walk/flat.blob");
  }
}

TEST_CASE("LeakyReLU layers and a tanh head with an output scale and offset: matches ONNX Runtime") {
  auto layout = robot::ParseIoLayout(R"(
robot: testbot
observations: [{name: o0}, {name: o1}, {name: o2}, {name: o3}, {name: o4}, {name: o5}]
actions:
  - {name: a0, command: c0, scale: 1, offset: 0, low: -5, high: 5}
  - {name: a1, command: c1, scale: 0.5, offset: 0.1, low: -5, high: 5}
  - {name: a2, command: c2, scale: 2, offset: 0, low: -5, high: 5}
)",
                                     "testbot.yaml");
  REQUIRE_MESSAGE(layout.ok(), layout.error().message);
  auto map = ox::ParseMapping(R"(
robot: testbot
input: {name: obs, size: 6}
output: {name: actions, size: 3}
observations: [o5, o4, o3, o2, o1, o0]
actions: [a1, a2, a0]
)",
                              "map.yaml", *layout);
  REQUIRE_MESSAGE(map.ok(), map.error().message);
  const Compared c =
      AgainstOrt("leaky_tanh_head", kModels + "/leaky_tanh_head.onnx", *layout, *map, RandomRows(1000, 6, 9));
  CHECK(c.max_ratio <= 1.0);
  CHECK(c.max_abs < 1e-5);
  CHECK(c.graph_ratio <= 1.0);
}

TEST_CASE("stacked history, frame-major and term-major: each output reads the frames it names, as ONNX Runtime") {
  // tools/onnx/make_models.py states where each frame sits in either order and writes one linear
  // layer reading a0 = p(now) + 0.5 v1(3 steps ago), a1 = v0(1 step ago) - v1(2 steps ago). The
  // layout keeps 4 frames; a 300-step sequence goes through its observation builder, then the
  // imported blob and ONNX Runtime.
  auto layout = robot::ParseIoLayout(R"(
robot: histbot
observations: [{name: p, history: 4}, {name: v0, history: 4}, {name: v1, history: 4}]
actions:
  - {name: a0, command: c0, scale: 1, offset: 0, low: -100, high: 100}
  - {name: a1, command: c1, scale: 1, offset: 0, low: -100, high: 100}
)",
                                     "histbot.yaml");
  REQUIRE_MESSAGE(layout.ok(), layout.error().message);
  const int steps = 300;
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  std::vector<std::array<double, 3>> signal(steps);
  for (auto& s : signal)
    for (double& x : s) x = u(rng);
  auto builder = robot::ObservationBuilder::Create(*layout, {"p", "v0", "v1"});
  REQUIRE(builder.ok());
  std::vector<std::vector<float>> rows(steps, std::vector<float>(layout->observation_size()));
  for (int t = 0; t < steps; ++t)
    builder->Build(signal[static_cast<std::size_t>(t)].data(), t == 0, rows[static_cast<std::size_t>(t)].data());
  auto ago = [&](int t, int k, int i) {  // signal i, k steps before step t (the first step fills the history)
    return static_cast<double>(
        static_cast<float>(signal[static_cast<std::size_t>(std::max(t - k, 0))][static_cast<std::size_t>(i)]));
  };
  for (const char* name : {"history_frame_major", "history_term_major"}) {
    CAPTURE(name);
    auto map = ox::LoadMapping(kModels + "/" + name + ".yaml", *layout);
    REQUIRE_MESSAGE(map.ok(), map.error().message);
    const Compared c = AgainstOrt(name, kModels + "/" + name + ".onnx", *layout, *map, rows);
    CHECK(c.max_ratio <= 1.0);
    CHECK(c.max_abs < 1e-5);
    CHECK(c.graph_ratio <= 1.0);
    double worst = 0;
    for (int t = 0; t < steps; ++t) {
      const auto& cmd = c.engine[static_cast<std::size_t>(t)];
      worst = std::max(worst, std::fabs(cmd[0] - (ago(t, 0, 0) + 0.5 * ago(t, 3, 2))));
      worst = std::max(worst, std::fabs(cmd[1] - (ago(t, 1, 1) - ago(t, 2, 2))));
    }
    MESSAGE(std::string(name) << ": engine against the frames it names, max |diff| " << worst);
    CHECK(worst < 1e-5);
  }
}
