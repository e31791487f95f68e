// Simbody model of the AUV. Compiled without NDEBUG (Debian's libsimbody is built without it;
// see sim_hil/CMakeLists.txt). Simbody names stay qualified.
#include "sim_hil/plants/auv_plant.hpp"

#include <Simbody.h>

#include "runtime/robot/yaml_fields.hpp"

#include <algorithm>
#include <cmath>

namespace pbppo::sim {
namespace {

using robot::YamlFields;

double Clamp(double x, double lo, double hi) {
  return std::min(std::max(x, lo), hi);
}
double Sign(double x) {
  return x > 0.0 ? 1.0 : x < 0.0 ? -1.0 : 0.0;
}

// Thruster outputs held constant over one physics step (zero-order hold).
struct Thrust {
  double starboard_n = 0.0;
  double port_n = 0.0;
  double vertical_n = 0.0;
};

// Hydrostatics, damping, the added-mass correction and thrust, on the one free body.
//
// Added mass: a Simbody body has one scalar mass, so the translational added mass is
// approximated by the surge value (mass = m + a_u in all three directions); the larger sway and
// heave added masses are left out of the inertia (their motions are small and dominated by the
// quadratic damping). The rotational added inertia is a diagonal tensor and is added exactly.
// Gravity acts on the dry mass only (not on the added mass), so it is applied here rather than
// with Force::Gravity. The Munk moment of the bare hull is taken as cancelled by the stern fins.
class HydroForce : public SimTK::Force::Custom::Implementation {
 public:
  HydroForce(const SimTK::MobilizedBody& body, const AuvParams& p, const Thrust* thrust)
      : body_(body), p_(p), thrust_(thrust) {}

  void calcForce(const SimTK::State& s, SimTK::Vector_<SimTK::SpatialVec>& body_forces,
                 SimTK::Vector_<SimTK::Vec3>& /*particle_forces*/, SimTK::Vector& /*mobility_forces*/) const override {
    const SimTK::Rotation& R = body_.getBodyRotation(s);
    const SimTK::Vec3 w_b = ~R * body_.getBodyAngularVelocity(s);
    const SimTK::Vec3 v_b = ~R * body_.getBodyOriginVelocity(s);
    SimTK::Vec3 f_b, m_b;
    for (int i = 0; i < 3; ++i) {
      const auto iu = static_cast<std::size_t>(i);
      f_b[i] = -(p_.damping_linear[iu] + p_.damping_quadratic[iu] * std::abs(v_b[i])) * v_b[i];
      m_b[i] = -(p_.damping_linear[iu + 3] + p_.damping_quadratic[iu + 3] * std::abs(w_b[i])) * w_b[i];
    }
    // Horizontal pair at y = -d (starboard) and y = +d (port); vertical thruster at the CG.
    f_b[0] += thrust_->starboard_n + thrust_->port_n;
    m_b[2] += p_.thruster_lateral_offset_m * (thrust_->starboard_n - thrust_->port_n);
    f_b[2] += thrust_->vertical_n;
    SimTK::Vec3 f_g = R * f_b;
    f_g[2] -= p_.mass_kg * p_.gravity_mps2;
    body_forces[body_.getMobilizedBodyIndex()] += SimTK::SpatialVec(R * m_b, f_g);
    // Buoyancy at the centre of buoyancy above the CG: the restoring moment in roll and pitch.
    body_.applyForceToBodyPoint(s, SimTK::Vec3(0, 0, p_.cb_above_cg_m), SimTK::Vec3(0, 0, p_.buoyancy_n), body_forces);
  }
  SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0.0; }
  bool dependsOnlyOnPositions() const override { return false; }

 private:
  SimTK::MobilizedBody body_;
  AuvParams p_;
  const Thrust* thrust_;
};

}  // namespace

int AuvParams::substeps() const noexcept {
  return static_cast<int>(std::lround(control_period_s / physics_step_s));
}

