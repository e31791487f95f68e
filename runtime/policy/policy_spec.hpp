// The complete description of a frozen policy, as the trainer builds it and the blob stores it.
// Set-up-time data: vectors and strings. The runtime repacks it into a PolicyModel.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace pbppo::policy {

// kLeakyRelu: x > 0 ? x : alpha * x, with the layer's alpha (the negative slope) in [0, 1].
enum class Activation : std::uint32_t { kIdentity = 0, kTanh = 1, kElu = 2, kRelu = 3, kLeakyRelu = 4 };
// The deterministic action head applied to the last layer's output (the Gaussian mean).
enum class ActionHead : std::uint32_t { kLinear = 0, kTanh = 1 };

const char* ToString(Activation a) noexcept;
const char* ToString(ActionHead h) noexcept;
bool ParseActivation(const std::string& s, Activation* out) noexcept;

struct DenseLayer {
  std::uint32_t in = 0;
  std::uint32_t out = 0;
  Activation activation = Activation::kIdentity;
  // The negative slope of kLeakyRelu, in [0, 1] (so the activation stays 1-Lipschitz); must be
  // 0 for every other activation.
  float alpha = 0.0f;
  std::vector<float> weight;  // row-major [out][in]
  std::vector<float> bias;    // [out]
};

struct Provenance {
  std::string trainer_version;
  std::string git_revision;
  std::string environment;
  std::string clip_schedule;
  std::uint64_t seed = 0;
  std::uint64_t env_steps = 0;
  double final_return = 0.0;
};

struct PolicySpec {
  std::uint32_t input_size = 0;
  std::uint32_t output_size = 0;
  // Observation normaliser: x = clamp((obs - mean) * inv_std, -clip, clip).
  std::vector<float> obs_mean;
  std::vector<float> obs_inv_std;
  float obs_clip = 10.0f;
  std::vector<DenseLayer> layers;
  ActionHead action_head = ActionHead::kLinear;
  // Action map: action = clamp(head(y) * scale + offset, low, high).
  std::vector<float> action_scale;
  std::vector<float> action_offset;
  std::vector<float> action_low;
  std::vector<float> action_high;
  // The robot IO layout this policy was trained for.
  std::uint64_t io_layout_hash = 0;
  std::vector<std::string> observation_names;
  std::vector<std::string> action_names;
  Provenance provenance;

  std::uint64_t ParameterCount() const noexcept;
};

// A spec with the given layer widths (input first, output last), hidden activation and
// Gaussian-random weights from `seed`; identity normaliser and action map, generated names.
// Hidden kLeakyRelu layers get alpha = kRandomSpecLeakyAlpha.
// For benchmarks, tests and latency work on shapes that have no trained policy yet.
inline constexpr float kRandomSpecLeakyAlpha = 0.01f;
PolicySpec MakeRandomSpec(const std::vector<std::uint32_t>& widths, Activation hidden, std::uint64_t seed);

}  // namespace pbppo::policy
