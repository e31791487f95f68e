// Single-call latency of the policy forward pass on the reference shapes.
//
//   pbppo_bench_inference [--calls N] [--kernel auto|portable|avx512|neon|all] [--per-sample N] [--json FILE]
//
// Each call is timed on its own with the CPU's counter (x86-64: the time-stamp counter, serialising
// reads; aarch64: the generic timer's virtual count, between instruction barriers), the median
// cost of an empty timed region is subtracted, and the distribution over N calls is reported
// with the allocations per call and the weight-streaming bound: parameter bytes / the bytes one
// core loads per cycle (64 with AVX-512 registers, 32 with two 16-byte NEON loads) at the core
// clock measured here. Where the counter ticks too slowly to time one call (the generic timer of
// an ARM board runs at 19-1000 MHz), each timed sample runs a fixed number of calls and the
// figures are per call; the header says how many.
#if defined(__x86_64__)
#include <immintrin.h>
#include <x86intrin.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench/read_floor.hpp"
#include "runtime/core/aligned_arena.hpp"
#include "runtime/core/alloc_probe.hpp"
#include "runtime/core/random.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/policy_model.hpp"

using namespace pbppo::policy;

namespace {

struct Shape {
  const char* name;
  std::vector<std::uint32_t> widths;
  Activation act;
  double target_us;                     // 0: no target (measured beside the others)
  LayerKind first = LayerKind::kDense;  // a recurrent first layer: its width is the hidden size
};

#if defined(__x86_64__)
constexpr const char* kCounter = "TSC";
constexpr double kLoadBytesPerCycle = 64.0;
inline std::uint64_t Stamp() noexcept {
  unsigned aux;
  _mm_lfence();
  const std::uint64_t t = __rdtscp(&aux);
  _mm_lfence();
  return t;
}
#elif defined(__aarch64__)
constexpr const char* kCounter = "cntvct";
constexpr double kLoadBytesPerCycle = 32.0;
inline std::uint64_t Stamp() noexcept {
  std::uint64_t t;
  asm volatile("isb\n\tmrs %0, cntvct_el0\n\tisb" : "=r"(t) : : "memory");
  return t;
}
#else
#error "pbppo_bench_inference: a cycle counter for this architecture is missing (x86-64 and aarch64 have one)"
#endif

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Time-stamp-counter ticks per second, against the steady clock over 200 ms.
double TscHz() {
  const double t0 = Now();
  const std::uint64_t c0 = Stamp();
  while (Now() - t0 < 0.2) {
  }
  const double t1 = Now();
  const std::uint64_t c1 = Stamp();
  return static_cast<double>(c1 - c0) / (t1 - t0);
}

// Core clock: a chain of dependent register-register adds runs at one per cycle (adds of an
// immediate are not used: recent cores fold those chains at rename). Median of 5.
double CoreHz() {
  std::vector<double> hz;
  for (int rep = 0; rep < 5; ++rep) {
    const long iters = 20'000'000;
    std::uint64_t x = 0;
    const std::uint64_t step = 3;
    const double t0 = Now();
    for (long i = 0; i < iters; ++i) {
#if defined(__x86_64__)
      asm volatile(
          "add %1, %0\n\tadd %1, %0\n\tadd %1, %0\n\tadd %1, %0\n\t"
          "add %1, %0\n\tadd %1, %0\n\tadd %1, %0\n\tadd %1, %0\n\t"
          "add %1, %0\n\tadd %1, %0\n\tadd %1, %0\n\tadd %1, %0\n\t"
          "add %1, %0\n\tadd %1, %0\n\tadd %1, %0\n\tadd %1, %0"
          : "+r"(x)
          : "r"(step));
#else
      asm volatile(
          "add %0, %0, %1\n\tadd %0, %0, %1\n\tadd %0, %0, %1\n\tadd %0, %0, %1\n\t"
          "add %0, %0, %1\n\tadd %0, %0, %1\n\tadd %0, %0, %1\n\tadd %0, %0, %1\n\t"
          "add %0, %0, %1\n\tadd %0, %0, %1\n\tadd %0, %0, %1\n\tadd %0, %0, %1\n\t"
          "add %0, %0, %1\n\tadd %0, %0, %1\n\tadd %0, %0, %1\n\tadd %0, %0, %1"
          : "+r"(x)
          : "r"(step));
#endif
    }
    hz.push_back(16.0 * static_cast<double>(iters) / (Now() - t0));
  }
  std::sort(hz.begin(), hz.end());
  return hz[2];
}

struct Stats {
  double median, p99, p999, max, mean;
};

Stats Summarise(std::vector<double>& v) {
  std::sort(v.begin(), v.end());
  auto q = [&](double p) {
    return v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())))];
  };
  double sum = 0;
  for (double x : v) sum += x;
  return {q(0.5), q(0.99), q(0.999), v.back(), sum / static_cast<double>(v.size())};
}

}  // namespace