Status ValidateAuvParams(const AuvParams& p) {
  auto bad = [](const std::string& field, double v, const std::string& why) {
    return MakeError(ErrorCode::kInvalidValue, "auv params: " + field + " = " + std::to_string(v) + ": " + why);
  };
  auto positive = [&](const std::string& field, double v) -> Status {
    if (!std::isfinite(v) || v <= 0.0) return bad(field, v, "must be finite and > 0");
    return {};
  };
  auto non_negative = [&](const std::string& field, double v) -> Status {
    if (!std::isfinite(v) || v < 0.0) return bad(field, v, "must be finite and >= 0");
    return {};
  };
  for (auto [f, v] : {std::pair<const char*, double>{"hull.mass_kg", p.mass_kg},
                      {"hull.length_m", p.length_m},
                      {"hull.diameter_m", p.diameter_m},
                      {"hull.buoyancy_n", p.buoyancy_n},
                      {"hull.gravity_mps2", p.gravity_mps2},
                      {"thrusters.lateral_offset_m", p.thruster_lateral_offset_m},
                      {"thrusters.forward_max_n", p.thrust_forward_max_n},
                      {"thrusters.reverse_max_n", p.thrust_reverse_max_n},
                      {"thrusters.heave_max_n", p.heave_thrust_max_n},
                      {"controller.surge_speed_max_mps", p.surge_speed_max_mps},
                      {"controller.yaw_rate_max_radps", p.yaw_rate_max_radps},
                      {"simulation.physics_step_s", p.physics_step_s},
                      {"control period", p.control_period_s}}) {
    if (auto st = positive(f, v); !st) return st;
  }
  if (auto st = non_negative("hull.cb_above_cg_m", p.cb_above_cg_m); !st) return st;
  for (std::size_t i = 0; i < 3; ++i) {
    if (auto st = positive("hull.inertia_kgm2[" + std::to_string(i) + "]", p.inertia_kgm2[i]); !st) return st;
    if (auto st = non_negative("added_mass.translational_kg[" + std::to_string(i) + "]", p.added_mass_kg[i]); !st)
      return st;
    if (auto st = non_negative("added_mass.rotational_kgm2[" + std::to_string(i) + "]", p.added_inertia_kgm2[i]); !st)
      return st;
  }
  for (std::size_t i = 0; i < 6; ++i) {
    if (auto st = non_negative("damping.linear[" + std::to_string(i) + "]", p.damping_linear[i]); !st) return st;
    if (auto st = non_negative("damping.quadratic[" + std::to_string(i) + "]", p.damping_quadratic[i]); !st) return st;
  }
  for (auto [name, g] :
       {std::pair<const char*, const PidGains*>{"surge", &p.surge}, {"yaw_rate", &p.yaw_rate}, {"depth", &p.depth}}) {
    const std::string w = std::string("controller.") + name;
    if (auto st = non_negative(w + ".kp", g->kp); !st) return st;
    if (auto st = non_negative(w + ".ki", g->ki); !st) return st;
    if (auto st = non_negative(w + ".kd", g->kd); !st) return st;
    if (auto st = non_negative(w + ".integral_limit", g->integral_limit); !st) return st;
  }
  if (!std::isfinite(p.surge_speed_min_mps) || p.surge_speed_min_mps >= p.surge_speed_max_mps)
    return bad("controller.surge_speed_min_mps", p.surge_speed_min_mps, "must be below surge_speed_max_mps");
  const double ratio = p.control_period_s / p.physics_step_s;
  if (std::abs(ratio - std::round(ratio)) > 1e-9 * ratio || ratio < 0.5)
    return bad("control period (robot.yaml timing.policy_period_s)", p.control_period_s,
               "must be a whole multiple of simulation.physics_step_s = " + std::to_string(p.physics_step_s));
  return {};
}

