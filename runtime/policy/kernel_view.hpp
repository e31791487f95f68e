// Plain views of a model's parameters and a data's buffers, shared by the forward kernels.
// Kept free of standard-library types so that kernels compiled for other instruction sets
// (forward_avx512.cpp) include nothing they could emit an incompatible inline copy of.
#pragma once

#include <cstdint>

namespace pbppo::policy::detail {

inline constexpr std::uint32_t kLanes = 16;         // floats per 64-byte vector
inline constexpr std::uint32_t kTileVectors = 8;    // output vectors per AVX-512 tile
inline constexpr std::uint32_t kRowFormMaxOut = 4;  // packed: narrower layers use row dot products

struct KernelLayer {
  // portable: row-major [out][in]; avx512 and neon (the packed layout): tiles
  // [tile][in][vectors*16], or for layers of at most kRowFormMaxOut outputs row-major
  // [out][in rounded up to 16], zero-padded
  const float* weight;
  const float* bias;  // [out_pad], zero beyond out
  std::uint32_t in;
  std::uint32_t out;
  std::uint32_t out_pad;  // out rounded up to 16
  std::uint32_t activation;
  float alpha;  // leaky_relu (activation 4): y = x > 0 ? x : alpha * x; 0 otherwise
  // Recurrent layers (kind 1 LSTM, 2 GRU; policy_spec.hpp's LayerKind) run as dense parts with the
  // identity activation, each laid out as above, and an element-wise step (RecurrentStep):
  // parts[0] = W x + Wb (in -> gates * out); LSTM parts[1] = R h + Rb (out -> 4 out); GRU
  // parts[1] = R_zr h + Rb_zr (out -> 2 out), parts[2] = R_h (r * h or h) + Rb_h (out -> out).
  // A dense layer (kind 0) has none; its weight and bias are the fields above.
  std::uint32_t kind;
  std::uint32_t linear_before_reset;  // GRU: 1 as torch exports it
  const KernelLayer* parts;
  std::uint32_t state;  // the layer's state in DataView::state, in floats: h [out_pad], LSTM c [out_pad]
};

struct ModelView {
  const KernelLayer* layers;
  std::uint32_t layer_count;
  std::uint32_t input_size;
  std::uint32_t input_pad;
  std::uint32_t output_size;
  std::uint32_t output_pad;
  std::uint32_t action_head;
  float obs_clip;
  const float* obs_mean;       // [input_pad], zero beyond input
  const float* obs_inv_std;    // [input_pad], zero beyond input
  const float* action_scale;   // [output_pad]
  const float* action_offset;  // [output_pad]
  const float* action_low;     // [output_pad]
  const float* action_high;    // [output_pad]
};

struct DataView {
  float* observation;  // [input_pad], caller writes the first input_size
  float* x;            // [input_pad] normalised observation
  float* ping;         // [max_width_pad]
  float* pong;         // [max_width_pad]
  float* action;       // [output_pad]
  // Recurrent layers only (null or unused otherwise): their state (zero at the start, kept between
  // calls; padding stays zero) and scratch for the gates, each aligned and zero-padded.
  float* state;  // [sum of the layers' state floats]
  float* gx;     // [max gates * out, padded]
  float* gh;     // [max gates * out, padded]
  float* rh;     // [max out_pad]: GRU r * h
  float* gt;     // [max out_pad]: GRU R_h (.) + Rb_h
};

// A kernel's dense layer: y[0, out_pad) = act(W x + b) in that kernel's layout, x zero-padded.
using DenseFn = void (*)(const KernelLayer& l, const float* x, float* y);

// One step of recurrent layer l (forward_recurrent.cpp, shared by every kernel): its dense parts
// through the kernel's `dense`, the gates element-wise (Eigen arrays), the state updated in place,
// y[0, out) = the new h and y[out, out_pad) = 0.
void RecurrentStep(const KernelLayer& l, const float* x, float* y, const DataView& d, DenseFn dense) noexcept;

// Return value of a kernel: bit 0 non-finite observation, bit 1 non-finite action.
inline constexpr std::uint32_t kBadObservation = 1u;
inline constexpr std::uint32_t kBadAction = 2u;

std::uint32_t ForwardPortable(const ModelView& m, const DataView& d) noexcept;
std::uint32_t ForwardAvx512(const ModelView& m, const DataView& d) noexcept;
bool CpuHasAvx512() noexcept;
std::uint32_t ForwardNeon(const ModelView& m, const DataView& d) noexcept;  // aarch64 (forward_neon.cpp)

}  // namespace pbppo::policy::detail
