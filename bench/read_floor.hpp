// The memory-read floor of a forward pass: the time to merely stream a model's parameters once
// from where they live, the bound no kernel beats. Shared by pbppo_bench_inference (timed per
// call with the CPU's counter) and pbppo_bench_tick (per tick, beside the loop's infer stage).
#pragma once

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include <cstddef>
#include <vector>

namespace pbppo::bench {

// Reads `n` floats once (eight independent sums, vectorised by the compiler): the time a
// forward pass would take if it did nothing but stream its parameters from where they live.
__attribute__((noinline)) inline float StreamOnce(const float* p, std::size_t n) {
  float acc[32] = {};
  for (std::size_t i = 0; i + 32 <= n; i += 32) {
    for (std::size_t k = 0; k < 32; ++k) acc[k] += p[i + k];
  }
  float s = 0;
  for (float a : acc) s += a;
  return s;
}

#if defined(__x86_64__)
// The same read with eight AVX-512 registers and aligned 64-byte loads (n a multiple of 32):
// on AVX-512 machines the fastest plain read found here, about 10 % faster than the loop above.
__attribute__((noinline, target("avx512f"))) inline float StreamOnceAvx512(const float* p, std::size_t n) {
  __m512 a0 = _mm512_setzero_ps(), a1 = a0, a2 = a0, a3 = a0, a4 = a0, a5 = a0, a6 = a0, a7 = a0;
  std::size_t i = 0;
  for (; i + 128 <= n; i += 128) {
    a0 = _mm512_add_ps(a0, _mm512_load_ps(p + i));
    a1 = _mm512_add_ps(a1, _mm512_load_ps(p + i + 16));
    a2 = _mm512_add_ps(a2, _mm512_load_ps(p + i + 32));
    a3 = _mm512_add_ps(a3, _mm512_load_ps(p + i + 48));
    a4 = _mm512_add_ps(a4, _mm512_load_ps(p + i + 64));
    a5 = _mm512_add_ps(a5, _mm512_load_ps(p + i + 80));
    a6 = _mm512_add_ps(a6, _mm512_load_ps(p + i + 96));
    a7 = _mm512_add_ps(a7, _mm512_load_ps(p + i + 112));
  }
  for (; i + 16 <= n; i += 16) a0 = _mm512_add_ps(a0, _mm512_load_ps(p + i));
  const __m512 s = _mm512_add_ps(_mm512_add_ps(_mm512_add_ps(a0, a1), _mm512_add_ps(a2, a3)),
                                 _mm512_add_ps(_mm512_add_ps(a4, a5), _mm512_add_ps(a6, a7)));
  alignas(64) float lanes[16];
  _mm512_store_ps(lanes, s);
  float sum = 0;
  for (float v : lanes) sum += v;
  return sum;
}
#endif

using StreamFn = float (*)(const float*, std::size_t);

// The plain readers this machine runs; the floor is the faster of them.
inline std::vector<StreamFn> StreamReaders() {
  std::vector<StreamFn> readers = {StreamOnce};
#if defined(__x86_64__)
  if (__builtin_cpu_supports("avx512f")) readers.push_back(StreamOnceAvx512);
#endif
  return readers;
}

}  // namespace pbppo::bench