Result<AuvParams> ParseAuvParams(const YAML::Node& root, const std::string& path, double control_period_s) {
  YamlFields f(path);
  PBPPO_TRY(f.Keys(
      root, "",
      {"hull", "added_mass", "damping", "thrusters", "controller", "simulation", "sonar", "task", "description"}));
  AuvParams p;
  p.control_period_s = control_period_s;
  constexpr double kBig = 1e9;
  YAML::Node n;
  PBPPO_TRY(f.Map(root, "hull", "", &n));
  PBPPO_TRY(f.Keys(
      n, "hull", {"mass_kg", "length_m", "diameter_m", "inertia_kgm2", "buoyancy_n", "cb_above_cg_m", "gravity_mps2"}));
  // Fields of the section `where` (in n) that must be positive.
  auto positive = [&](const char* where, std::initializer_list<std::pair<const char*, double*>> fields) -> Status {
    for (auto [k, out] : fields) PBPPO_TRY(f.Number(n, k, where, 1e-6, kBig, out));
    return {};
  };
  PBPPO_TRY(positive("hull", {{"mass_kg", &p.mass_kg},
                              {"length_m", &p.length_m},
                              {"diameter_m", &p.diameter_m},
                              {"buoyancy_n", &p.buoyancy_n}}));
  PBPPO_TRY(f.Number(n, "cb_above_cg_m", "hull", 0.0, 1.0, &p.cb_above_cg_m));
  PBPPO_TRY(f.OptionalNumber(n, "gravity_mps2", "hull", 1e-6, 100.0, &p.gravity_mps2));
  PBPPO_TRY(f.Array<3>(n, "inertia_kgm2", "hull", 1e-9, kBig, &p.inertia_kgm2));

  PBPPO_TRY(f.Map(root, "added_mass", "", &n));
  PBPPO_TRY(f.Keys(n, "added_mass", {"translational_kg", "rotational_kgm2"}));
  PBPPO_TRY(f.Array<3>(n, "translational_kg", "added_mass", 0.0, kBig, &p.added_mass_kg));
  PBPPO_TRY(f.Array<3>(n, "rotational_kgm2", "added_mass", 0.0, kBig, &p.added_inertia_kgm2));

  PBPPO_TRY(f.Map(root, "damping", "", &n));
  PBPPO_TRY(f.Keys(n, "damping", {"linear", "quadratic"}));
  PBPPO_TRY(f.Array<6>(n, "linear", "damping", 0.0, kBig, &p.damping_linear));
  PBPPO_TRY(f.Array<6>(n, "quadratic", "damping", 0.0, kBig, &p.damping_quadratic));

  PBPPO_TRY(f.Map(root, "thrusters", "", &n));
  PBPPO_TRY(f.Keys(n, "thrusters", {"lateral_offset_m", "forward_max_n", "reverse_max_n", "heave_max_n"}));
  PBPPO_TRY(positive("thrusters", {{"lateral_offset_m", &p.thruster_lateral_offset_m},
                                   {"forward_max_n", &p.thrust_forward_max_n},
                                   {"reverse_max_n", &p.thrust_reverse_max_n},
                                   {"heave_max_n", &p.heave_thrust_max_n}}));

  PBPPO_TRY(f.Map(root, "controller", "", &n));
  PBPPO_TRY(f.Keys(n, "controller", {"surge", "yaw_rate", "depth", "surge_speed_mps", "yaw_rate_max_radps"}));
  for (auto [k, g] :
       {std::pair<const char*, PidGains*>{"surge", &p.surge}, {"yaw_rate", &p.yaw_rate}, {"depth", &p.depth}}) {
    YAML::Node c;
    const std::string w = std::string("controller.") + k;
    PBPPO_TRY(f.Map(n, k, "controller", &c));
    PBPPO_TRY(f.Keys(c, w, {"kp", "ki", "kd", "integral_limit"}));
    g->kd = 0.0;
    PBPPO_TRY(f.Number(c, "kp", w, 0.0, kBig, &g->kp));
    PBPPO_TRY(f.Number(c, "ki", w, 0.0, kBig, &g->ki));
    PBPPO_TRY(f.OptionalNumber(c, "kd", w, 0.0, kBig, &g->kd));
    PBPPO_TRY(f.Number(c, "integral_limit", w, 0.0, kBig, &g->integral_limit));
  }
  std::array<double, 2> speeds{};
  PBPPO_TRY(f.Range(n, "surge_speed_mps", "controller", -10.0, 10.0, &speeds));
  p.surge_speed_min_mps = speeds[0];
  p.surge_speed_max_mps = speeds[1];
  PBPPO_TRY(f.Number(n, "yaw_rate_max_radps", "controller", 1e-6, 10.0, &p.yaw_rate_max_radps));

  PBPPO_TRY(f.Map(root, "simulation", "", &n));
  PBPPO_TRY(f.Keys(n, "simulation", {"physics_step_s", "integrator"}));
  PBPPO_TRY(f.Number(n, "physics_step_s", "simulation", 1e-5, 1.0, &p.physics_step_s));
  std::string integ;
  PBPPO_TRY(f.Text(n, "integrator", "simulation", &integ));
  if (integ == "rk2") {
    p.integrator = AuvIntegrator::kRk2;
  } else if (integ == "semi_explicit_euler") {
    p.integrator = AuvIntegrator::kSemiExplicitEuler;
  } else {
    return f.Fail("simulation.integrator", "'" + integ + "' is not one of rk2, semi_explicit_euler");
  }
  if (auto st = ValidateAuvParams(p); !st) return MakeError(st.error().code, path + ": " + st.error().message);
  return p;
}

