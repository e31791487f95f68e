// Training observes what the controller observes, bit for bit: the same sensor stream fed to a
// training environment and to the controller's tick (runtime/loop Tick with a PolicySource over a
// scripted transport) gives the same float inputs (memcmp), episode after episode, from the first
// observation (the history filled) through every step (histories, the last actions).
//   quadruped-walk  its devices on the robot's CAN buses (in process): each motor's MIT reply and the
//                   base IMU's frames made from the MuJoCo state, as the HIL's emulated devices
//                   send them, read by the controller's CAN transport every tick at 1 kHz, and
//                   the operator's command; the policy runs every 20 ticks. The fields the
//                   transport decodes are the environment's, bit for bit, too.
//   auv-nav         the task's sensor sample (what the HIL publishes) by the AUV transport's map;
//                   the policy runs on each new sample
// The controller's action drives the environment (in policy units, as the controller's last
// action is computed), so that both see the same last actions.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "policies/envs/auv_nav.hpp"
#include "policies/envs/quadruped_walk.hpp"
#include "runtime/loop/loop.hpp"
#include "runtime/loop/policy_source.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/robot/io_layout.hpp"
#include "runtime/robot/robot_data.hpp"
#include "runtime/transport/can/can_transport.hpp"
#include "runtime/transport/can/imu_codec.hpp"
#include "runtime/transport/can/memory_bus.hpp"
#include "runtime/transport/can/mit_codec.hpp"
#include "runtime/transport/dds/cdr.hpp"
#include "runtime/transport/dds/dds_link.hpp"
#include "tests/support/scripted_transport.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo;

namespace {

// The controller for one episode: a fresh loop (arming starts the run phase and the source's
// first observation), its robot data, a scripted transport the test feeds, and optionally a CAN
// transport before it.
struct Controller {
  const robot::RobotModel& m;
  std::unique_ptr<loop::PolicySource> source;
  robot::RobotData data;
  test::ScriptedTransport transport;
  std::unique_ptr<loop::LoopData> loop;
  std::vector<robot::Transport*> transports;
  std::uint64_t tick = 0;

  Controller(const robot::RobotModel& model, const policy::PolicyModel& policy, robot::Transport* can = nullptr)
      : m(model), data(robot::MakeRobotData(model)), transport(model) {
    auto s = loop::PolicySource::Create(model, policy);
    REQUIRE_MESSAGE(s.ok(), s.error().message);
    source = std::move(s).value();
    loop = loop::MakeLoopData(model, source.get());
    if (can != nullptr) transports.push_back(can);
    transports.push_back(&transport);
    loop->Arm();
  }
  // Stream `s` as a new sample with these fields (all of the robot's).
  void Put(std::uint32_t s, std::span<const double> fields) {
    transport.Put(m, s, fields.subspan(m.streams[s].first_field, m.streams[s].field_count));
  }
  void Tick() {
    rt::TickTiming timing;
    timing.tick = tick++;
    (void)loop::Tick(m, data, *loop, transports, timing);
  }
};

// The quadruped's devices on its CAN buses, in process: from the environment's MuJoCo state, each
// motor's MIT reply (position, velocity, the torque applied) and the base IMU's sample (orientation,
// base-frame angular velocity, specific force), sent as the HIL's emulated devices send them.
class Devices {
 public:
  Devices(const robot::RobotModel& m, const envs::QuadrupedWalk& env)
      : m_(m), map_(*m.can), network_(BusNames(*m.can)) {
    for (std::size_t b = 0; b < map_.buses.size(); ++b) {
      auto end = network_.Attach(b, {}, map_.buses[b].fd, false);  // sends; takes no frame
      REQUIRE_MESSAGE(end.ok(), end.error().message);
      ends_.push_back(std::move(end).value());
    }
    const mjModel* mj = env.mujoco_model();
    for (const robot::CanMotor& mo : map_.motors) {
      const int joint = mj_name2id(mj, mjOBJ_JOINT, mo.joint.c_str());
      const int actuator = mj_name2id(mj, mjOBJ_ACTUATOR, mo.joint.c_str());
      REQUIRE(joint >= 0);
      REQUIRE(actuator >= 0);
      qpos_.push_back(mj->jnt_qposadr[joint]);
      dof_.push_back(mj->jnt_dofadr[joint]);
      ctrl_.push_back(actuator);
    }
    can::CanTransportOptions o;
    o.network = &network_;
    auto t = can::CanTransport::Open(m, "can", o);
    REQUIRE_MESSAGE(t.ok(), t.error().message);
    transport_ = std::move(t).value();
  }
  robot::Transport* transport() { return transport_.get(); }

