// The AVX-512 forward pass. This file alone is compiled with AVX-512 enabled and is called only
// after CpuHasAvx512() said yes; it includes nothing but intrinsics and the plain kernel view.
#include "runtime/policy/kernel_view.hpp"

#if defined(__x86_64__)
#include <immintrin.h>

namespace pbppo::policy::detail {
namespace {

inline __m512 Set(float v) {
  return _mm512_set1_ps(v);
}

// e^x for x in [-87, 88]: x = k ln2 + r, |r| <= ln2/2, degree-7 Taylor for e^r (truncation
// below 1e-8 relative) evaluated in Estrin form for a short dependency chain, then 2^k.
inline __m512 Exp(__m512 x) {
  x = _mm512_min_ps(_mm512_max_ps(x, Set(-87.0f)), Set(88.0f));
  const __m512 k =
      _mm512_roundscale_ps(_mm512_mul_ps(x, Set(1.44269504088896341f)), _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
  __m512 r = _mm512_fnmadd_ps(k, Set(0.693359375f), x);
  r = _mm512_fnmadd_ps(k, Set(-2.12194440e-4f), r);
  const __m512 r2 = _mm512_mul_ps(r, r);
  const __m512 r4 = _mm512_mul_ps(r2, r2);
  const __m512 p01 = _mm512_fmadd_ps(r, Set(1.0f), Set(1.0f));
  const __m512 p23 = _mm512_fmadd_ps(r, Set(1.0f / 6.0f), Set(0.5f));
  const __m512 p45 = _mm512_fmadd_ps(r, Set(1.0f / 120.0f), Set(1.0f / 24.0f));
  const __m512 p67 = _mm512_fmadd_ps(r, Set(1.0f / 5040.0f), Set(1.0f / 720.0f));
  const __m512 p03 = _mm512_fmadd_ps(r2, p23, p01);
  const __m512 p47 = _mm512_fmadd_ps(r2, p67, p45);
  return _mm512_scalef_ps(_mm512_fmadd_ps(r4, p47, p03), k);
}

// 1/d for d >= 1: the 14-bit estimate refined by one Newton step (about 2^-27 relative).
inline __m512 Reciprocal(__m512 d) {
  const __m512 r = _mm512_rcp14_ps(d);
  return _mm512_mul_ps(r, _mm512_fnmadd_ps(d, r, Set(2.0f)));
}

// tanh(x) = sign(x) (1 - 2 / (e^{2|x|} + 1)).
inline __m512 Tanh(__m512 x) {
  const __m512i sign_mask = _mm512_set1_epi32(static_cast<int>(0x80000000u));
  const __m512i xi = _mm512_castps_si512(x);
  const __m512 ax = _mm512_castsi512_ps(_mm512_andnot_si512(sign_mask, xi));
  const __m512 e = Exp(_mm512_add_ps(ax, ax));
  const __m512 t = _mm512_fnmadd_ps(Set(2.0f), Reciprocal(_mm512_add_ps(e, Set(1.0f))), Set(1.0f));
  return _mm512_castsi512_ps(_mm512_or_si512(_mm512_castps_si512(t), _mm512_and_si512(sign_mask, xi)));
}

inline __m512 Activate(std::uint32_t activation, float alpha, __m512 y) {
  switch (activation) {
    case 1: return Tanh(y);
    case 2: {
      const __mmask16 pos = _mm512_cmp_ps_mask(y, _mm512_setzero_ps(), _CMP_GT_OQ);
      return _mm512_mask_blend_ps(pos, _mm512_sub_ps(Exp(y), Set(1.0f)), y);
    }
    case 3: return _mm512_max_ps(y, _mm512_setzero_ps());
    case 4: {  // leaky_relu: y > 0 ? y : alpha * y (a NaN lane is not > 0 and stays NaN)
      const __mmask16 not_pos = _mm512_cmp_ps_mask(y, _mm512_setzero_ps(), _CMP_NGT_UQ);
      return _mm512_mask_mul_ps(y, not_pos, y, Set(alpha));
    }
    default: return y;
  }
}

// One tile of NV output vectors over n inputs. S independent accumulator sets over the inputs
// keep at least 8 FMA chains in flight when the tile is narrow.
// N > 0: the input count is known at compile time and the loop is unrolled completely.
template <unsigned NV, unsigned S, unsigned N = 0>
inline void Tile(const float* __restrict w, const float* __restrict bias, const float* __restrict x, std::uint32_t n_rt,
                 std::uint32_t activation, float alpha, float* __restrict y) {
  const std::uint32_t n = N > 0 ? N : n_rt;
  constexpr unsigned kW = NV * 16;
  __m512 acc[S][NV];
#pragma GCC unroll 8
  for (unsigned k = 0; k < NV; ++k) acc[0][k] = _mm512_load_ps(bias + 16 * k);
#pragma GCC unroll 4
  for (unsigned s = 1; s < S; ++s) {
#pragma GCC unroll 8
    for (unsigned k = 0; k < NV; ++k) acc[s][k] = _mm512_setzero_ps();
  }
  std::uint32_t i = 0;
#pragma GCC unroll 32
  for (; i + S <= n; i += S) {
#pragma GCC unroll 4
    for (unsigned s = 0; s < S; ++s) {
      const __m512 xb = _mm512_set1_ps(x[i + s]);
      const float* row = w + static_cast<std::size_t>(i + s) * kW;
#pragma GCC unroll 8
      for (unsigned k = 0; k < NV; ++k) acc[s][k] = _mm512_fmadd_ps(_mm512_load_ps(row + 16 * k), xb, acc[s][k]);
    }
  }
  for (; i < n; ++i) {
    const __m512 xb = _mm512_set1_ps(x[i]);
    const float* row = w + static_cast<std::size_t>(i) * kW;
#pragma GCC unroll 8
    for (unsigned k = 0; k < NV; ++k) acc[0][k] = _mm512_fmadd_ps(_mm512_load_ps(row + 16 * k), xb, acc[0][k]);
  }
  // Pairwise reduction of the accumulator sets: log2(S) dependent adds.
#pragma GCC unroll 4
  for (unsigned step = 1; step < S; step *= 2) {
#pragma GCC unroll 8
    for (unsigned s = 0; s + step < S; s += 2 * step) {
#pragma GCC unroll 8
      for (unsigned k = 0; k < NV; ++k) acc[s][k] = _mm512_add_ps(acc[s][k], acc[s + step][k]);
    }
  }
#pragma GCC unroll 8
  for (unsigned k = 0; k < NV; ++k) _mm512_store_ps(y + 16 * k, Activate(activation, alpha, acc[0][k]));
}

// Narrow layers (out <= kRowFormMaxOut): one dot product per output over row-major weights
// [out][in_pad], reduced horizontally; far shorter than a 16-wide tile of mostly padding.
void DenseRows(const KernelLayer& l, const float* x, float* y) {
  const std::uint32_t in_pad = (l.in + 15) / 16 * 16;
  float out[16] __attribute__((aligned(64))) = {};
  for (std::uint32_t j = 0; j < l.out; ++j) {
    const float* row = l.weight + static_cast<std::size_t>(j) * in_pad;
    __m512 a0 = _mm512_setzero_ps(), a1 = _mm512_setzero_ps();
    std::uint32_t i = 0;
    for (; i + 32 <= in_pad; i += 32) {
      a0 = _mm512_fmadd_ps(_mm512_load_ps(row + i), _mm512_load_ps(x + i), a0);
      a1 = _mm512_fmadd_ps(_mm512_load_ps(row + i + 16), _mm512_load_ps(x + i + 16), a1);
    }
    if (i < in_pad) a0 = _mm512_fmadd_ps(_mm512_load_ps(row + i), _mm512_load_ps(x + i), a0);
    out[j] = _mm512_reduce_add_ps(_mm512_add_ps(a0, a1));
  }
  _mm512_store_ps(y, Activate(l.activation, l.alpha, _mm512_add_ps(_mm512_load_ps(out), _mm512_load_ps(l.bias))));
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
    const float* b = l.bias + 16 * v0;
    float* out = y + 16 * v0;
    switch (nv) {
      case 1: Tile<1, 8>(w, b, x, l.in, l.activation, l.alpha, out); break;
      case 2: Tile<2, 4>(w, b, x, l.in, l.activation, l.alpha, out); break;
      case 3: Tile<3, 2>(w, b, x, l.in, l.activation, l.alpha, out); break;
      case 4:
        if (l.in == 64) {
          Tile<4, 2, 64>(w, b, x, l.in, l.activation, l.alpha, out);
        } else if (l.in == 24) {
          Tile<4, 2, 24>(w, b, x, l.in, l.activation, l.alpha, out);
        } else {
          Tile<4, 2>(w, b, x, l.in, l.activation, l.alpha, out);
        }
        break;
      case 5: Tile<5, 1>(w, b, x, l.in, l.activation, l.alpha, out); break;
      case 6: Tile<6, 1>(w, b, x, l.in, l.activation, l.alpha, out); break;
      case 7: Tile<7, 1>(w, b, x, l.in, l.activation, l.alpha, out); break;
      default: Tile<8, 1>(w, b, x, l.in, l.activation, l.alpha, out); break;
    }
    w += static_cast<std::size_t>(l.in) * nv * 16;
  }
}

constexpr int kNonFiniteClass = 0x01 | 0x80 | 0x08 | 0x10;  // QNaN, SNaN, +Inf, -Inf

}  // namespace

std::uint32_t ForwardAvx512(const ModelView& m, const DataView& d) noexcept {
  // Normalise and check the observation, 16 at a time (padding lanes are zero).
  const __m512 clip = Set(m.obs_clip), nclip = Set(-m.obs_clip);
  __mmask16 bad = 0;
  for (std::uint32_t i = 0; i < m.input_pad; i += 16) {
    const __m512 o = _mm512_load_ps(d.observation + i);
    bad |= _mm512_fpclass_ps_mask(o, kNonFiniteClass);
    const __m512 v = _mm512_mul_ps(_mm512_sub_ps(o, _mm512_load_ps(m.obs_mean + i)), _mm512_load_ps(m.obs_inv_std + i));
    _mm512_store_ps(d.x + i, _mm512_min_ps(_mm512_max_ps(v, nclip), clip));
  }
  const __m512 qnan = _mm512_castsi512_ps(_mm512_set1_epi32(0x7FC00000));
  if (bad) {
    for (std::uint32_t i = 0; i < m.output_pad; i += 16) _mm512_store_ps(d.action + i, qnan);
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

  __mmask16 bad_action = 0;
  for (std::uint32_t i = 0; i < m.output_pad; i += 16) {
    __m512 a = _mm512_load_ps(src + i);
    if (m.action_head == 1) a = Tanh(a);
    a = _mm512_fmadd_ps(a, _mm512_load_ps(m.action_scale + i), _mm512_load_ps(m.action_offset + i));
    const __mmask16 nf = _mm512_fpclass_ps_mask(a, kNonFiniteClass);
    a = _mm512_min_ps(_mm512_max_ps(a, _mm512_load_ps(m.action_low + i)), _mm512_load_ps(m.action_high + i));
    a = _mm512_mask_blend_ps(nf, a, qnan);
    const std::uint32_t valid = m.output_size - i;
    const __mmask16 live = valid >= 16 ? static_cast<__mmask16>(0xFFFF) : static_cast<__mmask16>((1u << valid) - 1u);
    bad_action |= static_cast<__mmask16>(nf & live);
    _mm512_store_ps(d.action + i, a);
  }
  return bad_action ? kBadAction : 0u;
}

bool CpuHasAvx512() noexcept {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
         __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
}

}  // namespace pbppo::policy::detail

#else  // not x86-64: no AVX-512 path

namespace pbppo::policy::detail {
std::uint32_t ForwardAvx512(const ModelView& m, const DataView& d) noexcept {
  return ForwardPortable(m, d);
}
bool CpuHasAvx512() noexcept {
  return false;
}
}  // namespace pbppo::policy::detail

#endif