struct AuvPlant::Impl {
  explicit Impl(const AuvParams& p) : params(p), matter(system), forces(system) {
    const double m = p.mass_kg + p.added_mass_kg[0];
    const SimTK::Inertia inertia(p.inertia_kgm2[0] + p.added_inertia_kgm2[0],
                                 p.inertia_kgm2[1] + p.added_inertia_kgm2[1],
                                 p.inertia_kgm2[2] + p.added_inertia_kgm2[2]);
    SimTK::Body::Rigid hull(SimTK::MassProperties(m, SimTK::Vec3(0), inertia));
    body = SimTK::MobilizedBody::Free(matter.Ground(), SimTK::Transform(), hull, SimTK::Transform());
    SimTK::Force::Custom(forces, new HydroForce(body, params, &thrust));
    system.realizeTopology();
    state = system.getDefaultState();
    // Euler angles (body-fixed X-Y-Z) instead of a quaternion: no normalisation in the fixed-step
    // integrator; the singularity at 90 degrees of pitch is far outside an AUV's envelope.
    matter.setUseEulerAngles(state, true);
    system.realizeModel(state);
    q0.resize(state.getNQ());
    u0.resize(state.getNU());
    qd0.resize(state.getNQ());
    ud0.resize(state.getNU());
  }

  void Reset(const AuvPose& pose) {
    state.setTime(0.0);
    const SimTK::Rotation R(SimTK::BodyRotationSequence, pose.yaw_rad, SimTK::ZAxis, pose.pitch_rad, SimTK::YAxis,
                            pose.roll_rad, SimTK::XAxis);
    body.setQToFitTransform(state, SimTK::Transform(R, SimTK::Vec3(pose.x_m, pose.y_m, pose.z_m)));
    state.updU() = 0.0;
    thrust = Thrust{};
    i_surge = i_yaw = i_depth = 0.0;
    sat_surge = sat_yaw = sat_depth = 0.0;
    v_cmd = w_cmd = 0.0;
    z_ref = pose.z_m;
    steps = 0;
    system.realize(state, SimTK::Stage::Velocity);
    Publish();
  }

