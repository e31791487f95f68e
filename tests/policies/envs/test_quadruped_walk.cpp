// quadruped-walk: the generated MuJoCo model matches the description, the robot stands on its
// default pose, the observation is what the devices report, runs are deterministic, and bad
// inputs are refused at start naming the value.
#include <doctest/doctest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "policies/envs/mjcf.hpp"
#include "policies/envs/quadruped_walk.hpp"
#include "runtime/robot/robot_model.hpp"
#include "runtime/transport/can/mit_codec.hpp"
#include "runtime/transport/can/quantize.hpp"
#include "tests/support/robot_models.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;
using namespace pbppo::envs;

namespace {

QuadrupedWalkOptions Nominal(const std::string& terrain = "flat") {
  QuadrupedWalkOptions o;
  o.models_dir = test::SourcePath("models");
  o.terrain = terrain;
  o.noise = false;
  o.randomize = false;
  return o;
}

std::unique_ptr<QuadrupedWalk> MakeWalk(const QuadrupedWalkOptions& o) {
  auto e = QuadrupedWalk::Make(o);
  REQUIRE_MESSAGE(e.ok(), e.error().message);
  return std::move(e).value();
}

std::string Read(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// A copy of models/quadruped with texts of one file replaced (from, to, from, to, ...).
std::string ModelsWith(const std::string& name, const std::string& file, const std::vector<std::string>& edits) {
  const std::string dir = std::filesystem::path(test::CopyRobotFolder("quadruped", name)).parent_path().string();
  std::string text = Read(dir + "/quadruped/" + file);
  for (std::size_t k = 0; k + 1 < edits.size(); k += 2) {
    const auto at = text.find(edits[k]);
    REQUIRE_MESSAGE(at != std::string::npos, edits[k]);
    text.replace(at, edits[k].size(), edits[k + 1]);
  }
  std::ofstream(dir + "/quadruped/" + file) << text;
  return dir;
}

std::string ModelsWith(const std::string& name, const std::string& file, const std::string& from,
                       const std::string& to) {
  return ModelsWith(name, file, std::vector<std::string>{from, to});
}

std::string ErrorOf(const QuadrupedWalkOptions& o) {
  auto e = QuadrupedWalk::Make(o);
  REQUIRE_FALSE(e.ok());
  return e.error().message;
}

}  // namespace

TEST_CASE("quadruped-walk: trains with the controller's robot - robot.yaml's gains, layout and description") {
  auto model = robot::LoadRobotModel(test::SourcePath("models/quadruped/robot.yaml"));
  REQUIRE_MESSAGE(model.ok(), model.error().message);
  QuadrupedWalkOptions o;
  o.models_dir = test::SourcePath("models");
  auto env = QuadrupedWalk::Make(o);
  REQUIRE_MESSAGE(env.ok(), env.error().message);
  for (const auto& mo : model->motors) {
    CHECK(mo.policy_kp == (*env)->params().kp_nm_rad);
    CHECK(mo.policy_kd == (*env)->params().kd_nm_s_rad);
  }
  CHECK((*env)->layout().Hash() == model->io->Hash());
  // Gains edited in robot.yaml reach training: one place for them.
  o.models_dir = ModelsWith("walk_gains", "robot.yaml", "kp_nm_rad: 20.0", "kp_nm_rad: 25.0");
  auto edited = QuadrupedWalk::Make(o);
  REQUIRE_MESSAGE(edited.ok(), edited.error().message);
  CHECK((*edited)->params().kp_nm_rad == 25.0);
}

TEST_CASE("quadruped-walk: the generated MJCF is the URDF - free base, 12 hinges with their limits, the mass") {
  auto robot = robot::LoadRobotDescription(test::SourcePath("models/quadruped/quadruped.yaml"));
  REQUIRE(robot.ok());
  MjcfOptions o;
  auto xml = GenerateMjcf(*robot, o);
  REQUIRE(xml.ok());
  auto m = CompileMjcf(*xml, "q");
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  mjModel* model = *m;
  CHECK(model->nq == 19);
  CHECK(model->nv == 18);
  CHECK(model->nu == 12);
  CHECK(model->opt.timestep == doctest::Approx(0.005));
  double mass = 0;
  for (int b = 0; b < model->nbody; ++b) mass += model->body_mass[b];
  CHECK(mass == doctest::Approx(robot->urdf.TotalMassKg()));
  for (std::size_t i = 0; i < robot->joint_count(); ++i) {
    const robot::UrdfJoint& j = robot->joint_at(i);
    const int id = mj_name2id(model, mjOBJ_JOINT, j.name.c_str());
    REQUIRE(id >= 0);
    CHECK(model->jnt_range[2 * id] == doctest::Approx(j.lower_rad));
    CHECK(model->jnt_range[2 * id + 1] == doctest::Approx(j.upper_rad));
    // Motor i drives actuated joint i, limited to its effort.
    CHECK(model->actuator_trnid[2 * i] == id);
    CHECK(model->actuator_ctrlrange[2 * i + 1] == doctest::Approx(j.effort_nm));
  }
  int spheres = 0, capsules = 0;
  for (int g = 0; g < model->ngeom; ++g) {
    spheres += model->geom_type[g] == mjGEOM_SPHERE;
    capsules += model->geom_type[g] == mjGEOM_CAPSULE;
  }
  CHECK(spheres == 4);
  CHECK(capsules == 8);  // thighs and shanks
  const int geoms = model->ngeom;
  mj_deleteModel(model);
  o.block_geoms = 16;
  auto with_blocks = CompileMjcf(*GenerateMjcf(*robot, o), "q");
  REQUIRE(with_blocks.ok());
  CHECK((*with_blocks)->ngeom == geoms + 16);
  mj_deleteModel(*with_blocks);
  o.timestep_s = 0;
  CHECK(GenerateMjcf(*robot, o).error().message == "mjcf: timestep 0 s is not in (0, 0.05]");
}

TEST_CASE("quadruped-walk: sizes - 45 inputs from the devices, 12 joint targets, a 56-input critic") {
  auto e = MakeWalk(Nominal());
  CHECK(e->observation_size() == 45);
  CHECK(e->action_size() == 12);
  CHECK(e->critic_observation_size() == 56);
  CHECK(e->max_episode_steps() == 1000);
  CHECK(e->layout().Hash() != 0);
  for (const auto& o : e->layout().observations) CHECK(o.signal.find("lin_vel") == std::string::npos);
}

TEST_CASE("quadruped-walk: with zero actions the robot stands on its default pose - no fall, feet down") {
  auto e = MakeWalk(Nominal());
  Rng rng(3);
  std::vector<float> obs(e->observation_size()), act(12, 0.f), critic(e->critic_observation_size());
  e->Reset(rng, obs);
  for (int t = 0; t < 150; ++t) {
    const StepResult r = e->Step(act, obs);
    REQUIRE_FALSE(r.terminated);
    CHECK(r.reward >= 0.0);  // only positive rewards
  }
  e->CriticObservation(critic);
  const double height = critic[45 + 3];
  CHECK(height > 0.38);
  CHECK(height < 0.48);
  for (int f = 0; f < 4; ++f) CHECK(critic[45 + 4 + f] == 1.0f);  // every foot in contact
  CHECK(obs[5] == doctest::Approx(-1.0).epsilon(0.01));           // gravity straight down the base z axis
}

TEST_CASE("quadruped-walk: joint signals are what a MIT reply carries - quantised to the CAN map's ranges") {
  auto e = MakeWalk(Nominal());
  Rng rng(5);
  std::vector<float> obs(e->observation_size()), act(12, 0.3f);
  e->Reset(rng, obs);
  for (int t = 0; t < 20; ++t) (void)e->Step(act, obs);
  // Knee position (observation 9 + 2): (q - default) * 1; the reply's 16-bit code over [-8, 8] rad.
  const double q = static_cast<double>(obs[11]) + e->robot().default_q_rad[2];
  const double step = can::QuantizationStep(-8.0, 8.0, can::kMitPositionBits);
  const double code = (q + 8.0) / step;
  CHECK(std::fabs(code - std::round(code)) < 1e-3);  // on the 16-bit grid
  // The previous action is the one applied, after the layout's clamp to the joint limits.
  std::vector<float> big(12, 1e6f);
  (void)e->Step(big, obs);
  const auto& a = e->layout().actions[2];
  CHECK(obs[33 + 2] == doctest::Approx((a.high - a.offset) / a.scale));
}

TEST_CASE("quadruped-walk: same seed, same run - bit for bit, with noise, randomisation and blocks") {
  QuadrupedWalkOptions o = Nominal("mixed");
  o.noise = true;
  o.randomize = true;
  auto a = MakeWalk(o);
  auto b_env = a->Clone();
  Rng ra(11), rb(11), act_rng(2);
  std::vector<float> oa(45), ob(45), ca(56), cb(56), act(12);
  a->Reset(ra, oa);
  b_env->Reset(rb, ob);
  CHECK(oa == ob);
  for (int t = 0; t < 300; ++t) {
    for (auto& x : act) x = static_cast<float>(act_rng.Normal() * 0.5);
    const StepResult r1 = a->Step(act, oa);
    const StepResult r2 = b_env->Step(act, ob);
    REQUIRE(oa == ob);
    REQUIRE(r1.reward == r2.reward);
    a->CriticObservation(ca);
    b_env->CriticObservation(cb);
    REQUIRE(ca == cb);
    if (r1.terminated || r1.truncated) {
      a->Reset(ra, oa);
      b_env->Reset(rb, ob);
    }
  }
}

TEST_CASE("quadruped-walk: mixed terrain - half the episodes on blocks 5-15 cm high, the start kept flat") {
  auto e = MakeWalk(Nominal("mixed"));
  Rng rng(17);
  std::vector<float> obs(45), critic(56), act(12, 0.f);
  int blocks = 0;
  const int episodes = 40;
  for (int k = 0; k < episodes; ++k) {
    e->Reset(rng, obs);
    (void)e->Step(act, obs);
    blocks += e->telemetry().on_blocks;
    e->CriticObservation(critic);
    CHECK(critic[45 + 3] > 0.3);  // over the flat start area, not a block
  }
  CHECK(blocks > episodes / 4);
  CHECK(blocks < 3 * episodes / 4);
  auto flat = MakeWalk(Nominal("flat"));
  for (int k = 0; k < 5; ++k) {
    flat->Reset(rng, obs);
    CHECK_FALSE(flat->telemetry().on_blocks);
  }
}

TEST_CASE("quadruped-walk: the model has room for every contact - a flailing robot on blocks, none dropped") {
  // mjcf.cpp sizes the contact and constraint lists (MuJoCo sizes each mjData's memory from them):
  // random actions, pushes and falls on blocks never fill them.
  QuadrupedWalkOptions o = Nominal("mixed");
  o.blocks_fraction = 1.0;
  o.randomize = true;
  auto e = MakeWalk(o);
  Rng rng(5);
  std::vector<float> obs(45), act(12);
  e->Reset(rng, obs);
  int falls = 0;
  for (int k = 0; k < 3000; ++k) {
    for (float& a : act) a = static_cast<float>(rng.Uniform(-3.0, 3.0));
    const auto r = e->Step(act, obs);
    if (r.terminated || r.truncated) {
      falls += e->telemetry().fell;
      e->Reset(rng, obs);
    }
  }
  CHECK(falls > 10);
  CHECK(e->telemetry().physics_overflows == 0);
}

TEST_CASE("quadruped-walk: blocks carry the robot - large blocks under the start, it stands on them") {
  QuadrupedWalkOptions o = Nominal("mixed");
  // 300 blocks 4 m a side over 20 m x 20 m, none kept out of the start: the robot starts on one.
  o.models_dir = ModelsWith(
      "walk_dense", "walk.yaml",
      {"clear_radius_m: 0.8", "clear_radius_m: 0.0", "block_size_m: [0.3, 1.0]", "block_size_m: [4.0, 4.0]"});
  o.blocks_fraction = 1.0;
  auto e = MakeWalk(o);
  Rng rng(23);
  std::vector<float> obs(45), critic(56), act(12, 0.f);
  for (int k = 0; k < 4; ++k) {
    e->Reset(rng, obs);
    for (int t = 0; t < 100; ++t) REQUIRE_FALSE(e->Step(act, obs).terminated);
    e->CriticObservation(critic);
    const double over_ground = critic[45 + 3], world_z = e->telemetry().position[2];
    CHECK(over_ground > 0.38);
    CHECK(over_ground < 0.48);
    CHECK(world_z > over_ground + 0.049);  // on top of a block 5-15 cm high
  }
}

TEST_CASE("quadruped-walk: bad inputs are refused at start naming the value") {
  QuadrupedWalkOptions o = Nominal();
  o.terrain = "stairs";
  CHECK(ErrorOf(o) == "--terrain: 'stairs' unknown (flat, mixed)");
  o = Nominal();
  o.commands = "1:x:1";
  CHECK(ErrorOf(o) == "--commands: '1:x:1': vy 'x' is not a number in [0, 5]");
  o.commands = "1:1";
  CHECK(ErrorOf(o) == "--commands: '1:1' is not VX_MAX:VY_MAX:YAW_RATE_MAX (e.g. 1:1:1)");
  o = Nominal();
  o.models_dir = test::ScratchDir("walk_no_robot");
  CHECK(ErrorOf(o).find("quadruped/robot.yaml: cannot open") != std::string::npos);
  // A URDF whose joints are not the robot's joint order.
  o.models_dir = ModelsWith("walk_urdf", "quadruped.urdf", "<joint name=\"LF_KFE\"", "<joint name=\"LF_KNEE\"");
  CHECK(ErrorOf(o) == "quadruped.yaml: joints[2]: 'LF_KFE' is not a joint of quadruped.urdf");
  // An IO layout whose actions are not the joints in order, or not around the default pose.
  o.models_dir = ModelsWith("walk_order", "io_layout.yaml", "command: q_des_LF_HFE", "command: q_des_LF_KFE");
  CHECK(ErrorOf(o) ==
        "io_layout.yaml: actions[1] 'LF_HFE': command 'q_des_LF_KFE' is not q_des_LF_HFE (joint 1 of the description's "
        "joint order)");
  o.models_dir =
      ModelsWith("walk_offset", "io_layout.yaml", "command: q_des_LF_HFE, unit: rad, scale: 0.25, offset: 0.4",
                 "command: q_des_LF_HFE, unit: rad, scale: 0.25, offset: 0.5");
  CHECK(ErrorOf(o) ==
        "io_layout.yaml: actions[1] 'LF_HFE': offset 0.500000 is not the default pose 0.400000 of "
        "the description");
  o.models_dir = ModelsWith("walk_signal", "io_layout.yaml", "signal: base_ang_vel_x", "signal: base_lin_vel_x");
  CHECK(ErrorOf(o).find("signal 'base_lin_vel_x' is not provided") != std::string::npos);
  o.models_dir = ModelsWith("walk_yaml", "walk.yaml", "decimation: 4", "decimation: four");
  CHECK(ErrorOf(o).find("walk.yaml: simulation.decimation: 'four' is not a number") != std::string::npos);
  o.models_dir = ModelsWith("walk_range", "walk.yaml", "vx_mps: [-1.0, 1.0]", "vx_mps: [1.0, -1.0]");
  CHECK(ErrorOf(o).find("walk.yaml: commands.vx_mps: low 1 is above high -1") != std::string::npos);
}

TEST_CASE("quadruped-walk: training commands - a share follow a heading, a share stand or turn in place") {
  // Commands every 0.1 s on a standing robot. A heading command's yaw rate is clip(0.5 * wrap(
  // heading - yaw), -1, 1): saturated at exactly +-1 for (pi - 2) / pi = 36 % of headings; a drawn
  // one U(-1, 1) never is. A planar command is zero for zero_planar_share, and for the 3 % of
  // draws shorter than 0.2 m/s.
  auto count = [](double heading_share, double zero_share) {
    QuadrupedWalkOptions o = Nominal();
    o.models_dir = ModelsWith(
        "walk_shares_" + std::to_string(heading_share) + "_" + std::to_string(zero_share), "walk.yaml",
        {"resample_s: 5.0", "resample_s: 0.1", "heading_share: 1.0", "heading_share: " + std::to_string(heading_share),
         "zero_planar_share: 0.0", "zero_planar_share: " + std::to_string(zero_share)});
    auto e = MakeWalk(o);
    CHECK(e->params().heading_share == doctest::Approx(heading_share));
    CHECK(e->params().zero_planar_share == doctest::Approx(zero_share));
    Rng rng(5);
    std::vector<float> obs(45), act(12, 0.f);
    int commands = 0, saturated = 0, zero = 0;
    for (int episode = 0; episode < 2; ++episode) {
      e->Reset(rng, obs);
      std::uint32_t seen = e->telemetry().command_index;
      for (int t = 0; t < 1000; ++t) {
        const StepResult r = e->Step(act, obs);
        const WalkTelemetry& tel = e->telemetry();
        if (tel.command_index != seen) {
          seen = tel.command_index;
          ++commands;
          saturated += std::abs(tel.command[2]) == 1.0;
          zero += tel.command[0] == 0.0 && tel.command[1] == 0.0;
        }
        if (r.terminated || r.truncated) break;
      }
    }
    REQUIRE(commands > 300);
    return std::pair{static_cast<double>(saturated) / commands, static_cast<double>(zero) / commands};
  };
  const auto [sat_half, zero_fifth] = count(0.5, 0.2);
  MESSAGE("shares 0.5 / 0.2: saturated yaw rate " << sat_half << ", planar zero " << zero_fifth);
  CHECK(sat_half == doctest::Approx(0.18).epsilon(0.4));
  CHECK(zero_fifth == doctest::Approx(0.22).epsilon(0.35));
  const auto [sat_all, zero_none] = count(1.0, 0.0);
  CHECK(sat_all == doctest::Approx(0.36).epsilon(0.3));
  CHECK(zero_none < 0.08);
  const auto [sat_none, zero_all] = count(0.0, 1.0);
  CHECK(sat_none == 0.0);
  CHECK(zero_all == 1.0);
  // The paper's test whatever walk.yaml says: commands every 10 s, each following a heading.
  QuadrupedWalkOptions o = Nominal();
  o.paper_test = true;
  auto test = MakeWalk(o);
  CHECK(test->params().resample_s == 10.0);
  CHECK(test->params().heading_share == 1.0);
  CHECK(test->params().zero_planar_share == 0.0);
  o.models_dir = ModelsWith("walk_share_range", "walk.yaml", "heading_share: 1.0", "heading_share: 1.5");
  o.paper_test = false;
  CHECK(ErrorOf(o).find("walk.yaml: commands.heading_share: '1.5' is outside [0, 1]") != std::string::npos);
}

TEST_CASE("quadruped-walk: single-axis commands - vx, vy or a yaw rate alone, a third each, no heading") {
  // --command-shares 1:0:1: every command along one axis (the heading share gives way to it);
  // 1:0 keeps walk.yaml's single-axis share (0) and mixes the axes.
  auto run = [](const std::string& shares) {
    QuadrupedWalkOptions o = Nominal();
    o.models_dir = ModelsWith("walk_single_axis", "walk.yaml", "resample_s: 5.0", "resample_s: 0.1");
    o.command_shares = shares;
    auto e = MakeWalk(o);
    Rng rng(6);
    std::vector<float> obs(45), act(12, 0.f);
    std::array<int, 4> alone{};  // commands with only vx, only vy, only a yaw rate, more than one axis
    int commands = 0;
    for (int episode = 0; episode < 6; ++episode) {
      e->Reset(rng, obs);
      std::uint32_t seen = e->telemetry().command_index;
      for (int t = 0; t < 1000; ++t) {
        const StepResult r = e->Step(act, obs);
        const auto& c = e->telemetry().command;
        if (e->telemetry().command_index != seen) {
          seen = e->telemetry().command_index;
          ++commands;
          const int nonzero = (c[0] != 0) + (c[1] != 0) + (c[2] != 0);
          if (nonzero > 1)
            ++alone[3];
          else if (nonzero == 1)
            ++alone[c[0] != 0 ? 0 : c[1] != 0 ? 1 : 2];
        }
        if (r.terminated || r.truncated) break;
      }
    }
    REQUIRE(commands > 300);
    return std::pair{alone, commands};
  };
  const auto [single, n] = run("1:0:1");
  MESSAGE("single axis: vx " << single[0] << ", vy " << single[1] << ", yaw " << single[2] << ", mixed " << single[3]
                             << " of " << n);
  CHECK(single[3] == 0);
  // A third each; a planar one below 0.2 m/s (a fifth of U(-1, 1)) is sent as 0.
  CHECK(single[0] == doctest::Approx(0.8 * n / 3.0).epsilon(0.25));
  CHECK(single[1] == doctest::Approx(0.8 * n / 3.0).epsilon(0.25));
  CHECK(single[2] == doctest::Approx(n / 3.0).epsilon(0.25));
  const auto [mixed, m] = run("1:0");
  CHECK(mixed[3] > m * 0.9);
  QuadrupedWalkOptions o = Nominal();
  o.command_shares = "1:0:1.5";
  CHECK(ErrorOf(o).find("--command-shares: '1:0:1.5': single axis share '1.5' is not a number in [0, 1]") !=
        std::string::npos);
  o.command_shares = "0.5:0.2";
  auto kept = MakeWalk(o);
  CHECK(kept->params().single_axis_share == 0.0);
  CHECK(kept->provenance().find("(0.5 heading, 0.2 zero planar)") != std::string::npos);
  CHECK(kept->provenance().rfind("quadruped-walk, robot quadruped, terrain flat, commands", 0) == 0);
  o.command_shares = "0.5:0.2:0.3";
  CHECK(MakeWalk(o)->provenance().find("(0.5 heading, 0.2 zero planar, 0.3 single axis)") != std::string::npos);
}

TEST_CASE("quadruped-walk: --command-resample sets the training's command period, not the paper's test's") {
  QuadrupedWalkOptions o = Nominal();
  o.command_resample = "2.5";
  auto e = MakeWalk(o);
  CHECK(e->params().resample_s == 2.5);
  CHECK(e->provenance().find("commands every 2.5 s (") != std::string::npos);
  // A new command (command_index) every 125 policy steps, and only then.
  Rng rng(3);
  std::vector<float> obs(45), act(12, 0.f);
  e->Reset(rng, obs);
  std::uint32_t seen = e->telemetry().command_index;
  std::vector<int> changes;
  for (int t = 1; t <= 400; ++t) {
    const StepResult r = e->Step(act, obs);
    if (e->telemetry().command_index != seen) changes.push_back(t);
    seen = e->telemetry().command_index;
    if (r.terminated || r.truncated) break;
  }
  REQUIRE(changes.size() >= 2);
  CHECK(changes[0] == 125);
  CHECK(changes[1] == 250);
  o.paper_test = true;
  CHECK(MakeWalk(o)->params().resample_s == 10.0);
  o.paper_test = false;
  for (const char* bad : {"0.01", "4000", "x", "2.5s", "nan"}) {
    o.command_resample = bad;
    CHECK(ErrorOf(o).find(std::string("--command-resample: '") + bad + "' is not a period in [0.02, 3600] s") !=
          std::string::npos);
  }
}

TEST_CASE("quadruped-walk: --reward-scales replaces walk.yaml's scales for a run - the reward follows them") {
  QuadrupedWalkOptions o = Nominal();
  auto base = MakeWalk(o);
  o.reward_scales = "tracking_ang_vel=1.0,termination=-50";
  auto changed = MakeWalk(o);
  CHECK(changed->params().scales.tracking_ang_vel == 1.0);
  CHECK(changed->params().scales.termination == -50.0);
  CHECK(changed->params().scales.tracking_lin_vel == base->params().scales.tracking_lin_vel);
  CHECK(base->params().scales.termination == 0.0);
  CHECK(changed->provenance().find("; rewards tracking_ang_vel=1.0,termination=-50; noise") != std::string::npos);
  // The same robot, commands and actions: the yaw-rate tracking pays twice as much, so every
  // step's reward is higher until the fall, which then costs 50 x 0.02.
  Rng ra(9), rb(9), noise(4);
  std::vector<float> oa(45), ob(45), act(12);
  base->Reset(ra, oa);
  changed->Reset(rb, ob);
  bool fell = false;
  for (int t = 0; t < 1000 && !fell; ++t) {
    for (float& a : act) a = static_cast<float>(noise.Uniform(-4.0, 4.0));
    const StepResult a = base->Step(act, oa), b = changed->Step(act, ob);
    REQUIRE(a.terminated == b.terminated);
    fell = a.terminated;
    if (fell) {
      CHECK(b.reward == doctest::Approx(a.reward - 50 * 0.02));
    } else if (a.reward > 0) {
      CHECK(b.reward > a.reward);
    }
  }
  CHECK(fell);
  o.reward_scales = "tracking_ang_vel=1.0,feet_air=2";
  CHECK(ErrorOf(o).find("--reward-scales: 'feet_air' is not a reward term (tracking_lin_vel, ") != std::string::npos);
  o.reward_scales = "torques=1e9";
  CHECK(ErrorOf(o).find("--reward-scales: torques: '1e9' is not a number") != std::string::npos);
  // tracking_sigma, the tracking terms' width, is set the same way and kept to walk.yaml's range.
  o.reward_scales = "tracking_sigma=0.15";
  CHECK(MakeWalk(o)->params().tracking_sigma == 0.15);
  CHECK(base->params().tracking_sigma == 0.25);
  o.reward_scales = "tracking_sigma=-1";
  CHECK(ErrorOf(o).find("--reward-scales: tracking_sigma: '-1' is not in [1e-06, 100]") != std::string::npos);
}

TEST_CASE("quadruped-walk: base_height costs the base's distance from its target - optional, refused without one") {
  // Both with every step's reward unclipped, one with the term: on the same robot and actions
  // the difference is the term, from the base height the critic sees (its 49th input).
  const std::string plain = ModelsWith("walk_bh_plain", "walk.yaml", "only_positive: true", "only_positive: false");
  const std::string with = ModelsWith("walk_bh", "walk.yaml",
                                      {"only_positive: true", "only_positive: false\n  base_height_target_m: 0.45",
                                       "dof_pos_limits: -10.0", "dof_pos_limits: -10.0\n    base_height: -30.0"});
  QuadrupedWalkOptions o = Nominal();
  o.models_dir = plain;
  auto base = MakeWalk(o);
  o.models_dir = with;
  auto changed = MakeWalk(o);
  CHECK(base->params().scales.base_height == 0.0);
  CHECK(changed->params().scales.base_height == -30.0);
  CHECK(changed->params().base_height_target_m == 0.45);
  Rng ra(3), rb(3), noise(5);
  std::vector<float> oa(45), ob(45), act(12), critic(static_cast<std::size_t>(changed->critic_observation_size()));
  base->Reset(ra, oa);
  changed->Reset(rb, ob);
  double largest = 0;
  for (int t = 0; t < 200; ++t) {
    for (float& a : act) a = static_cast<float>(noise.Uniform(-0.5, 0.5));
    const StepResult a = base->Step(act, oa), b = changed->Step(act, ob);
    REQUIRE(a.terminated == b.terminated);
    if (a.terminated) break;
    changed->CriticObservation(critic);
    const double h = critic[48] - 0.45, cost = -30.0 * h * h * 0.02;
    CHECK(b.reward - a.reward == doctest::Approx(cost).epsilon(1e-5));
    largest = std::min(largest, cost);
  }
  CHECK(largest < -1e-4);  // the robot was off its target, so the term cost something
  // A scale without a target is refused, in walk.yaml and from --reward-scales.
  o.models_dir = ModelsWith("walk_bh_no_target", "walk.yaml", "dof_pos_limits: -10.0",
                            "dof_pos_limits: -10.0\n    base_height: -30.0");
  CHECK(ErrorOf(o).find(
            "walk.yaml: rewards: missing field 'base_height_target_m': rewards.scales.base_height is not 0") !=
        std::string::npos);
  o = Nominal();
  o.reward_scales = "base_height=-30";
  CHECK(
      ErrorOf(o).find("--reward-scales: base_height=-30: the task sets no rewards.base_height_target_m (walk.yaml)") !=
      std::string::npos);
  o.reward_scales = "base_height=0";
  CHECK(MakeWalk(o)->params().scales.base_height == 0.0);
  // The Go2's task uses it.
  o = Nominal();
  o.robot = "go2";
  auto go2 = MakeWalk(o);
  CHECK(go2->params().scales.base_height < 0);
  CHECK(go2->params().base_height_target_m == doctest::Approx(0.28));
}