  void Send(const envs::QuadrupedWalk& env) {
    const mjModel* mj = env.mujoco_model();
    const mjData* d = env.mujoco_data();
    for (std::size_t k = 0; k < map_.motors.size(); ++k) {
      const robot::CanMotor& mo = map_.motors[k];
      const can::MitReply r{static_cast<std::uint8_t>(mo.id), d->qpos[qpos_[k]], d->qvel[dof_[k]], d->ctrl[ctrl_[k]]};
      const can::CanFrame f = can::MakeMitReplyFrame(mo.reply_id, map_.range_of(mo), r);
      REQUIRE(ends_[mo.bus]->Send({&f, 1}) == 1);
    }
    can::ImuSample s;
    mjtNum rot[9], a[3], f[3];
    mju_quat2Mat(rot, d->qpos + 3);
    for (int k = 0; k < 3; ++k) a[k] = d->qacc[k] - mj->opt.gravity[k];
    mju_mulMatTVec(f, rot, a, 3, 3);
    for (int k = 0; k < 4; ++k) s.quat_wxyz[k] = d->qpos[3 + k];
    for (int k = 0; k < 3; ++k) {
      s.gyro_rad_s[k] = d->qvel[3 + k];
      s.accel_m_s2[k] = f[k];
    }
    s.seq = seq_++;
    s.status = can::kImuOrientationValid;
    const robot::CanImu& imu = map_.imus[0];
    REQUIRE(imu.format == robot::ImuFormat::kClassic);
    can::CanFrame frames[3];
    can::MakeImuClassicFrames(imu.id, s, frames);
    REQUIRE(ends_[imu.bus]->Send(frames) == 3);
  }

