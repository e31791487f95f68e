#include "policies/trainer/exporter.hpp"

#include <algorithm>
#include <cmath>

#include "runtime/policy/blob.hpp"
#include "runtime/policy/reference.hpp"
#include "runtime/robot/io_layout.hpp"

namespace pbppo::trainer {
namespace {

Error InitError(const std::string& what) {
  return MakeError(ErrorCode::kInvalidValue, "--init: " + what);
}

// A blob's text field holds at most `max` bytes (the reader's BlobLimits): a longer text is cut
// and says so, ending in "..." (summary.json keeps the run's whole text).
std::string FitText(const std::string& text, std::size_t max) {
  return text.size() <= max ? text : text.substr(0, max - 3) + "...";
}

}  // namespace

policy::PolicySpec FreezeActor(const GaussianPolicy<float>& actor, const float* params,
                               const ObservationNormalizer& normalizer, const envs::Env& env,
                               const ProvenanceInfo& info) {
  policy::PolicySpec s;
  s.input_size = static_cast<std::uint32_t>(actor.mean.input_size());
  s.output_size = static_cast<std::uint32_t>(actor.action_size);
  s.obs_mean = normalizer.mean();
  s.obs_inv_std = normalizer.inv_std();
  s.obs_clip = normalizer.clip();
  for (std::size_t l = 0; l < actor.mean.layers(); ++l) {
    policy::Layer L;
    L.in = static_cast<std::uint32_t>(actor.mean.in(l));
    L.out = static_cast<std::uint32_t>(actor.mean.out(l));
    L.activation = actor.mean.activation(l);
    const auto W = actor.mean.W(params, l);
    L.weight.resize(static_cast<std::size_t>(L.in) * L.out);
    for (std::uint32_t o = 0; o < L.out; ++o)
      for (std::uint32_t i = 0; i < L.in; ++i) L.weight[o * L.in + i] = W(o, i);
    const auto b = actor.mean.b(params, l);
    L.bias.assign(b.data(), b.data() + b.size());
    s.layers.push_back(std::move(L));
  }
  s.action_head = policy::ActionHead::kLinear;  // the Gaussian mean
  // The layout's action map (scale, offset, command limits): the blob outputs commands.
  robot::ApplyLayoutToSpec(env.layout(), s);
  s.provenance.trainer_version = std::string("pbppo-rt ") + PBPPO_VERSION;
  s.provenance.git_revision = BuildGitRevision();
  s.provenance.environment = FitText(env.provenance(), policy::BlobLimits{}.max_text_bytes);
  s.provenance.clip_schedule = FitText(info.clip_schedule, 200);
  s.provenance.seed = info.seed;
  s.provenance.env_steps = info.env_steps;
  s.provenance.final_return = info.final_return;
  return s;
}

Status WritePolicy(const std::string& path, const policy::PolicySpec& spec, std::uint64_t seed) {
  return policy::WritePolicyFiles(path, spec, policy::MakeGoldenVectors(spec, 32, seed));
}

Status LoadActor(const std::string& path, const envs::Env& env, const GaussianPolicy<float>& actor, float* params,
                 ObservationNormalizer* normalizer) {
  auto blob = policy::ReadBlobFile(path);
  if (!blob) return MakeError(blob.error().code, "--init: " + blob.error().message);
  const policy::PolicySpec& s = *blob;
  if (auto st = robot::CheckPolicyMatchesLayout(s, env.layout()); !st)
    return InitError("'" + path + "': " + st.error().message);
  const Mlp<float>& mean = actor.mean;
  if (s.layers.size() != mean.layers())
    return InitError("'" + path + "' has " + std::to_string(s.layers.size()) + " layers, --hidden gives " +
                     std::to_string(mean.layers()));
  for (std::size_t l = 0; l < s.layers.size(); ++l) {
    const policy::Layer& L = s.layers[l];
    const std::string where = "'" + path + "' layer " + std::to_string(l) + " ";
    if (L.kind != policy::LayerKind::kDense)
      return InitError(where + "is " + policy::ToString(L.kind) +
                       ": the trainer's actor is an MLP (dense layers only)");
    if (static_cast<int>(L.in) != mean.in(l) || static_cast<int>(L.out) != mean.out(l))
      return InitError(where + "is " + std::to_string(L.in) + "x" + std::to_string(L.out) + ", --hidden gives " +
                       std::to_string(mean.in(l)) + "x" + std::to_string(mean.out(l)));
    if (L.activation != mean.activation(l))
      return InitError(where + "has activation " + policy::ToString(L.activation) + ", the trainer " +
                       policy::ToString(mean.activation(l)) + " (--activation)");
  }
  for (std::size_t l = 0; l < s.layers.size(); ++l) {
    const policy::Layer& L = s.layers[l];
    auto W = mean.W(params, l);
    for (std::uint32_t o = 0; o < L.out; ++o)
      for (std::uint32_t i = 0; i < L.in; ++i) W(o, i) = L.weight[o * L.in + i];
    auto b = mean.b(params, l);
    for (std::uint32_t o = 0; o < L.out; ++o) b[o] = L.bias[o];
  }
  normalizer->Load(s.obs_mean, s.obs_inv_std, s.obs_clip);
  return {};
}

double CheckFrozen(const policy::PolicySpec& spec, const GaussianPolicy<float>& actor, const float* params,
                   const ObservationNormalizer& normalizer, const envs::Env& env, const float* raw_obs, long count) {
  const int d = actor.mean.input_size(), a = actor.action_size;
  typename Mlp<float>::Workspace ws;
  Mat<float> x(d, 1);
  double worst = 0;
  for (long k = 0; k < 16; ++k) {
    const float* raw = raw_obs + ((k * 7919) % count) * d;
    normalizer.Normalize(raw, x.data());
    const Mat<float>& mu = actor.mean.Forward(params, x, ws);
    const policy::ReferenceOutput ref = policy::ReferenceForward(spec, raw);
    for (int j = 0; j < a; ++j) {
      const auto q = static_cast<std::size_t>(j);
      const double act = std::clamp(mu(j, 0), env.action_low()[q], env.action_high()[q]);
      const double mine = std::clamp(act * spec.action_scale[q] + spec.action_offset[q],
                                     static_cast<double>(spec.action_low[q]), static_cast<double>(spec.action_high[q]));
      // The trainer's float forward rounds like the runtime's: allow twice the bound, plus 1e-6.
      const double bound = 2.0 * ref.error_bound[q] + 1e-6;
      worst = std::max(worst, std::fabs(mine - ref.action[q]) / bound);
    }
  }
  return worst;
}

}  // namespace pbppo::trainer
