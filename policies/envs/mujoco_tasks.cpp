#include "policies/envs/mujoco_tasks.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>

namespace pbppo::envs {
namespace {

// The v3 tasks' defaults (docs/mujoco_tasks.md has them beside the standard task's source).
constexpr MujocoTaskSpec kSpecs[] = {
    {MujocoTaskKind::kHopper, "hopper", "hopper", 4, 1e-3, 0.0, 1.0, true, 5e-3, false, 10.0},
    {MujocoTaskKind::kWalker2d, "walker2d", "walker2d", 4, 1e-3, 0.0, 1.0, true, 5e-3, false, 10.0},
    {MujocoTaskKind::kHalfCheetah, "half-cheetah", "half_cheetah", 5, 0.1, 0.0, 0.0, false, 0.1, true, 0.0},
    {MujocoTaskKind::kAnt, "ant", "ant", 5, 0.5, 5e-4, 1.0, true, 0.1, true, 0.0},
};

// What each body must look like for the task's observation and health checks.
struct Shape {
  int nq, nv, nu, nbody;
};

Shape ShapeOf(MujocoTaskKind kind) {
  switch (kind) {
    case MujocoTaskKind::kHopper: return {6, 6, 3, 5};
    case MujocoTaskKind::kWalker2d: return {9, 9, 6, 8};
    case MujocoTaskKind::kHalfCheetah: return {9, 9, 6, 8};
    case MujocoTaskKind::kAnt: return {15, 14, 8, 14};
  }
  return {};
}

std::uint32_t ObservationSize(MujocoTaskKind kind, const mjModel* m) {
  if (kind == MujocoTaskKind::kAnt) return static_cast<std::uint32_t>((m->nq - 2) + m->nv + 6 * m->nbody);
  return static_cast<std::uint32_t>((m->nq - 1) + m->nv);
}

// pbppo eval --through-ends: every episode runs its 1000 steps.
class ThroughEnds final : public EpisodeHooks {
 public:
  bool through_ends() const noexcept override { return true; }
};

}  // namespace

std::vector<EnvSpec> MujocoTaskEnvs() {
  std::vector<EnvSpec> out;
  for (const MujocoTaskSpec& task : kSpecs) {
    EnvSpec s;
    s.name = task.name;
    s.description = std::string("MuJoCo's ") + task.name + ", v3 rules, docs/mujoco_tasks.md";
    s.flags.push_back(Flag("through-ends", EnvFlag::kEval, EnvFlag::Kind::kSwitch, "", "step on after an episode ends",
                           "every episode runs 1000 steps, on through terminations (the paper's script's way)"));
    if (task.kind == MujocoTaskKind::kAnt)
      s.flags.push_back(Flag(
          "contact-forces", EnvFlag::kBoth, EnvFlag::Kind::kText, "computed", "has contact forces to leave out",
          "computed, or zero as the paper's software ran (no cost)",
          [](const std::string& v) -> Status {
            if (v == "computed" || v == "zero") return {};
            return MakeError(ErrorCode::kInvalidValue, "'" + v + "' is not computed or zero");
          },
          true));
    s.make = [&task](const EnvOptions& o) -> Result<std::unique_ptr<Env>> {
      return AsEnv(MujocoTask::Make(task, ModelsDir(o), FlagText(o, "contact-forces") != "zero"));
    };
    s.evaluation.hooks = [](const EvalRequest& r, Env&) -> Result<std::unique_ptr<EpisodeHooks>> {
      if (!FlagSet(*r.env, "through-ends")) return std::unique_ptr<EpisodeHooks>();
      return std::unique_ptr<EpisodeHooks>(new ThroughEnds());
    };
    out.push_back(std::move(s));
  }
  return out;
}

struct MujocoTask::Shared {
  const MujocoTaskSpec* spec = nullptr;
  mjModel* model = nullptr;
  robot::IoLayout layout;
  int torso = -1;              // ant: the body whose x position measures progress
  bool contact_forces = true;  // ant: computed (else left at zero)
  ~Shared() {
    if (model != nullptr) mj_deleteModel(model);
  }
};

const MujocoTaskSpec* FindMujocoTask(const std::string& name) noexcept {
  for (const auto& s : kSpecs)
    if (name == s.name) return &s;
  return nullptr;
}

std::vector<std::string> MujocoTaskNames() {
  std::vector<std::string> out;
  for (const auto& s : kSpecs) out.emplace_back(s.name);
  return out;
}

Result<std::unique_ptr<MujocoTask>> MujocoTask::Make(const MujocoTaskSpec& spec, const std::string& models_dir,
                                                     bool contact_forces) {
  const std::string folder = models_dir + "/" + spec.folder;
  const std::string xml = folder + "/" + spec.folder + ".xml";
  auto layout = robot::LoadIoLayout(folder + "/io_layout.yaml");
  if (!layout) return std::move(layout).error();

  auto shared = std::make_shared<Shared>();
  shared->spec = &spec;
  shared->contact_forces = contact_forces;
  shared->layout = std::move(layout).value();
  char error[1000] = "";
  shared->model = mj_loadXML(xml.c_str(), nullptr, error, sizeof error);
  if (shared->model == nullptr) return MakeError(ErrorCode::kFormat, xml + ": MuJoCo refused the model: " + error);
  const mjModel* m = shared->model;

  const Shape want = ShapeOf(spec.kind);
  if (m->nq != want.nq || m->nv != want.nv || m->nu != want.nu || m->nbody != want.nbody)
    return MakeError(ErrorCode::kFormat, xml + ": " + spec.name + " needs nq " + std::to_string(want.nq) + ", nv " +
                                             std::to_string(want.nv) + ", " + std::to_string(want.nu) + " motors and " +
                                             std::to_string(want.nbody) + " bodies; the model has " +
                                             std::to_string(m->nq) + ", " + std::to_string(m->nv) + ", " +
                                             std::to_string(m->nu) + " and " + std::to_string(m->nbody));
  // The root: a free joint (ant) or slide x, slide z, hinge y (the planar tasks), first.
  if (spec.kind == MujocoTaskKind::kAnt) {
    if (m->jnt_type[0] != mjJNT_FREE) return MakeError(ErrorCode::kFormat, xml + ": the first joint must be free");
    shared->torso = mj_name2id(m, mjOBJ_BODY, "torso");
    if (shared->torso < 0) return MakeError(ErrorCode::kFormat, xml + ": no body 'torso'");
  } else if (m->njnt < 3 || m->jnt_type[0] != mjJNT_SLIDE || m->jnt_type[1] != mjJNT_SLIDE ||
             m->jnt_type[2] != mjJNT_HINGE) {
    return MakeError(ErrorCode::kFormat, xml + ": the first joints must be slide x, slide z and hinge y");
  }
  for (int i = 0; i < m->nu; ++i)
    if (m->actuator_ctrllimited[i] == 0 || m->actuator_ctrlrange[2 * i] != -1 || m->actuator_ctrlrange[2 * i + 1] != 1)
      return MakeError(ErrorCode::kFormat, xml + ": motor " + std::to_string(i) + " must be limited to [-1, 1]");

  const robot::IoLayout& l = shared->layout;
  const std::uint32_t obs = ObservationSize(spec.kind, m);
  if (l.observation_size() != obs || l.action_size() != static_cast<std::uint32_t>(m->nu))
    return MakeError(ErrorCode::kFormat, folder + "/io_layout.yaml: " + spec.name + " has " + std::to_string(obs) +
                                             " observations and " + std::to_string(m->nu) + " actions; the layout " +
                                             std::to_string(l.observation_size()) + " and " +
                                             std::to_string(l.action_size()));
  for (const auto& a : l.actions)
    if (a.scale != 1 || a.offset != 0 || a.low != -1 || a.high != 1)
      return MakeError(ErrorCode::kFormat, folder + "/io_layout.yaml: action '" + a.name +
                                               "' must map [-1, 1] to itself (scale 1, offset 0, low -1, high 1)");
  return std::make_unique<MujocoTask>(std::move(shared));
}

MujocoTask::MujocoTask(std::shared_ptr<const Shared> shared) : shared_(std::move(shared)) {
  const mjModel* m = shared_->model;
  name_ = shared_->spec->name;
  d_ = mj_makeData(m);
  low_.assign(static_cast<std::size_t>(m->nu), -1.0f);
  high_.assign(static_cast<std::size_t>(m->nu), 1.0f);
  mj_forward(m, d_);
}

MujocoTask::~MujocoTask() {
  if (d_ != nullptr) mj_deleteData(d_);
}

const robot::IoLayout& MujocoTask::layout() const noexcept {
  return shared_->layout;
}
const mjModel_* MujocoTask::model() const noexcept {
  return shared_->model;
}
const MujocoTaskSpec& MujocoTask::spec() const noexcept {
  return *shared_->spec;
}
double MujocoTask::dt() const noexcept {
  return shared_->model->opt.timestep * shared_->spec->frame_skip;
}

std::unique_ptr<Env> MujocoTask::Clone() const {
  auto copy = std::make_unique<MujocoTask>(shared_);
  mj_copyData(copy->d_, shared_->model, d_);
  copy->elapsed_ = elapsed_;
  return copy;
}

double MujocoTask::forward_position() const noexcept {
  // The planar tasks measure the root's x; the ant its torso's x as the last kinematics pass left
  // it (after a step: the state before the step's last physics step, as the standard task reads it).
  if (shared_->torso >= 0) return d_->xpos[3 * shared_->torso];
  return d_->qpos[0];
}

bool MujocoTask::healthy() const noexcept {
  const mjModel* m = shared_->model;
  const double* q = d_->qpos;
  switch (shared_->spec->kind) {
    case MujocoTaskKind::kHopper: {
      for (int i = 2; i < m->nq; ++i)
        if (!(q[i] > -100 && q[i] < 100)) return false;
      for (int i = 0; i < m->nv; ++i)
        if (!(d_->qvel[i] > -100 && d_->qvel[i] < 100)) return false;
      return q[1] > 0.7 && q[2] > -0.2 && q[2] < 0.2;
    }
    case MujocoTaskKind::kWalker2d: return q[1] > 0.8 && q[1] < 2.0 && q[2] > -1.0 && q[2] < 1.0;
    case MujocoTaskKind::kHalfCheetah: return true;
    case MujocoTaskKind::kAnt: {
      for (int i = 0; i < m->nq; ++i)
        if (!std::isfinite(q[i])) return false;
      for (int i = 0; i < m->nv; ++i)
        if (!std::isfinite(d_->qvel[i])) return false;
      return q[2] >= 0.2 && q[2] <= 1.0;
    }
  }
  return false;
}

std::string MujocoTask::provenance() const {
  return shared_->contact_forces ? name_ : name_ + " (contact forces zero)";
}

void MujocoTask::Observe(std::span<float> observation) const noexcept {
  const mjModel* m = shared_->model;
  const MujocoTaskSpec& s = *shared_->spec;
  const int skip = s.kind == MujocoTaskKind::kAnt ? 2 : 1;  // the root's x (and y): not observed
  std::size_t k = 0;
  for (int i = skip; i < m->nq; ++i) observation[k++] = static_cast<float>(d_->qpos[i]);
  for (int i = 0; i < m->nv; ++i) {
    const double v = d_->qvel[i];
    observation[k++] = static_cast<float>(s.velocity_clip > 0 ? std::clamp(v, -s.velocity_clip, s.velocity_clip) : v);
  }
  if (s.kind == MujocoTaskKind::kAnt)
    for (int i = 0; i < 6 * m->nbody; ++i)
      observation[k++] = shared_->contact_forces ? static_cast<float>(std::clamp(d_->cfrc_ext[i], -1.0, 1.0)) : 0.0f;
}

void MujocoTask::Reset(Rng& rng, std::span<float> observation) {
  const mjModel* m = shared_->model;
  const MujocoTaskSpec& s = *shared_->spec;
  mj_resetData(m, d_);
  for (int i = 0; i < m->nq; ++i) d_->qpos[i] = m->qpos0[i] + rng.Uniform(-s.reset_noise, s.reset_noise);
  for (int i = 0; i < m->nv; ++i)
    d_->qvel[i] = s.normal_velocity_noise ? s.reset_noise * rng.Normal() : rng.Uniform(-s.reset_noise, s.reset_noise);
  mj_forward(m, d_);
  if (s.kind == MujocoTaskKind::kAnt && shared_->contact_forces) mj_rnePostConstraint(m, d_);
  elapsed_ = 0;
  Observe(observation);
}

StepResult MujocoTask::Step(std::span<const float> action, std::span<float> observation) {
  const mjModel* m = shared_->model;
  const MujocoTaskSpec& s = *shared_->spec;
  double ctrl_sq = 0;
  for (int i = 0; i < m->nu; ++i) {
    const double a = std::clamp(static_cast<double>(action[static_cast<std::size_t>(i)]), -1.0, 1.0);
    d_->ctrl[i] = a;
    ctrl_sq += a * a;
  }
  const double before = forward_position();
  for (int i = 0; i < s.frame_skip; ++i) mj_step(m, d_);
  double contact_sq = 0;
  if (s.kind == MujocoTaskKind::kAnt && shared_->contact_forces) {
    // MuJoCo computes the external contact forces only on request.
    mj_rnePostConstraint(m, d_);
    for (int i = 0; i < 6 * m->nbody; ++i) {
      const double f = std::clamp(d_->cfrc_ext[i], -1.0, 1.0);
      contact_sq += f * f;
    }
  }
  const double velocity = (forward_position() - before) / dt();
  const bool ok = healthy();
  StepResult r;
  r.reward =
      velocity + ((ok || s.terminates) ? s.healthy_reward : 0.0) - s.ctrl_cost * ctrl_sq - s.contact_cost * contact_sq;
  r.terminated = s.terminates && !ok;
  ++elapsed_;
  r.truncated = !r.terminated && elapsed_ >= kEpisodeSteps;
  Observe(observation);
  return r;
}

}  // namespace pbppo::envs
