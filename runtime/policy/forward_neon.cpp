// The NEON (AArch64 Advanced SIMD) forward pass. It reads the same packed weights as the AVX-512
// kernel (kernel_view.hpp: tiles of up to 8 output vectors of 16 floats over all inputs; layers of
// at most kRowFormMaxOut outputs as zero-padded rows), four 128-bit registers per 16-float vector.
// Advanced SIMD is part of every ARMv8-A CPU, so on aarch64 this kernel is always available; on
// other targets the entry point falls back to the portable kernel and is never chosen.
#include "runtime/policy/kernel_view.hpp"

#if defined(__aarch64__)
#include <arm_neon.h>

namespace pbppo::policy::detail {
namespace {

inline float32x4_t Set(float v) {
  return vdupq_n_f32(v);
}

// e^x for x in [-87, 88]: x = k ln2 + r, |r| <= ln2/2, degree-7 Taylor for e^r (truncation
// below 1e-8 relative) in Estrin form, times 2^k built in the exponent field (k in [-126, 127]).
inline float32x4_t Exp(float32x4_t x) {
  x = vminq_f32(vmaxq_f32(x, Set(-87.0f)), Set(88.0f));
  const float32x4_t k = vrndnq_f32(vmulq_f32(x, Set(1.44269504088896341f)));
  float32x4_t r = vfmsq_f32(x, k, Set(0.693359375f));
  r = vfmsq_f32(r, k, Set(-2.12194440e-4f));
  const float32x4_t r2 = vmulq_f32(r, r);
  const float32x4_t r4 = vmulq_f32(r2, r2);
  const float32x4_t p01 = vfmaq_f32(Set(1.0f), r, Set(1.0f));
  const float32x4_t p23 = vfmaq_f32(Set(0.5f), r, Set(1.0f / 6.0f));
  const float32x4_t p45 = vfmaq_f32(Set(1.0f / 24.0f), r, Set(1.0f / 120.0f));
  const float32x4_t p67 = vfmaq_f32(Set(1.0f / 720.0f), r, Set(1.0f / 5040.0f));
  const float32x4_t p03 = vfmaq_f32(p01, r2, p23);
  const float32x4_t p47 = vfmaq_f32(p45, r2, p67);
  const float32x4_t p = vfmaq_f32(p03, r4, p47);
  const int32x4_t bits = vshlq_n_s32(vaddq_s32(vcvtq_s32_f32(k), vdupq_n_s32(127)), 23);
  return vmulq_f32(p, vreinterpretq_f32_s32(bits));
}

// tanh(x) = sign(x) (1 - 2 / (e^{2|x|} + 1)); a NaN stays NaN.
inline float32x4_t Tanh(float32x4_t x) {
  const uint32x4_t sign = vandq_u32(vreinterpretq_u32_f32(x), vdupq_n_u32(0x80000000u));
  const float32x4_t ax = vabsq_f32(x);
  const float32x4_t e = Exp(vaddq_f32(ax, ax));
  const float32x4_t t = vsubq_f32(Set(1.0f), vdivq_f32(Set(2.0f), vaddq_f32(e, Set(1.0f))));
  const float32x4_t y = vreinterpretq_f32_u32(vorrq_u32(vreinterpretq_u32_f32(t), sign));
  return vbslq_f32(vceqq_f32(x, x), y, x);
}

inline float32x4_t Activate(std::uint32_t activation, float alpha, float32x4_t y) {
  switch (activation) {
    case 1: return Tanh(y);
    case 2: return vbslq_f32(vcgtq_f32(y, Set(0.0f)), y, vsubq_f32(Exp(y), Set(1.0f)));  // NaN: exp(NaN) - 1
    case 3: return vmaxq_f32(y, Set(0.0f));
    case 4: return vbslq_f32(vcgtq_f32(y, Set(0.0f)), y, vmulq_f32(y, Set(alpha)));  // NaN: alpha * NaN
    default: return y;
  }
}

// CB 16-float vectors (4 CB registers) of a tile whose rows are kW floats long, over n inputs.
// S independent accumulator sets keep at least 8 FMA chains in flight when CB is small.
template <unsigned CB, unsigned S>
inline void Block(const float* __restrict w, std::uint32_t kW, const float* __restrict bias, const float* __restrict x,
                  std::uint32_t n, std::uint32_t activation, float alpha, float* __restrict y) {
  constexpr unsigned kR = CB * 4;
  float32x4_t acc[S][kR];
#pragma GCC unroll 16
  for (unsigned k = 0; k < kR; ++k) acc[0][k] = vld1q_f32(bias + 4 * k);
#pragma GCC unroll 4
  for (unsigned s = 1; s < S; ++s) {
#pragma GCC unroll 16
    for (unsigned k = 0; k < kR; ++k) acc[s][k] = Set(0.0f);
  }
  std::uint32_t i = 0;
  for (; i + S <= n; i += S) {
#pragma GCC unroll 4
    for (unsigned s = 0; s < S; ++s) {
      const float32x4_t xb = vdupq_n_f32(x[i + s]);
      const float* row = w + static_cast<std::size_t>(i + s) * kW;
#pragma GCC unroll 16
      for (unsigned k = 0; k < kR; ++k) acc[s][k] = vfmaq_f32(acc[s][k], vld1q_f32(row + 4 * k), xb);
    }
  }
  for (; i < n; ++i) {
    const float32x4_t xb = vdupq_n_f32(x[i]);
    const float* row = w + static_cast<std::size_t>(i) * kW;
#pragma GCC unroll 16
    for (unsigned k = 0; k < kR; ++k) acc[0][k] = vfmaq_f32(acc[0][k], vld1q_f32(row + 4 * k), xb);
  }
#pragma GCC unroll 4
  for (unsigned step = 1; step < S; step *= 2) {
#pragma GCC unroll 4
    for (unsigned s = 0; s + step < S; s += 2 * step) {
#pragma GCC unroll 16
      for (unsigned k = 0; k < kR; ++k) acc[s][k] = vaddq_f32(acc[s][k], acc[s + step][k]);
    }
  }
#pragma GCC unroll 16
  for (unsigned k = 0; k < kR; ++k) vst1q_f32(y + 4 * k, Activate(activation, alpha, acc[0][k]));
}

// Narrow layers (out <= kRowFormMaxOut): one dot product per output over rows [out][in_pad].
void DenseRows(const KernelLayer& l, const float* x, float* y) {
  const std::uint32_t in_pad = (l.in + 15) / 16 * 16;
  float out[16] __attribute__((aligned(64))) = {};
  for (std::uint32_t j = 0; j < l.out; ++j) {
    const float* row = l.weight + static_cast<std::size_t>(j) * in_pad;
    float32x4_t a0 = Set(0.0f), a1 = Set(0.0f), a2 = Set(0.0f), a3 = Set(0.0f);
    for (std::uint32_t i = 0; i < in_pad; i += 16) {
      a0 = vfmaq_f32(a0, vld1q_f32(row + i), vld1q_f32(x + i));
      a1 = vfmaq_f32(a1, vld1q_f32(row + i + 4), vld1q_f32(x + i + 4));
      a2 = vfmaq_f32(a2, vld1q_f32(row + i + 8), vld1q_f32(x + i + 8));
      a3 = vfmaq_f32(a3, vld1q_f32(row + i + 12), vld1q_f32(x + i + 12));
    }
    out[j] = vaddvq_f32(vaddq_f32(vaddq_f32(a0, a1), vaddq_f32(a2, a3)));
  }
#pragma GCC unroll 4
  for (unsigned k = 0; k < 4; ++k)
    vst1q_f32(y + 4 * k, Activate(l.activation, l.alpha, vaddq_f32(vld1q_f32(out + 4 * k), vld1q_f32(l.bias + 4 * k))));
}

void Dense(const KernelLayer& l, const float* x, float* y) {
  if (l.out <= kRowFormMaxOut) {
    DenseRows(l, x, y);
    return;
  }
  const std::uint32_t vectors = l.out_pad / 16;
  const float* w = l.weight;
  for (std::uint32_t v0 = 0; v0 < vectors; v0 += kTileVectors) {
    const std::uint32_t nv = vectors - v0 < kTileVectors ? vectors - v0 : kTileVectors;
    const std::uint32_t kW = nv * 16;
    // The tile's columns in blocks of up to 4 vectors: 16 accumulators of the 32 registers.
    for (std::uint32_t c = 0; c < nv; c += 4) {
      const std::uint32_t cb = nv - c < 4 ? nv - c : 4;
      const float* wc = w + 16 * c;
      const float* b = l.bias + 16 * (v0 + c);
      float* out = y + 16 * (v0 + c);
      switch (cb) {
        case 1: Block<1, 2>(wc, kW, b, x, l.in, l.activation, l.alpha, out); break;
        case 2: Block<2, 2>(wc, kW, b, x, l.in, l.activation, l.alpha, out); break;
        case 3: Block<3, 1>(wc, kW, b, x, l.in, l.activation, l.alpha, out); break;
        default: Block<4, 1>(wc, kW, b, x, l.in, l.activation, l.alpha, out); break;
      }
    }
    w += static_cast<std::size_t>(l.in) * kW;
  }
}

// All ones in a lane whose value is finite (v - v is 0 only for finite v).
inline uint32x4_t Finite(float32x4_t v) {
  return vceqq_f32(vsubq_f32(v, v), Set(0.0f));
}

}  // namespace

std::uint32_t ForwardNeon(const ModelView& m, const DataView& d) noexcept {
  // Normalise and check the observation, 4 at a time (padding lanes are zero).
  const float32x4_t clip = Set(m.obs_clip), nclip = Set(-m.obs_clip);
  uint32x4_t finite = vdupq_n_u32(0xFFFFFFFFu);
  for (std::uint32_t i = 0; i < m.input_pad; i += 4) {
    const float32x4_t o = vld1q_f32(d.observation + i);
    finite = vandq_u32(finite, Finite(o));
    const float32x4_t v = vmulq_f32(vsubq_f32(o, vld1q_f32(m.obs_mean + i)), vld1q_f32(m.obs_inv_std + i));
    vst1q_f32(d.x + i, vminq_f32(vmaxq_f32(v, nclip), clip));
  }
  const float32x4_t qnan = vreinterpretq_f32_u32(vdupq_n_u32(0x7FC00000u));
  if (vminvq_u32(finite) == 0) {
    for (std::uint32_t i = 0; i < m.output_pad; i += 4) vst1q_f32(d.action + i, qnan);
    return kBadObservation;
  }

  const float* src = d.x;
  float* dst = d.ping;
  for (std::uint32_t li = 0; li < m.layer_count; ++li) {
    const KernelLayer& l = m.layers[li];
    if (l.kind == 0) {
      Dense(l, src, dst);
    } else {
      RecurrentStep(l, src, dst, d, &Dense);
    }
    src = dst;
    dst = (dst == d.ping) ? d.pong : d.ping;
  }

  std::uint32_t bad = 0;
  for (std::uint32_t i = 0; i < m.output_pad; i += 4) {
    float32x4_t a = vld1q_f32(src + i);
    if (m.action_head == 1) a = Tanh(a);
    a = vfmaq_f32(vld1q_f32(m.action_offset + i), a, vld1q_f32(m.action_scale + i));
    const uint32x4_t ok = Finite(a);
    a = vminq_f32(vmaxq_f32(a, vld1q_f32(m.action_low + i)), vld1q_f32(m.action_high + i));
    a = vbslq_f32(ok, a, qnan);
    // Only the live lanes (below output_size) count.
    const std::uint32_t valid = m.output_size > i ? m.output_size - i : 0;
    static constexpr std::uint32_t kLane[4] = {0u, 1u, 2u, 3u};
    const uint32x4_t live = vcltq_u32(vld1q_u32(kLane), vdupq_n_u32(valid));
    if (vmaxvq_u32(vbicq_u32(live, ok)) != 0) bad = kBadAction;
    vst1q_f32(d.action + i, a);
  }
  return bad;
}

}  // namespace pbppo::policy::detail

#else  // not aarch64: no NEON path

namespace pbppo::policy::detail {
std::uint32_t ForwardNeon(const ModelView& m, const DataView& d) noexcept {
  return ForwardPortable(m, d);
}
}  // namespace pbppo::policy::detail

#endif
