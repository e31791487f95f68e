#include "runtime/policy/policy_spec.hpp"

#include <cmath>

#include "runtime/core/enum_name.hpp"
#include "runtime/core/random.hpp"

namespace pbppo::policy {

const char* ToString(Activation a) noexcept {
  return EnumName(a, {"identity", "tanh", "elu", "relu", "leaky_relu"});
}

const char* ToString(ActionHead h) noexcept {
  return EnumName(h, {"linear", "tanh"});
}

const char* ToString(LayerKind k) noexcept {
  return EnumName(k, {"dense", "lstm", "gru"});
}

std::uint32_t GateCount(LayerKind k) noexcept {
  switch (k) {
    case LayerKind::kDense: return 1;
    case LayerKind::kLstm: return 4;
    case LayerKind::kGru: return 3;
  }
  return 1;
}

std::uint32_t StateFloats(LayerKind k, std::uint32_t out) noexcept {
  switch (k) {
    case LayerKind::kDense: return 0;
    case LayerKind::kLstm: return 2 * out;
    case LayerKind::kGru: return out;
  }
  return 0;
}

std::uint64_t Layer::ParameterCount() const noexcept {
  const std::uint64_t rows = static_cast<std::uint64_t>(gates()) * out;
  const std::uint64_t n = rows * in + rows;
  return kind == LayerKind::kDense ? n : n + rows * out + rows;
}

bool ParseActivation(const std::string& s, Activation* out) noexcept {
  for (auto a :
       {Activation::kIdentity, Activation::kTanh, Activation::kElu, Activation::kRelu, Activation::kLeakyRelu}) {
    if (s == ToString(a)) {
      *out = a;
      return true;
    }
  }
  return false;
}

std::uint64_t PolicySpec::ParameterCount() const noexcept {
  std::uint64_t n = 0;
  for (const auto& l : layers) n += l.ParameterCount();
  return n;
}

bool PolicySpec::Recurrent() const noexcept {
  for (const auto& l : layers)
    if (l.kind != LayerKind::kDense) return true;
  return false;
}

std::uint64_t PolicySpec::StateSize() const noexcept {
  std::uint64_t n = 0;
  for (const auto& l : layers) n += StateFloats(l.kind, l.out);
  return n;
}

PolicySpec MakeRandomSpec(const std::vector<std::uint32_t>& widths, Activation hidden, std::uint64_t seed) {
  Rng rng(seed);
  PolicySpec s;
  if (widths.size() < 2) return s;
  s.input_size = widths.front();
  s.output_size = widths.back();
  for (std::size_t i = 0; i + 1 < widths.size(); ++i) {
    Layer l;
    l.in = widths[i];
    l.out = widths[i + 1];
    l.activation = (i + 2 == widths.size()) ? Activation::kIdentity : hidden;
    if (l.activation == Activation::kLeakyRelu) l.alpha = kRandomSpecLeakyAlpha;
    // Variance-preserving scale, so that activations stay in the interesting range.
    const double gain = 1.0 / std::sqrt(static_cast<double>(l.in));
    l.weight.resize(static_cast<std::size_t>(l.in) * l.out);
    for (float& w : l.weight) w = static_cast<float>(gain * rng.Normal());
    l.bias.resize(l.out);
    for (float& b : l.bias) b = static_cast<float>(0.1 * rng.Normal());
    s.layers.push_back(std::move(l));
  }
  s.obs_mean.resize(s.input_size);
  s.obs_inv_std.resize(s.input_size);
  for (std::uint32_t i = 0; i < s.input_size; ++i) {
    s.obs_mean[i] = static_cast<float>(0.5 * rng.Normal());
    s.obs_inv_std[i] = static_cast<float>(std::exp(0.5 * rng.Normal()));
    s.observation_names.push_back("obs" + std::to_string(i));
  }
  s.obs_clip = 5.0f;
  for (std::uint32_t i = 0; i < s.output_size; ++i) {
    s.action_scale.push_back(0.5f);
    s.action_offset.push_back(0.0f);
    s.action_low.push_back(-1.0f);
    s.action_high.push_back(1.0f);
    s.action_names.push_back("act" + std::to_string(i));
  }
  s.provenance.trainer_version = "random";
  s.provenance.environment = "none";
  s.provenance.clip_schedule = "none";
  s.provenance.seed = seed;
  return s;
}

}  // namespace pbppo::policy

namespace pbppo::policy {

PolicySpec MakeRandomRecurrentSpec(const std::vector<std::uint32_t>& widths, Activation hidden, std::size_t index,
                                   LayerKind kind, bool linear_before_reset, std::uint64_t seed) {
  PolicySpec s = MakeRandomSpec(widths, hidden, seed);
  if (index + 1 >= s.layers.size()) return s;
  Rng rng(seed ^ 0x5EC0u);
  Layer& l = s.layers[index];
  l.kind = kind;
  l.activation = Activation::kIdentity;
  l.alpha = 0.0f;
  l.linear_before_reset = kind == LayerKind::kGru && linear_before_reset;
  const std::size_t rows = static_cast<std::size_t>(l.gates()) * l.out;
  const double k = 1.0 / std::sqrt(static_cast<double>(l.out));
  auto fill = [&](std::vector<float>& v, std::size_t n) {
    v.resize(n);
    for (float& x : v) x = static_cast<float>(k * (2.0 * rng.Uniform() - 1.0));
  };
  fill(l.weight, rows * l.in);
  fill(l.bias, rows);
  fill(l.recurrent_weight, rows * l.out);
  fill(l.recurrent_bias, rows);
  return s;
}

}  // namespace pbppo::policy