 private:
  static std::vector<std::string> BusNames(const robot::CanMap& map) {
    std::vector<std::string> names;
    for (const auto& b : map.buses) names.push_back(b.name);
    return names;
  }
  const robot::RobotModel& m_;
  const robot::CanMap& map_;
  can::MemoryCanNetwork network_;
  std::vector<std::unique_ptr<can::MemoryCanBus>> ends_;
  std::vector<int> qpos_, dof_, ctrl_;
  std::unique_ptr<can::CanTransport> transport_;
  std::uint8_t seq_ = 0;
};

// The controller's action for its current observation (the same Forward it ran), in policy units
// as the controller computes its last action: (command - offset) / scale.
std::vector<float> ControllerAction(const policy::PolicyModel& policy, policy::PolicyData& pd,
                                    std::span<const float> observation, const robot::IoLayout& layout) {
  std::copy(observation.begin(), observation.end(), pd.observation().begin());
  REQUIRE(policy::Forward(policy, pd) == policy::ForwardStatus::kOk);
  std::vector<float> a(layout.actions.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    a[i] =
        static_cast<float>((static_cast<double>(pd.action()[i]) - layout.actions[i].offset) / layout.actions[i].scale);
  return a;
}

bool SameBits(std::span<const float> a, std::span<const float> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

std::string FirstDifference(const robot::IoLayout& layout, std::span<const float> env, std::span<const float> ctrl) {
  const auto names = layout.ObservationNames();
  for (std::size_t i = 0; i < env.size() && i < ctrl.size(); ++i)
    if (std::memcmp(&env[i], &ctrl[i], sizeof(float)) != 0)
      return names[i] + ": environment " + std::to_string(env[i]) + ", controller " + std::to_string(ctrl[i]);
  return "sizes " + std::to_string(env.size()) + " and " + std::to_string(ctrl.size());
}

// Whether the controller's sample check refused a stream of this tick (it then observes nothing).
bool Refused(const robot::RobotModel& m, const robot::RobotData& d) {
  for (std::size_t s = 0; s < m.streams.size(); ++s)
    if (d.streams[s].invalid_input >= 0) {
      MESSAGE("the controller refused " << m.fields[static_cast<std::size_t>(d.streams[s].invalid_input)].name << " = "
                                        << d.fields[static_cast<std::size_t>(d.streams[s].invalid_input)]);
      return true;
    }
  return false;
}

// quadruped-walk over `episodes` episodes of up to `steps` policy steps, the controller beside it.
// Returns the observations compared.
int CompareWalk(std::shared_ptr<const robot::RobotModel> model, const policy::PolicyModel& policy,
                const std::string& terrain, int episodes, int steps) {
  envs::QuadrupedWalkOptions o;
  o.models_dir = test::SourcePath("models");
  o.robot_model = model;
  o.terrain = terrain;
  o.noise = false;  // training noise: added to the signals, off here
  o.randomize = true;
  auto made = envs::QuadrupedWalk::Make(o);
  REQUIRE_MESSAGE(made.ok(), made.error().message);
  envs::QuadrupedWalk& env = **made;
  const robot::RobotModel& m = env.robot_model();
  REQUIRE(&m == model.get());  // the controller's robot model, not a copy
  const std::uint32_t period = m.policy_period_ticks;
  auto pd = policy::MakePolicyData(policy);
  REQUIRE(pd.ok());
  Rng rng(11);
  std::vector<float> obs(env.observation_size());
  int compared = 0, refused = 0;
  // The gravity direction from the IMU's quantised orientation against MuJoCo's exact one (the
  // environment's observation before it took the IMU's path): the largest difference.
  const auto names = env.layout().ObservationNames();
  std::size_t gravity[3];
  for (std::size_t k = 0; k < 3; ++k) {
    const std::string name = std::string("projected_gravity_") + "xyz"[k];
    gravity[k] = static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
    REQUIRE(gravity[k] < names.size());
  }
  double gravity_error = 0;
  auto exact_gravity = [&] {
    const mjtNum* q = env.mujoco_data()->qpos + 3;
    const double g[3] = {-2 * (q[1] * q[3] - q[0] * q[2]), -2 * (q[2] * q[3] + q[0] * q[1]),
                         -(1 - 2 * (q[1] * q[1] + q[2] * q[2]))};
    for (std::size_t k = 0; k < 3; ++k)
      gravity_error = std::max(gravity_error, std::fabs(static_cast<double>(obs[gravity[k]]) - g[k]));
  };
  const std::uint32_t command = static_cast<std::uint32_t>(m.StreamIndex("velocity_command"));
  // One tick: the devices' frames and the operator's command, then the controller's tick; the
  // fields the CAN transport decoded are the ones the environment wrote.
  auto tick = [&](Devices& devices, Controller& c) {
    devices.Send(env);
    c.Put(command, env.fields());
    c.Tick();
    for (std::size_t f = 0; f < m.fields.size(); ++f)
      if (std::memcmp(&c.data.fields[f], &env.fields()[f], sizeof(double)) != 0)
        FAIL(m.fields[f].name << ": environment " << env.fields()[f] << ", controller " << c.data.fields[f]);
  };
  for (int ep = 0; ep < episodes; ++ep) {
    CAPTURE(ep);
    env.Reset(rng, obs);
    Devices devices(m, env);
    Controller c(m, policy, devices.transport());
    // Arming, stand-up and hold on the reset state's replies, then the first run.
    for (int k = 0; k < 5000 && c.source->runs() == 0; ++k) tick(devices, c);
    REQUIRE(c.loop->phase() == loop::Phase::kRun);
    REQUIRE(c.source->runs() == 1);
    REQUIRE_MESSAGE(SameBits(obs, c.source->observation()),
                    FirstDifference(env.layout(), obs, c.source->observation()));
    exact_gravity();
    ++compared;
    for (int step = 1; step <= steps; ++step) {
      CAPTURE(step);
      const std::vector<float> a = ControllerAction(policy, *pd, c.source->observation(), env.layout());
      const envs::StepResult r = env.Step(a, obs);
      // The devices report the new state every tick until the next run.
      const std::uint64_t runs = c.source->runs();
      for (std::uint32_t k = 0; k < period && c.source->runs() == runs; ++k) tick(devices, c);
      REQUIRE(c.source->runs() == runs + 1);
      // A reply the sample check refuses (a knee beyond its speed limit as a foot strikes a block
      // edge) gives the controller no new observation: the episode ends there for the comparison.
      if (Refused(m, c.data)) {
        ++refused;
        break;
      }
      REQUIRE_MESSAGE(SameBits(obs, c.source->observation()),
                      FirstDifference(env.layout(), obs, c.source->observation()));
      exact_gravity();
      ++compared;
      if (r.terminated || r.truncated) break;
    }
  }
  CHECK(refused <= 1);
  CHECK(gravity_error < 1e-4);
  MESSAGE(compared << " observations compared; gravity from the IMU's orientation within " << gravity_error
                   << " of MuJoCo's exact one");
  return compared;
}

std::shared_ptr<const robot::RobotModel> Quadruped() {
  auto m = robot::LoadRobotModel(test::SourcePath("models/quadruped/robot.yaml"));
  REQUIRE_MESSAGE(m.ok(), m.error().message);
  return std::make_shared<const robot::RobotModel>(std::move(m).value());
}

}  // namespace

TEST_CASE("observation path: quadruped-walk and the controller, the shipped policy on blocks - bit for bit") {
  const auto model = Quadruped();
  auto policy = policy::PolicyModel::FromFile(test::SourcePath("policies/frozen/quadruped_walk/flat.blob"));
  REQUIRE_MESSAGE(policy.ok(), policy.error().message);
  CHECK(CompareWalk(model, *policy, "mixed", 3, 300) > 600);
}

TEST_CASE("observation path: quadruped-walk and the controller, histories of 3 - bit for bit") {
  // The shipped layout with a history of 3 on the IMU's signals, the command and the last actions:
  // the history slots must shift alike, and start filled.
  auto loaded = robot::LoadRobotModel(test::SourcePath("models/quadruped/robot.yaml"));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error().message);
  robot::RobotModel edited = std::move(loaded).value();
  int with_history = 0;
  for (robot::ObservationElement& e : edited.io->observations)
    if (e.signal.rfind("base_ang_vel_", 0) == 0 || e.signal.rfind("projected_gravity_", 0) == 0 ||
        e.signal.rfind("command_", 0) == 0 || e.signal.rfind("last_action_", 0) == 0) {
      e.history = 3;
      ++with_history;
    }
  REQUIRE(with_history == 21);
  const auto model = std::make_shared<const robot::RobotModel>(std::move(edited));
  // A small random policy for that layout, its actions scaled down to keep the robot up.
  policy::PolicySpec spec = policy::MakeRandomSpec({model->io->observation_size(), 16, model->io->action_size()},
                                                   policy::Activation::kTanh, 5);
  robot::ApplyLayoutToSpec(*model->io, spec);
  auto policy = policy::PolicyModel::FromSpec(spec);
  REQUIRE_MESSAGE(policy.ok(), policy.error().message);
  CHECK(CompareWalk(model, *policy, "flat", 2, 150) > 200);
}

TEST_CASE("observation path: auv-nav and the controller, the shipped policy on mixed layouts - bit for bit") {
  auto loaded = robot::LoadRobotModel(test::SourcePath("models/auv/robot.yaml"));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error().message);
  const auto model = std::make_shared<const robot::RobotModel>(std::move(loaded).value());
  envs::AuvNavOptions o;
  o.robot_model = model;
  o.layout = "mixed";
  auto made = envs::AuvNav::Make(o);
  REQUIRE_MESSAGE(made.ok(), made.error().message);
  envs::AuvNav& env = **made;
  REQUIRE(env.robot_model() == model.get());
  const robot::RobotModel& m = *model;
  auto policy = policy::PolicyModel::FromFile(test::SourcePath("policies/frozen/auv_nav/auv_nav.blob"));
  REQUIRE_MESSAGE(policy.ok(), policy.error().message);
  auto pd = policy::MakePolicyData(*policy);
  REQUIRE(pd.ok());
  // The sensor sample on the wire: the robot file's message (its IDL, its mapping onto the stream).
  const robot::DdsMessageSpec& msg = m.transports[0].dds.messages[0];
  REQUIRE(msg.direction == robot::MessageDirection::kIn);
  const robot::StreamSpec& stream = m.streams[msg.stream];
  dds::DdsSample wire(msg.type);
  std::vector<double> fields(m.fields.size(), 0.0), received(m.fields.size(), 0.0);
  Rng rng(3);
  std::vector<float> obs(env.observation_size());
  int compared = 0, ends = 0;
  for (int ep = 0; ep < 4; ++ep) {
    CAPTURE(ep);
    env.Reset(rng, obs);
    Controller c(m, *policy);
    // Each of the task's samples, as the vehicle publishes it (encoded as the robot file maps its
    // fields onto the message, decoded as the controller's transport does), is one new sample of
    // the sensor stream.
    auto deliver = [&] {
      env.task().FillSensorFields(fields);
      for (const robot::FieldLeaf& fl : msg.fields) wire.Set(fl.leaf, fields[fl.field]);
      for (const robot::FieldLeaf& fl : msg.fields) received[fl.field] = wire.Get(fl.leaf);
      c.transport.Put(m, msg.stream, std::span<const double>(received).subspan(stream.first_field, stream.field_count));
      const std::uint64_t runs = c.source->runs();
      c.Tick();
      REQUIRE(c.source->runs() == runs + 1);
    };
    deliver();
    REQUIRE(c.loop->phase() == loop::Phase::kRun);
    REQUIRE_MESSAGE(SameBits(obs, c.source->observation()),
                    FirstDifference(env.layout(), obs, c.source->observation()));
    ++compared;
    for (std::uint32_t step = 1; step <= env.max_episode_steps(); ++step) {
      CAPTURE(step);
      const std::vector<float> a = ControllerAction(*policy, *pd, c.source->observation(), env.layout());
      const envs::StepResult r = env.Step(a, obs);
      deliver();
      REQUIRE_MESSAGE(SameBits(obs, c.source->observation()),
                      FirstDifference(env.layout(), obs, c.source->observation()));
      ++compared;
      if (r.terminated || r.truncated) {
        ++ends;  // the last observation carries episode_end
        break;
      }
    }
  }
  CHECK(compared > 600);
  CHECK(ends == 4);  // every episode's last observation (episode_end) compared too
}
