#include "sim_hil/plants/quadruped_plant.hpp"

#include <Simbody.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace pbppo::sim {
namespace {

// Joint stops: 2000 Nm/rad (a 12 kg robot folded onto a stop sinks ~0.01 rad into it), with
// Hunt-Crossley dissipation 1 s/rad (a leg that falls onto its stop does not bounce).
constexpr double kStopStiffnessNmRad = 2000.0;
constexpr double kStopDissipationSRad = 1.0;

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

// One point of a collision shape that can touch the terrain: a sphere of `radius` around
// `station` (in the body's frame); a box corner is a sphere of radius 0.
struct ContactPoint {
  SimTK::MobilizedBody body;
  SimTK::Vec3 station;
  double radius = 0;
  int foot = -1;  // foot index (URDF sphere order), -1: another shape
};

// The terrain's contact forces. Which points touched is kept for the plant to read after the
// tick (OR-ed over the tick's force evaluations).
class TerrainContact : public SimTK::Force::Custom::Implementation {
 public:
  TerrainContact(std::vector<ContactPoint> points, const ContactParams& params, const std::vector<TerrainBlock>* blocks)
      : points_(std::move(points)), p_(params), blocks_(blocks) {}

  void calcForce(const SimTK::State& s, SimTK::Vector_<SimTK::SpatialVec>& body_forces, SimTK::Vector_<SimTK::Vec3>&,
                 SimTK::Vector&) const override {
    for (const ContactPoint& c : points_) {
      const SimTK::Vec3 x = c.body.findStationLocationInGround(s, c.station);
      if (x[2] - c.radius > max_height_) continue;  // above every surface
      const SimTK::Vec3 v = c.body.findStationVelocityInGround(s, c.station);
      SimTK::Vec3 f(0);
      // The floor.
      AddContact(SimTK::Vec3(0, 0, 1), c.radius - x[2], v, f);
      // The blocks: the closest point of each box to the sphere's centre.
      for (const TerrainBlock& b : *blocks_) {
        const SimTK::Vec3 q(std::clamp(x[0], b.x0, b.x1), std::clamp(x[1], b.y0, b.y1),
                            std::clamp(x[2], 0.0, b.height));
        const SimTK::Vec3 d = x - q;
        const double dist = d.norm();
        if (dist > c.radius) continue;
        if (dist > 1e-9) {
          AddContact(d / dist, c.radius - dist, v, f);
        } else {  // the centre is inside the block: out through the top
          AddContact(SimTK::Vec3(0, 0, 1), c.radius + b.height - x[2], v, f);
        }
      }
      if (f.normSqr() > 0) {
        c.body.applyForceToBodyPoint(s, c.station, f, body_forces);
        if (c.foot >= 0)
          feet_ |= 1u << c.foot;
        else
          body_ = true;
      }
    }
  }
  SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0; }

  void ClearContacts() const noexcept {
    feet_ = 0;
    body_ = false;
  }
  std::uint32_t feet() const noexcept { return feet_; }
  bool body() const noexcept { return body_; }
  void SetMaxHeight(double h) noexcept { max_height_ = h; }

 private:
  // Normal n (unit, out of the surface), penetration depth, the point's velocity.
  void AddContact(const SimTK::Vec3& n, double depth, const SimTK::Vec3& v, SimTK::Vec3& f) const noexcept {
    if (depth <= 0) return;
    const double vn = SimTK::dot(v, n);
    const double fn = p_.stiffness * depth * std::sqrt(depth) * (1.0 - 1.5 * p_.dissipation * vn);
    if (fn <= 0) return;
    const SimTK::Vec3 vt = v - vn * n;
    const double speed = vt.norm();
    SimTK::Vec3 ft(0);
    if (speed > 1e-12) ft = -(p_.friction * fn * std::min(speed / p_.transition_mps, 1.0) / speed) * vt;
    f += fn * n + ft;
  }

  std::vector<ContactPoint> points_;
  ContactParams p_;
  const std::vector<TerrainBlock>* blocks_;
  double max_height_ = 0;
  mutable std::uint32_t feet_ = 0;
  mutable bool body_ = false;
};

}  // namespace

