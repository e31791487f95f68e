#include "sim_hil/plants/quadruped_plant.hpp"

#include <Simbody.h>

#include <cmath>
#include <string>
#include <vector>

namespace pbppo::sim {
namespace {

SimTK::Rotation FromRpy(const robot::Vec3d& rpy) {
  return SimTK::Rotation(SimTK::BodyOrSpaceType::SpaceRotationSequence, rpy[0], SimTK::XAxis, rpy[1], SimTK::YAxis,
                         rpy[2], SimTK::ZAxis);
}

SimTK::Transform FromPose(const robot::UrdfPose& p) {
  return SimTK::Transform(FromRpy(p.rpy), SimTK::Vec3(p.xyz[0], p.xyz[1], p.xyz[2]));
}

// Mass properties of a URDF link about its body frame origin, expressed in the body frame.
SimTK::MassProperties LinkMass(const robot::UrdfLink& l) {
  if (!l.has_inertial) return SimTK::MassProperties(0, SimTK::Vec3(0), SimTK::Inertia(0));
  const robot::UrdfInertial& in = l.inertial;
  const SimTK::Rotation R = FromRpy(in.origin.rpy);
  const SimTK::Vec3 com(in.origin.xyz[0], in.origin.xyz[1], in.origin.xyz[2]);
  // Inertia about the COM in the inertial frame, re-expressed in the body frame, then shifted to the origin.
  const SimTK::Inertia Ic(SimTK::Vec3(in.ixx, in.iyy, in.izz), SimTK::Vec3(in.ixy, in.ixz, in.iyz));
  const SimTK::Inertia Ic_B = Ic.reexpress(~R);
  const SimTK::Inertia Io = Ic_B.shiftFromMassCenter(-com, in.mass_kg);
  return SimTK::MassProperties(in.mass_kg, com, Io);
}

// Joint torques held outside the State: the plant invalidates the cache whenever they change.
class TorqueInput : public SimTK::Force::Custom::Implementation {
 public:
  TorqueInput(std::vector<SimTK::MobilizedBody> joints, const std::vector<double>* tau)
      : joints_(std::move(joints)), tau_(tau) {}
  void calcForce(const SimTK::State& s, SimTK::Vector_<SimTK::SpatialVec>&, SimTK::Vector_<SimTK::Vec3>&,
                 SimTK::Vector& mobility) const override {
    for (std::size_t i = 0; i < joints_.size(); ++i) joints_[i].applyOneMobilityForce(s, 0, (*tau_)[i], mobility);
  }
  SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0; }

 private:
  std::vector<SimTK::MobilizedBody> joints_;
  const std::vector<double>* tau_;
};

}  // namespace

struct QuadrupedStandPlant::Impl {
  QuadrupedPlantOptions options;
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter{system};
  SimTK::GeneralForceSubsystem forces{system};
  std::vector<SimTK::MobilizedBody> joint_body;  // per actuated joint: the pin's outboard body
  std::vector<double> tau;
  std::vector<double> q, dq;  // cached after each tick
  std::unique_ptr<SimTK::RungeKutta2Integrator> integ;
  std::uint64_t tick = 0;
  double gravity = 9.81;

  void Capture() {
    const SimTK::State& s = integ->getState();
    for (std::size_t i = 0; i < joint_body.size(); ++i) {
      q[i] = joint_body[i].getOneQ(s, SimTK::QIndex(0));
      dq[i] = joint_body[i].getOneU(s, SimTK::UIndex(0));
    }
  }
};

QuadrupedStandPlant::QuadrupedStandPlant() : impl_(std::make_unique<Impl>()) {}
QuadrupedStandPlant::~QuadrupedStandPlant() = default;