int main(int argc, char** argv) {
  long calls = 1'000'000;
  long per_sample_arg = 0;  // 0: chosen from the counter's period
  std::string kernel_arg = "auto", json_path;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "pbppo_bench_inference: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--calls") {
      const std::string v = next();
      char* end = nullptr;
      calls = std::strtol(v.c_str(), &end, 10);
      if (*end != '\0' || calls < 1000) {
        std::fprintf(stderr, "pbppo_bench_inference: --calls '%s' must be an integer >= 1000\n", v.c_str());
        return 2;
      }
    } else if (a == "--kernel") {
      kernel_arg = next();
    } else if (a == "--per-sample") {
      const std::string v = next();
      char* end = nullptr;
      per_sample_arg = std::strtol(v.c_str(), &end, 10);
      if (*end != '\0' || per_sample_arg < 1 || per_sample_arg > 1024) {
        std::fprintf(stderr, "pbppo_bench_inference: --per-sample '%s' must be an integer in 1..1024\n", v.c_str());
        return 2;
      }
    } else if (a == "--json") {
      json_path = next();
    } else {
      std::fprintf(stderr,
                   "usage: pbppo_bench_inference [--calls N] [--kernel auto|portable|avx512|neon|all] [--per-sample N] "
                   "[--json FILE]\n");
      return 2;
    }
  }
  std::vector<Kernel> kernels;
  if (kernel_arg == "all") {
    kernels = AvailableKernels();
  } else if (kernel_arg == "auto") {
    kernels = {AutoKernel()};
  } else if (const auto k = KernelFromName(kernel_arg)) {
    if (!KernelAvailable(*k)) {
      std::fprintf(stderr, "pbppo_bench_inference: --kernel %s: not supported by this CPU\n", kernel_arg.c_str());
      return 2;
    }
    kernels = {*k};
  } else {
    std::fprintf(stderr, "pbppo_bench_inference: --kernel '%s' unknown (auto, portable, avx512, neon, all)\n",
                 kernel_arg.c_str());
    return 2;
  }

  const std::vector<Shape> shapes = {
      {"P1", {48, 512, 256, 128, 12}, Activation::kElu, 4.0},
      {"P2", {48, 256, 128, 64, 12}, Activation::kElu, 1.3},
      {"P3", {24, 64, 64, 2}, Activation::kTanh, 0.15},
      // Recurrent actors: an LSTM or GRU on the observation, an MLP head (the shape of rsl_rl's
      // recurrent actors: unitree_rl_gym's G1 and H1 use LSTM 64 and a 32-wide head).
      {"L64", {48, 64, 32, 12}, Activation::kElu, 0.0, LayerKind::kLstm},
      {"G64", {48, 64, 32, 12}, Activation::kElu, 0.0, LayerKind::kGru},
      {"L256", {48, 256, 128, 64, 12}, Activation::kElu, 0.0, LayerKind::kLstm},
  };

  const double tsc_hz = TscHz();
  const double core_hz = CoreHz();
  // Cost of the timing itself: median of an empty timed region.
  std::vector<double> empty(200000);
  for (auto& e : empty) {
    const std::uint64_t a = Stamp();
    const std::uint64_t b = Stamp();
    e = static_cast<double>(b - a);
  }
  std::sort(empty.begin(), empty.end());
  const double overhead_ticks = empty[empty.size() / 2];
  // Calls per timed sample: one where the counter resolves a call; otherwise enough that the
  // smallest shape's sample spans at least 100 counter periods (P3 runs in well over 20 ns).
  const double period_ns = 1e9 / tsc_hz;
  int per_sample = 1;
  if (per_sample_arg > 0)
    per_sample = static_cast<int>(per_sample_arg);
  else if (period_ns > 1.0)
    while (20.0 * per_sample < 100.0 * period_ns && per_sample < 1024) per_sample *= 2;
  // Warm-up and read-floor samples: fixed for the default 1,000,000 calls, fewer for short runs.
  const long warm_calls = std::min(20000L, calls / 10), read_samples = std::min(100000L, calls);

  std::printf("policy inference latency, batch 1, one thread, %ld calls per row\n", calls);
  std::printf("core clock %.2f GHz (dependent-add chain), %s %.3f GHz, timer overhead %.1f ns subtracted\n",
              core_hz / 1e9, kCounter, tsc_hz / 1e9, overhead_ticks / tsc_hz * 1e9);
  if (per_sample > 1)
    std::printf("the counter ticks every %.1f ns: each timed sample runs %d calls; figures are per call\n", period_ns,
                per_sample);
  std::printf("\n%-5s %-9s %-28s %9s %9s %9s %9s %9s %8s %8s %8s %8s %7s\n", "shape", "kernel", "layers", "median",
              "p99", "p99.9", "max", "mean", "allocs", "bound", "x bound", "read", "target");
  std::printf("%-5s %-9s %-28s %9s %9s %9s %9s %9s %8s %8s %8s %8s %7s\n", "", "", "", "us", "us", "us", "us", "us",
              "/call", "us", "", "us", "us");

  std::string json = "{\n  \"core_hz\": " + std::to_string(core_hz) + ",\n  \"counter\": \"" + kCounter +
                     "\",\n  \"calls_per_sample\": " + std::to_string(per_sample) +
                     ",\n  \"calls\": " + std::to_string(calls) + ",\n  \"rows\": [\n";
  bool first = true;
  int misses = 0;
  for (const Shape& shape : shapes) {
    const PolicySpec spec =
        shape.first == LayerKind::kDense
            ? MakeRandomSpec(shape.widths, shape.act, 1)
            : MakeRandomRecurrentSpec(shape.widths, shape.act, 0, shape.first, /*linear_before_reset=*/true, 1);
    // Through the real blob path: encode, then load from bytes.
    auto bytes = EncodeBlob(spec);
    if (!bytes) return 1;
    // The same timing over a plain read of as many bytes as the model's parameters.
    const std::size_t n_floats = (spec.ParameterCount() + 31) / 32 * 32;
    pbppo::AlignedBlock block(n_floats * sizeof(float));
    auto* floats = reinterpret_cast<float*>(block.data());
    for (std::size_t i = 0; i < n_floats; ++i) floats[i] = 1e-3f;
    // The read floor: the faster (by median) of the plain loops this machine can run.
    const std::vector<pbppo::bench::StreamFn> readers = pbppo::bench::StreamReaders();
    Stats r{};
    for (auto* read : readers) {
      std::vector<double> read_ticks(static_cast<std::size_t>(read_samples));
      volatile float sink = 0;
      for (long w = 0; w < warm_calls / 4; ++w) sink = sink + read(floats, n_floats);
      for (double& t : read_ticks) {
        const std::uint64_t t0 = Stamp();
        for (int b = 0; b < per_sample; ++b) sink = sink + read(floats, n_floats);
        t = (static_cast<double>(Stamp() - t0) - overhead_ticks) / per_sample;
      }
      const Stats rs = Summarise(read_ticks);
      if (read == readers.front() || rs.median < r.median) r = rs;
    }
    for (Kernel k : kernels) {
      auto model = PolicyModel::FromBlob(*bytes, {.kernel = k});
      if (!model) {
        std::fprintf(stderr, "%s: %s\n", shape.name, model.error().message.c_str());
        return 1;
      }
      auto data = MakePolicyData(*model);
      if (!data) return 1;
      pbppo::Rng rng(7);
      std::vector<float> obs(static_cast<std::size_t>(spec.input_size) * 64);
      for (float& o : obs) o = static_cast<float>(rng.Normal());
      std::vector<double> ticks(static_cast<std::size_t>(calls));
      for (long w = 0; w < warm_calls; ++w) (void)Forward(*model, *data);  // warm caches and clocks
      std::uint64_t allocations = 0;
      {
        pbppo::AllocationScope scope;
        for (long c = 0; c < calls; ++c) {
          const float* src = obs.data() + static_cast<std::size_t>(c % 64) * spec.input_size;
          std::memcpy(data->observation().data(), src, spec.input_size * sizeof(float));
          const std::uint64_t t0 = Stamp();
          for (int b = 0; b < per_sample; ++b) (void)Forward(*model, *data);
          const std::uint64_t t1 = Stamp();
          ticks[static_cast<std::size_t>(c)] = (static_cast<double>(t1 - t0) - overhead_ticks) / per_sample;
        }
        allocations = scope.count();
      }
      const long forward_calls = calls * per_sample;
      const Stats s = Summarise(ticks);
      const double us = 1e6 / tsc_hz;
      const double bound_us = static_cast<double>(model->parameter_bytes()) / kLoadBytesPerCycle / core_hz * 1e6;
      std::string layers;
      for (std::size_t i = 0; i < shape.widths.size(); ++i) layers += (i ? "-" : "") + std::to_string(shape.widths[i]);
      layers += std::string(" ") + ToString(shape.act);
      if (shape.first != LayerKind::kDense) layers = std::string(ToString(shape.first)) + " " + layers;
      const bool meets = shape.target_us <= 0.0 || s.median * us <= shape.target_us;
      misses += !meets;
      char target[16] = "     -";
      if (shape.target_us > 0.0) std::snprintf(target, sizeof target, "%6.2f", shape.target_us);
      std::printf("%-5s %-9s %-28s %9.3f %9.3f %9.3f %9.2f %9.3f %8.2g %8.3f %8.2f %8.3f %s%s\n", shape.name,
                  ToString(k), layers.c_str(), s.median * us, s.p99 * us, s.p999 * us, s.max * us, s.mean * us,
                  static_cast<double>(allocations) / static_cast<double>(forward_calls), bound_us,
                  s.median * us / bound_us, r.median * us, target,
                  meets                             ? ""
                  : shape.target_us < r.median * us ? " (missed: target below the read floor)"
                                                    : " (missed)");
      char row[512];
      std::snprintf(
          row, sizeof row,
          "%s    {\"shape\": \"%s\", \"kernel\": \"%s\", \"median_us\": %.4f, \"p99_us\": %.4f, \"p999_us\": %.4f, "
          "\"max_us\": %.3f, \"allocations_per_call\": %.3g, \"bound_us\": %.4f, \"read_us\": %.4f, "
          "\"target_us\": %.3f}",
          first ? "" : ",\n", shape.name, ToString(k), s.median * us, s.p99 * us, s.p999 * us, s.max * us,
          static_cast<double>(allocations) / static_cast<double>(forward_calls), bound_us, r.median * us,
          shape.target_us);
      json += row;
      first = false;
    }
  }
  json += "\n  ]\n}\n";
  std::printf("\nbound: parameter bytes / (%.0f bytes per cycle x core clock); x bound = median / bound\n",
              kLoadBytesPerCycle);
  std::printf(
      "read: median time to merely read as many bytes as the parameters, timed the same way (a\n"
      "      compiler-vectorised loop, or an 8-register AVX-512 loop where faster): a forward pass whose parameters\n"
      "      stream from L2 cannot beat it\n");
  if (!json_path.empty()) {
    if (auto st = WriteFileAtomic(json_path, {reinterpret_cast<const std::uint8_t*>(json.data()), json.size()}); !st) {
      std::fprintf(stderr, "%s\n", st.error().message.c_str());
      return 1;
    }
  }
  return 0;
}