struct QuadrupedPlant::Impl {
  QuadrupedPlantOptions options;
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter{system};
  SimTK::GeneralForceSubsystem forces{system};
  SimTK::MobilizedBody base;
  std::vector<SimTK::MobilizedBody> joint_body;  // per actuated joint: the pin's outboard body
  std::vector<double> tau;
  std::vector<double> q, dq;  // cached after each tick
  BaseState base_state;
  double accel_world[3] = {0, 0, 0};
  std::unique_ptr<SimTK::RungeKutta2Integrator> integ;
  const TerrainContact* contact = nullptr;  // owned by the force subsystem
  std::uint32_t feet = 0;
  bool body_contact = false;
  std::size_t foot_count = 0;
  std::uint64_t tick = 0;

  void Capture(bool with_accel) {
    const SimTK::State& s = integ->getState();
    for (std::size_t i = 0; i < joint_body.size(); ++i) {
      q[i] = joint_body[i].getOneQ(s, SimTK::QIndex(0));
      dq[i] = joint_body[i].getOneU(s, SimTK::UIndex(0));
    }
    if (options.mount != Mount::kGround) return;
    system.realize(s, SimTK::Stage::Velocity);
    const SimTK::Transform& X = base.getBodyTransform(s);
    const SimTK::Quaternion quat = X.R().convertRotationToQuaternion();
    const SimTK::Vec3 v = base.getBodyOriginVelocity(s);
    const SimTK::Vec3 w = ~X.R() * base.getBodyAngularVelocity(s);
    BaseState& b = base_state;
    for (int k = 0; k < 3; ++k) {
      if (with_accel) accel_world[k] = (v[k] - b.velocity_mps[k]) / options.tick_s;
      b.position_m[k] = X.p()[k];
      b.velocity_mps[k] = v[k];
      b.angular_radps[k] = w[k];
    }
    for (int k = 0; k < 4; ++k) b.quat_wxyz[k] = quat[k];
  }
};

QuadrupedPlant::QuadrupedPlant() : impl_(std::make_unique<Impl>()) {}
QuadrupedPlant::~QuadrupedPlant() = default;