  // The low-level controller at the start of a physics step; needs Stage::Velocity.
  void Control(double h) {
    const SimTK::Rotation& R = body.getBodyRotation(state);
    const SimTK::Vec3 w_b = ~R * body.getBodyAngularVelocity(state);
    const SimTK::Vec3 v_g = body.getBodyOriginVelocity(state);
    const SimTK::Vec3 v_b = ~R * v_g;
    const double z = body.getBodyOriginLocation(state)[2];
    const auto& p = params;
    // Surge and yaw rate: feed-forward of the hull's damping at the commanded value plus PI.
    // Conditional integration: an integrator does not grow while the previous step's output
    // was saturated in the direction of its error (no wind-up during full-thrust manoeuvres).
    const double e_u = v_cmd - v_b[0];
    if (e_u * sat_surge <= 0.0) i_surge = Clamp(i_surge + e_u * h, -p.surge.integral_limit, p.surge.integral_limit);
    const double x_force = (p.damping_linear[0] + p.damping_quadratic[0] * std::abs(v_cmd)) * v_cmd + p.surge.kp * e_u +
                           p.surge.ki * i_surge;
    const double e_r = w_cmd - w_b[2];
    if (e_r * sat_yaw <= 0.0) i_yaw = Clamp(i_yaw + e_r * h, -p.yaw_rate.integral_limit, p.yaw_rate.integral_limit);
    const double n_moment = (p.damping_linear[5] + p.damping_quadratic[5] * std::abs(w_cmd)) * w_cmd +
                            p.yaw_rate.kp * e_r + p.yaw_rate.ki * i_yaw;
    // Depth: PID on the world depth error plus the net buoyancy as feed-forward.
    const double e_z = z_ref - z;
    if (e_z * sat_depth <= 0.0) i_depth = Clamp(i_depth + e_z * h, -p.depth.integral_limit, p.depth.integral_limit);
    const double z_force =
        p.depth.kp * e_z + p.depth.ki * i_depth - p.depth.kd * v_g[2] - (p.buoyancy_n - p.mass_kg * p.gravity_mps2);
    // Allocation to the horizontal pair, X = Ts + Tp, N = d (Ts - Tp), with yaw priority: the
    // differential is kept (up to what the pair can give) and the common part is cut to fit, so
    // a saturated turn slows the vehicle down instead of widening the turn.
    const double fwd = p.thrust_forward_max_n, rev = p.thrust_reverse_max_n;
    const double want_diff = n_moment / (2.0 * p.thruster_lateral_offset_m);
    const double half_diff = Clamp(want_diff, -0.5 * (fwd + rev), 0.5 * (fwd + rev));
    const double common = Clamp(0.5 * x_force, -rev + std::abs(half_diff), fwd - std::abs(half_diff));
    thrust.starboard_n = common + half_diff;
    thrust.port_n = common - half_diff;
    thrust.vertical_n = Clamp(z_force, -p.heave_thrust_max_n, p.heave_thrust_max_n);
    sat_surge = Sign(0.5 * x_force - common);
    sat_yaw = Sign(want_diff - half_diff);
    sat_depth = Sign(z_force - thrust.vertical_n);
  }

  void Step() {
    const double h = params.physics_step_s;
    const double t = state.getTime();
    Control(h);  // state is realised to Velocity here
    system.realize(state, SimTK::Stage::Acceleration);
    const int nq = state.getNQ(), nu = state.getNU();
    for (int i = 0; i < nq; ++i) q0[i] = state.getQ()[i];
    for (int i = 0; i < nu; ++i) u0[i] = state.getU()[i];
    if (params.integrator == AuvIntegrator::kSemiExplicitEuler) {
      // u1 = u0 + h a(q0, u0); q1 = q0 + h N(q0) u1.
      for (int i = 0; i < nu; ++i) ud0[i] = state.getUDot()[i];
      {
        SimTK::Vector& u = state.updU();
        for (int i = 0; i < nu; ++i) u[i] = u0[i] + h * ud0[i];
      }
      system.realize(state, SimTK::Stage::Velocity);
      for (int i = 0; i < nq; ++i) qd0[i] = state.getQDot()[i];
      SimTK::Vector& q = state.updQ();
      for (int i = 0; i < nq; ++i) q[i] = q0[i] + h * qd0[i];
    } else {
      // Heun (explicit trapezoidal RK2).
      for (int i = 0; i < nq; ++i) qd0[i] = state.getQDot()[i];
      for (int i = 0; i < nu; ++i) ud0[i] = state.getUDot()[i];
      {
        SimTK::Vector& q = state.updQ();
        for (int i = 0; i < nq; ++i) q[i] = q0[i] + h * qd0[i];
        SimTK::Vector& u = state.updU();
        for (int i = 0; i < nu; ++i) u[i] = u0[i] + h * ud0[i];
      }
      state.setTime(t + h);
      system.realize(state, SimTK::Stage::Acceleration);
      for (int i = 0; i < nq; ++i) qd0[i] = 0.5 * (qd0[i] + state.getQDot()[i]);
      for (int i = 0; i < nu; ++i) ud0[i] = 0.5 * (ud0[i] + state.getUDot()[i]);
      SimTK::Vector& q = state.updQ();
      for (int i = 0; i < nq; ++i) q[i] = q0[i] + h * qd0[i];
      SimTK::Vector& u = state.updU();
      for (int i = 0; i < nu; ++i) u[i] = u0[i] + h * ud0[i];
    }
    ++steps;
    // Time as a step count: no accumulated rounding.
    state.setTime(static_cast<double>(steps) * h);
    system.realize(state, SimTK::Stage::Velocity);
  }

