// The complete description of a frozen policy, as the trainer builds it and the blob stores it.
// Set-up-time data: vectors and strings. The runtime repacks it into a PolicyModel.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace pbppo::policy {

// A limit given in double, held in float32 on its inside: the nearest float not below `low`, not
// above `high`. A blob clamps its commands to float limits; rounded to nearest, a limit such as
// -0.83776 becomes -0.8377599716, just above the double limit the supervisor checks, so a policy
// at its joint limit would send a command "beyond" it.
inline float FloatNotBelow(double low) noexcept {
  const float f = static_cast<float>(low);
  return static_cast<double>(f) < low ? std::nextafter(f, HUGE_VALF) : f;
}
inline float FloatNotAbove(double high) noexcept {
  const float f = static_cast<float>(high);
  return static_cast<double>(f) > high ? std::nextafter(f, -HUGE_VALF) : f;
}

// kLeakyRelu: x > 0 ? x : alpha * x, with the layer's alpha (the negative slope) in [0, 1].
enum class Activation : std::uint32_t { kIdentity = 0, kTanh = 1, kElu = 2, kRelu = 3, kLeakyRelu = 4 };
// The deterministic action head applied to the last layer's output (the Gaussian mean).
enum class ActionHead : std::uint32_t { kLinear = 0, kTanh = 1 };

// What a layer computes. kDense: y = act(W x + b). The recurrent kinds keep a state between
// forward passes (PolicyData's, zero at the start) and follow the ONNX LSTM and GRU operators
// with their default activations (sigmoid, tanh), one direction, no peepholes, no clip:
// - kLstm, gates in ONNX's order i, o, f, c (each `out` rows of weight, bias, recurrent_*):
//     g = W x + Wb + R h + Rb;  i = sigmoid(g_i), o = sigmoid(g_o), f = sigmoid(g_f), u = tanh(g_c)
//     c' = f * c + i * u;  h' = o * tanh(c');  y = h'  (state: h, c)
// - kGru, gates in ONNX's order z, r, h:
//     z = sigmoid(W_z x + Wb_z + R_z h + Rb_z);  r = sigmoid(W_r x + Wb_r + R_r h + Rb_r)
//     n = tanh(W_h x + Wb_h + R_h (r * h) + Rb_h)            (linear_before_reset false)
//     n = tanh(W_h x + Wb_h + r * (R_h h + Rb_h))            (linear_before_reset true: torch's)
//     h' = (1 - z) * n + z * h;  y = h'  (state: h)
enum class LayerKind : std::uint32_t { kDense = 0, kLstm = 1, kGru = 2 };

const char* ToString(Activation a) noexcept;
const char* ToString(ActionHead h) noexcept;
const char* ToString(LayerKind k) noexcept;
bool ParseActivation(const std::string& s, Activation* out) noexcept;

// Rows of weight and bias per output: 1 for a dense layer, 4 for an LSTM, 3 for a GRU.
std::uint32_t GateCount(LayerKind k) noexcept;
// Floats of state a layer carries between forward passes: 0 dense, 2 * out LSTM (h, c), out GRU.
std::uint32_t StateFloats(LayerKind k, std::uint32_t out) noexcept;

struct Layer {
  LayerKind kind = LayerKind::kDense;
  std::uint32_t in = 0;
  std::uint32_t out = 0;  // a recurrent layer's hidden size
  // The output's activation: any for a dense layer, kIdentity for a recurrent one.
  Activation activation = Activation::kIdentity;
  // The negative slope of kLeakyRelu, in [0, 1] (so the activation stays 1-Lipschitz); must be
  // 0 for every other activation.
  float alpha = 0.0f;
  std::vector<float> weight;            // row-major [gates * out][in]
  std::vector<float> bias;              // [gates * out]
  std::vector<float> recurrent_weight;  // row-major [gates * out][out]; empty for a dense layer
  std::vector<float> recurrent_bias;    // [gates * out]; empty for a dense layer
  bool linear_before_reset = false;     // kGru only (see LayerKind)

  std::uint32_t gates() const noexcept { return GateCount(kind); }
  std::uint64_t ParameterCount() const noexcept;
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
  std::vector<Layer> layers;
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
  bool Recurrent() const noexcept;
  // Floats of state all layers carry (StateFloats summed).
  std::uint64_t StateSize() const noexcept;
};

// A spec with the given layer widths (input first, output last), hidden activation and
// Gaussian-random weights from `seed`; identity normaliser and action map, generated names.
// Hidden kLeakyRelu layers get alpha = kRandomSpecLeakyAlpha.
// For benchmarks, tests and latency work on shapes that have no trained policy yet.
inline constexpr float kRandomSpecLeakyAlpha = 0.01f;
PolicySpec MakeRandomSpec(const std::vector<std::uint32_t>& widths, Activation hidden, std::uint64_t seed);
// The same with layer `index` (0-based, not the last) made a recurrent layer of `kind`, its width
// the hidden size, weights uniform in +-1/sqrt(hidden) as torch initialises them.
PolicySpec MakeRandomRecurrentSpec(const std::vector<std::uint32_t>& widths, Activation hidden, std::size_t index,
                                   LayerKind kind, bool linear_before_reset, std::uint64_t seed);

}  // namespace pbppo::policy