Result<std::unique_ptr<QuadrupedPlant>> QuadrupedPlant::Make(const robot::RobotDescription& robot,
                                                             const QuadrupedPlantOptions& options) {
  if (!(options.tick_s > 0) || options.substeps < 1)
    return MakeError(ErrorCode::kInvalidValue, "quadruped plant: tick_s " + std::to_string(options.tick_s) +
                                                   " and substeps " + std::to_string(options.substeps) +
                                                   " must be positive");
  const ContactParams& cp = options.contact;
  if (!(cp.stiffness > 0) || !(cp.dissipation >= 0) || !(cp.friction >= 0) || !(cp.transition_mps > 0))
    return MakeError(ErrorCode::kInvalidValue, "quadruped plant: contact stiffness " + std::to_string(cp.stiffness) +
                                                   ", dissipation " + std::to_string(cp.dissipation) + ", friction " +
                                                   std::to_string(cp.friction) + ", transition " +
                                                   std::to_string(cp.transition_mps) +
                                                   " m/s: stiffness and transition must be positive, the rest >= 0");
  for (std::size_t i = 0; i < options.terrain.size(); ++i) {
    const TerrainBlock& b = options.terrain[i];
    if (!(b.x1 > b.x0) || !(b.y1 > b.y0) || !(b.height > 0) || !std::isfinite(b.x0 + b.x1 + b.y0 + b.y1 + b.height))
      return MakeError(ErrorCode::kInvalidValue,
                       "quadruped plant: terrain block " + std::to_string(i) + " is empty or not finite");
  }
  std::unique_ptr<QuadrupedPlant> plant(new QuadrupedPlant());
  Impl& m = *plant->impl_;
  m.options = options;
  const robot::UrdfModel& urdf = robot.urdf;
  SimTK::Force::Gravity(m.forces, m.matter, -SimTK::ZAxis, options.gravity_m_s2);

  // The base welded to the stand, or free; then every joint in topological order.
  std::vector<SimTK::MobilizedBody> link_body(urdf.links.size());
  const SimTK::Body::Rigid base_body(LinkMass(urdf.links[urdf.root]));
  if (options.mount == Mount::kStand) {
    m.base =
        SimTK::MobilizedBody::Weld(m.matter.Ground(), SimTK::Transform(SimTK::Vec3(0, 0, robot.stand_base_height_m)),
                                   base_body, SimTK::Transform());
  } else {
    m.base = SimTK::MobilizedBody::Free(m.matter.Ground(), SimTK::Transform(), base_body, SimTK::Transform());
  }
  link_body[urdf.root] = m.base;
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
    // The joint's mechanical stops at its URDF limits (a leg left limp folds against them, as the
    // robot's would, instead of turning past them); no force inside the limits.
    if (std::isfinite(joint.lower_rad) && std::isfinite(joint.upper_rad))
      SimTK::Force::MobilityLinearStop(m.forces, pin, SimTK::MobilizerQIndex(0), kStopStiffnessNmRad,
                                       kStopDissipationSRad, joint.lower_rad, joint.upper_rad);
    link_body[joint.child] = pin;
  }
  for (std::size_t i = 0; i < robot.joint_count(); ++i) m.joint_body.push_back(link_body[robot.joint_at(i).child]);
  const std::size_t n = m.joint_body.size();
  m.tau.assign(n, 0.0);
  m.q.assign(n, 0.0);
  m.dq.assign(n, 0.0);
  SimTK::Force::Custom(m.forces, new TorqueInput(m.joint_body, &m.tau));
  if (options.mount == Mount::kGround) {
    std::vector<ContactPoint> points;
    int feet = 0;
    for (std::size_t l = 0; l < urdf.links.size(); ++l) {
      for (const robot::UrdfCollision& c : urdf.links[l].collisions) {
        const SimTK::Transform X = FromPose(c.origin);
        if (c.shape == robot::UrdfShape::kSphere) {
          points.push_back({link_body[l], X.p(), c.size[0], feet++});
        } else if (c.shape == robot::UrdfShape::kCylinder) {
          for (double end : {-0.5, 0.5})
            points.push_back({link_body[l], X * SimTK::Vec3(0, 0, end * c.size[1]), c.size[0], -1});
        } else {
          for (int k = 0; k < 8; ++k)
            points.push_back({link_body[l],
                              X * SimTK::Vec3((k & 1 ? 0.5 : -0.5) * c.size[0], (k & 2 ? 0.5 : -0.5) * c.size[1],
                                              (k & 4 ? 0.5 : -0.5) * c.size[2]),
                              0.0, -1});
        }
      }
    }
    if (feet == 0 || feet > 32)
      return MakeError(ErrorCode::kMismatch, "quadruped plant: " + robot.urdf_path + " has " + std::to_string(feet) +
                                                 " collision spheres (feet); the ground mount needs 1 to 32");
    m.foot_count = static_cast<std::size_t>(feet);
    auto* contact = new TerrainContact(std::move(points), cp, &m.options.terrain);
    double top = 0;
    for (const TerrainBlock& b : m.options.terrain) top = std::max(top, b.height);
    contact->SetMaxHeight(top);
    m.contact = contact;
    SimTK::Force::Custom(m.forces, contact);
  }
  m.system.realizeTopology();
  std::vector<double> zero(n, 0.0);
  const double xyz[3] = {0, 0, 1.0};
  if (auto s = plant->Reset(zero, zero, xyz); !s) return s.error();
  return plant;
}

Mount QuadrupedPlant::mount() const noexcept {
  return impl_->options.mount;
}

std::size_t QuadrupedPlant::joint_count() const noexcept {
  return impl_->joint_body.size();
}

Status QuadrupedPlant::Reset(const std::vector<double>& q_rad, const std::vector<double>& dq_rad_s,
                             const double base_xyz[3], double base_yaw_rad) {
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
  if (m.options.mount == Mount::kGround) {
    const SimTK::Vec3 p =
        base_xyz != nullptr ? SimTK::Vec3(base_xyz[0], base_xyz[1], base_xyz[2]) : SimTK::Vec3(0, 0, 1);
    m.system.realize(state, SimTK::Stage::Instance);
    m.base.setQToFitTransform(state, SimTK::Transform(SimTK::Rotation(base_yaw_rad, SimTK::ZAxis), p));
    m.base.setUToFitVelocity(state, SimTK::SpatialVec(SimTK::Vec3(0), SimTK::Vec3(0)));
  }
  m.integ = std::make_unique<SimTK::RungeKutta2Integrator>(m.system);
  m.integ->setFixedStepSize(m.options.tick_s / m.options.substeps);
  m.integ->setAllowInterpolation(false);
  m.integ->initialize(state);
  m.tick = 0;
  m.base_state = BaseState{};
  m.Capture(false);
  for (double& a : m.accel_world) a = 0;
  return {};
}