  void Publish() {
    const SimTK::Rotation& R = body.getBodyRotation(state);
    const SimTK::Vec3 ypr =
        R.convertThreeAxesRotationToThreeAngles(SimTK::BodyRotationSequence, SimTK::ZAxis, SimTK::YAxis, SimTK::XAxis);
    const SimTK::Vec3& pos = body.getBodyOriginLocation(state);
    const SimTK::Vec3 w_b = ~R * body.getBodyAngularVelocity(state);
    const SimTK::Vec3 v_b = ~R * body.getBodyOriginVelocity(state);
    auto put = [](const SimTK::Vec3& v, double* a, double* b, double* c) { *a = v[0], *b = v[1], *c = v[2]; };
    out.time_s = state.getTime();
    put(pos, &out.x_m, &out.y_m, &out.z_m);
    put(ypr, &out.yaw_rad, &out.pitch_rad, &out.roll_rad);
    put(v_b, &out.u_mps, &out.v_mps, &out.w_mps);
    put(w_b, &out.p_radps, &out.q_radps, &out.r_radps);
    out.thrust_n = {thrust.starboard_n, thrust.port_n, thrust.vertical_n};
  }

  AuvParams params;
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter;
  SimTK::GeneralForceSubsystem forces;
  SimTK::MobilizedBody::Free body;
  SimTK::State state;
  SimTK::Vector q0, u0, qd0, ud0;
  Thrust thrust;
  double v_cmd = 0.0, w_cmd = 0.0, z_ref = 0.0;
  double i_surge = 0.0, i_yaw = 0.0, i_depth = 0.0;
  // Sign of the last step's saturation per loop (+1 above the limit, -1 below, 0 within).
  double sat_surge = 0.0, sat_yaw = 0.0, sat_depth = 0.0;
  std::uint64_t steps = 0;
  AuvState out;
};

Result<AuvPlant> AuvPlant::Create(const AuvParams& params) {
  PBPPO_TRY(ValidateAuvParams(params));
  auto impl = std::make_unique<Impl>(params);
  impl->Reset(AuvPose{});
  return AuvPlant(std::move(impl));
}

AuvPlant::AuvPlant(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
AuvPlant::AuvPlant(AuvPlant&&) noexcept = default;
AuvPlant& AuvPlant::operator=(AuvPlant&&) noexcept = default;
AuvPlant::~AuvPlant() = default;

void AuvPlant::Reset(const AuvPose& pose) {
  impl_->Reset(pose);
}

void AuvPlant::SetCommand(double v_mps, double w_radps) noexcept {
  const auto& p = impl_->params;
  impl_->v_cmd = std::isfinite(v_mps) ? Clamp(v_mps, p.surge_speed_min_mps, p.surge_speed_max_mps) : 0.0;
  impl_->w_cmd = std::isfinite(w_radps) ? Clamp(w_radps, -p.yaw_rate_max_radps, p.yaw_rate_max_radps) : 0.0;
}

void AuvPlant::SetDepthSetpoint(double z_m) noexcept {
  if (std::isfinite(z_m)) impl_->z_ref = z_m;
}

void AuvPlant::Advance(double dt_s) noexcept {
  const long n = std::isfinite(dt_s) ? std::lround(dt_s / impl_->params.physics_step_s) : 1;
  AdvanceSteps(static_cast<int>(std::max(1L, n)));
}

void AuvPlant::AdvanceSteps(int steps) noexcept {
  for (int i = 0; i < steps; ++i) impl_->Step();
  impl_->Publish();
}

const AuvState& AuvPlant::State() const noexcept {
  return impl_->out;
}
const AuvParams& AuvPlant::params() const noexcept {
  return impl_->params;
}
std::uint64_t AuvPlant::physics_steps() const noexcept {
  return impl_->steps;
}

}  // namespace pbppo::sim