Result<std::unique_ptr<QuadrupedStandPlant>> QuadrupedStandPlant::Make(const robot::RobotDescription& robot,
                                                                       const QuadrupedPlantOptions& options) {
  if (!(options.tick_s > 0) || options.substeps < 1)
    return MakeError(ErrorCode::kInvalidValue, "quadruped plant: tick_s " + std::to_string(options.tick_s) +
                                                   " and substeps " + std::to_string(options.substeps) +
                                                   " must be positive");
  std::unique_ptr<QuadrupedStandPlant> plant(new QuadrupedStandPlant());
  Impl& m = *plant->impl_;
  m.options = options;
  m.gravity = options.gravity_m_s2;
  const robot::UrdfModel& urdf = robot.urdf;
  SimTK::Force::Gravity(m.forces, m.matter, -SimTK::ZAxis, options.gravity_m_s2);

  // The base welded to the world at the stand height; then every joint in topological order.
  std::vector<SimTK::MobilizedBody> link_body(urdf.links.size());
  link_body[urdf.root] =
      SimTK::MobilizedBody::Weld(m.matter.Ground(), SimTK::Transform(SimTK::Vec3(0, 0, robot.stand_base_height_m)),
                                 SimTK::Body::Rigid(LinkMass(urdf.links[urdf.root])), SimTK::Transform());
  std::vector<int> body_of_joint(urdf.joints.size(), -1);
  for (std::size_t j = 0; j < urdf.joints.size(); ++j) {
    const robot::UrdfJoint& joint = urdf.joints[j];
    const SimTK::Body::Rigid body(LinkMass(urdf.links[joint.child]));
    const SimTK::Transform X_PJ = FromPose(joint.origin);
    if (joint.type == robot::UrdfJointType::kFixed) {
      link_body[joint.child] = SimTK::MobilizedBody::Weld(link_body[joint.parent], X_PJ, body, SimTK::Transform());
      continue;
    }
    // A Simbody pin turns about the z axis of its frames: align z with the URDF axis.
    const SimTK::Rotation R_JA(SimTK::UnitVec3(SimTK::Vec3(joint.axis[0], joint.axis[1], joint.axis[2])), SimTK::ZAxis);
    SimTK::MobilizedBody::Pin pin(link_body[joint.parent], X_PJ * SimTK::Transform(R_JA), body, SimTK::Transform(R_JA));
    if (joint.damping_nm_s_rad > 0)
      SimTK::Force::MobilityLinearDamper(m.forces, pin, SimTK::MobilizerUIndex(0), joint.damping_nm_s_rad);
    link_body[joint.child] = pin;
  }
  for (std::size_t i = 0; i < robot.joint_count(); ++i) m.joint_body.push_back(link_body[robot.joint_at(i).child]);
  const std::size_t n = m.joint_body.size();
  m.tau.assign(n, 0.0);
  m.q.assign(n, 0.0);
  m.dq.assign(n, 0.0);
  SimTK::Force::Custom(m.forces, new TorqueInput(m.joint_body, &m.tau));
  m.system.realizeTopology();
  std::vector<double> zero(n, 0.0);
  if (auto s = plant->Reset(zero, zero); !s) return s.error();
  return plant;
}

std::size_t QuadrupedStandPlant::joint_count() const noexcept {
  return impl_->joint_body.size();
}

Status QuadrupedStandPlant::Reset(const std::vector<double>& q_rad, const std::vector<double>& dq_rad_s) {
  Impl& m = *impl_;
  const std::size_t n = m.joint_body.size();
  if (q_rad.size() != n || dq_rad_s.size() != n)
    return MakeError(ErrorCode::kMismatch, "quadruped plant: Reset with " + std::to_string(q_rad.size()) +
                                               " positions and " + std::to_string(dq_rad_s.size()) +
                                               " velocities for " + std::to_string(n) + " joints");
  SimTK::State state = m.system.getDefaultState();
  for (std::size_t i = 0; i < n; ++i) {
    m.joint_body[i].setOneQ(state, SimTK::QIndex(0), q_rad[i]);
    m.joint_body[i].setOneU(state, SimTK::UIndex(0), dq_rad_s[i]);
  }
  m.integ = std::make_unique<SimTK::RungeKutta2Integrator>(m.system);
  m.integ->setFixedStepSize(m.options.tick_s / m.options.substeps);
  m.integ->setAllowInterpolation(false);
  m.integ->initialize(state);
  m.tick = 0;
  m.Capture();
  return {};
}

void QuadrupedStandPlant::SetJointTorques(const double* tau_nm, std::size_t count) noexcept {
  Impl& m = *impl_;
  const std::size_t n = std::min(count, m.tau.size());
  for (std::size_t i = 0; i < n; ++i) m.tau[i] = std::isfinite(tau_nm[i]) ? tau_nm[i] : 0.0;
  m.integ->updAdvancedState().invalidateAllCacheAtOrAbove(SimTK::Stage::Dynamics);
}

bool QuadrupedStandPlant::Step() noexcept {
  Impl& m = *impl_;
  const double target = static_cast<double>(m.tick + 1) * m.options.tick_s;
  try {
    // The first stepTo() after initialize() may return without advancing: loop to the target.
    for (int guard = 0; guard < 4 * m.options.substeps + 4 && m.integ->getTime() < target - 1e-12; ++guard)
      m.integ->stepTo(target);
  } catch (const std::exception&) {
    return false;
  }
  m.Capture();
  for (std::size_t i = 0; i < m.q.size(); ++i)
    if (!std::isfinite(m.q[i]) || !std::isfinite(m.dq[i])) return false;
  ++m.tick;
  return true;
}

std::uint64_t QuadrupedStandPlant::tick() const noexcept {
  return impl_->tick;
}
double QuadrupedStandPlant::time_s() const noexcept {
  return impl_->integ->getTime();
}
double QuadrupedStandPlant::q_rad(std::size_t j) const noexcept {
  return impl_->q[j];
}
double QuadrupedStandPlant::dq_rad_s(std::size_t j) const noexcept {
  return impl_->dq[j];
}
double QuadrupedStandPlant::tau_nm(std::size_t j) const noexcept {
  return impl_->tau[j];
}

void QuadrupedStandPlant::BaseImu(double quat_wxyz[4], double gyro_rad_s[3], double accel_m_s2[3]) const noexcept {
  quat_wxyz[0] = 1;
  quat_wxyz[1] = quat_wxyz[2] = quat_wxyz[3] = 0;
  gyro_rad_s[0] = gyro_rad_s[1] = gyro_rad_s[2] = 0;
  accel_m_s2[0] = accel_m_s2[1] = 0;
  accel_m_s2[2] = impl_->gravity;  // at rest on the stand the accelerometer reads +g upwards
}

}  // namespace pbppo::sim