void QuadrupedPlant::SetJointTorques(const double* tau_nm, std::size_t count) noexcept {
  Impl& m = *impl_;
  const std::size_t n = std::min(count, m.tau.size());
  for (std::size_t i = 0; i < n; ++i) m.tau[i] = std::isfinite(tau_nm[i]) ? tau_nm[i] : 0.0;
  m.integ->updAdvancedState().invalidateAllCacheAtOrAbove(SimTK::Stage::Dynamics);
}

void QuadrupedPlant::Push(double dvx, double dvy, double dvz) {
  Impl& m = *impl_;
  if (m.options.mount != Mount::kGround) return;
  SimTK::State state = m.integ->getState();
  m.system.realize(state, SimTK::Stage::Velocity);
  const SimTK::Vec3 v = m.base.getBodyOriginVelocity(state) + SimTK::Vec3(dvx, dvy, dvz);
  m.base.setUToFitLinearVelocity(state, v);
  m.integ->initialize(state);
}

bool QuadrupedPlant::Step() noexcept {
  Impl& m = *impl_;
  const double target = static_cast<double>(m.tick + 1) * m.options.tick_s;
  if (m.contact != nullptr) m.contact->ClearContacts();
  try {
    // The first stepTo() after initialize() may return without advancing: loop to the target.
    for (int guard = 0; guard < 4 * m.options.substeps + 4 && m.integ->getTime() < target - 1e-12; ++guard)
      m.integ->stepTo(target);
    m.Capture(true);
  } catch (const std::exception&) {
    return false;
  }
  if (m.contact != nullptr) {
    m.feet = m.contact->feet();
    m.body_contact = m.contact->body();
  }
  for (std::size_t i = 0; i < m.q.size(); ++i)
    if (!std::isfinite(m.q[i]) || !std::isfinite(m.dq[i])) return false;
  for (double x : m.base_state.position_m)
    if (!std::isfinite(x)) return false;
  ++m.tick;
  return true;
}

std::uint64_t QuadrupedPlant::tick() const noexcept {
  return impl_->tick;
}
double QuadrupedPlant::time_s() const noexcept {
  return impl_->integ->getTime();
}
double QuadrupedPlant::q_rad(std::size_t j) const noexcept {
  return impl_->q[j];
}
double QuadrupedPlant::dq_rad_s(std::size_t j) const noexcept {
  return impl_->dq[j];
}
double QuadrupedPlant::tau_nm(std::size_t j) const noexcept {
  return impl_->tau[j];
}
const BaseState& QuadrupedPlant::base() const noexcept {
  return impl_->base_state;
}
double QuadrupedPlant::TerrainHeightAt(double x, double y) const noexcept {
  return TerrainHeight(impl_->options.terrain, x, y);
}
std::uint32_t QuadrupedPlant::foot_contacts() const noexcept {
  return impl_->feet;
}
bool QuadrupedPlant::body_contact() const noexcept {
  return impl_->body_contact;
}
std::size_t QuadrupedPlant::foot_count() const noexcept {
  return impl_->foot_count;
}

void QuadrupedPlant::BaseImu(double quat_wxyz[4], double gyro_rad_s[3], double accel_m_s2[3]) const noexcept {
  const Impl& m = *impl_;
  if (m.options.mount == Mount::kStand) {
    quat_wxyz[0] = 1;
    quat_wxyz[1] = quat_wxyz[2] = quat_wxyz[3] = 0;
    gyro_rad_s[0] = gyro_rad_s[1] = gyro_rad_s[2] = 0;
    accel_m_s2[0] = accel_m_s2[1] = 0;
    accel_m_s2[2] = m.options.gravity_m_s2;  // at rest on the stand the accelerometer reads +g upwards
    return;
  }
  const BaseState& b = m.base_state;
  for (int k = 0; k < 4; ++k) quat_wxyz[k] = b.quat_wxyz[k];
  for (int k = 0; k < 3; ++k) gyro_rad_s[k] = b.angular_radps[k];
  // Specific force a - g in the base frame: R^T (a + g e_z).
  const double w = b.quat_wxyz[0], x = b.quat_wxyz[1], y = b.quat_wxyz[2], z = b.quat_wxyz[3];
  const double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                          {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                          {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  const double f[3] = {m.accel_world[0], m.accel_world[1], m.accel_world[2] + m.options.gravity_m_s2};
  for (int r = 0; r < 3; ++r) accel_m_s2[r] = R[0][r] * f[0] + R[1][r] * f[1] + R[2][r] * f[2];
}

}  // namespace pbppo::sim
