// The runtime forward pass, every available kernel, against the writer's float64 reference.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "runtime/core/random.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/policy/reference.hpp"
#include "tests/support/golden_check.hpp"
#include "tests/support/policy_on_kernel.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo::policy;

namespace {

using pbppo::test::Deviation;

struct Shape {
  const char* name;
  std::vector<std::uint32_t> widths;
  Activation act;
  ActionHead head;
};

const Shape kShapes[] = {
    {"P1", {48, 512, 256, 128, 12}, Activation::kElu, ActionHead::kLinear},
    {"P2", {48, 256, 128, 64, 12}, Activation::kElu, ActionHead::kLinear},
    {"P3", {24, 64, 64, 2}, Activation::kTanh, ActionHead::kLinear},
    {"relu-odd", {7, 33, 17, 5}, Activation::kRelu, ActionHead::kTanh},
    {"leaky-P2", {48, 256, 128, 64, 12}, Activation::kLeakyRelu, ActionHead::kLinear},
    {"leaky-odd", {7, 33, 17, 5}, Activation::kLeakyRelu, ActionHead::kTanh},
    {"identity-wide", {130, 200, 19}, Activation::kIdentity, ActionHead::kLinear},
    {"single-layer", {1, 1}, Activation::kIdentity, ActionHead::kTanh},
};

}  // namespace

TEST_CASE("every kernel reproduces the golden vectors within the float32 error bound") {
  for (const Shape& shape : kShapes) {
    PolicySpec spec = MakeRandomSpec(shape.widths, shape.act, 21);
    spec.action_head = shape.head;
    // A non-trivial action map that also clamps.
    for (std::size_t j = 0; j < spec.output_size; ++j) {
      spec.action_scale[j] = 0.75f + 0.1f * static_cast<float>(j);
      spec.action_offset[j] = 0.05f * static_cast<float>(j);
      spec.action_low[j] = -0.8f;
      spec.action_high[j] = 0.9f;
    }
    const GoldenVectors g = MakeGoldenVectors(spec, 64, 5);
    for (Kernel k : AvailableKernels()) {
      CAPTURE(shape.name);
      const std::string kernel_name = ToString(k);
      CAPTURE(kernel_name);
      auto model = PolicyModel::FromSpec(spec, {.kernel = k});
      REQUIRE(model.ok());
      REQUIRE(model->kernel() == k);
      const Deviation d = pbppo::test::CheckGolden(*model, g);
      const std::string what = std::string(shape.name) + " " + ToString(k);
      MESSAGE(what << ": max |error| " << d.worst_abs << ", " << d.worst_ratio << " of the bound");
      // The bound is a worst case; a float32 forward lands far inside it. This catches a path
      // that silently lost precision (reduced-precision weights deviate by ~1e-3).
      CHECK(d.worst_abs < 1e-5);
    }
  }
}

TEST_CASE("leaky_relu with random slopes in [0, 1]: every kernel within the bound, on every tile form") {
  // Output widths reach every avx512 tile width (1..8 vectors, more than 8, the unrolled 24- and
  // 64-input tiles) and the row form (<= 4 outputs); the output layer is leaky in some specs too.
  const std::vector<std::vector<std::uint32_t>> shapes = {
      {13, 16, 48, 97, 130, 3}, {11, 32, 64, 96, 128, 4}, {24, 64, 64, 2}, {5, 80, 112, 200, 1}, {1, 1}};
  pbppo::Rng rng(31);
  int specs = 0;
  for (const auto& widths : shapes) {
    for (std::uint64_t seed : {1u, 2u, 3u}) {
      PolicySpec spec = MakeRandomSpec(widths, Activation::kLeakyRelu, seed);
      if (seed != 1) {
        spec.layers.back().activation = Activation::kLeakyRelu;
        spec.layers.back().alpha = 0.0f;
      }
      spec.action_head = seed == 3 ? ActionHead::kTanh : ActionHead::kLinear;
      for (Layer& l : spec.layers) {
        if (l.activation != Activation::kLeakyRelu) continue;
        const double u = rng.Uniform();
        l.alpha = u < 0.15 ? 0.0f : u < 0.3 ? 1.0f : u < 0.45 ? 0.01f : static_cast<float>(rng.Uniform());
      }
      for (std::size_t j = 0; j < spec.output_size; ++j) spec.action_scale[j] = 0.9f;
      REQUIRE(ValidateSpec(spec).ok());
      const GoldenVectors g = MakeGoldenVectors(spec, 48, seed + 10);
      for (Kernel k : AvailableKernels()) {
        CAPTURE(specs);
        const std::string kernel_name = ToString(k);
        CAPTURE(kernel_name);
        auto model = PolicyModel::FromSpec(spec, {.kernel = k});
        REQUIRE(model.ok());
        const Deviation d = pbppo::test::CheckGolden(*model, g);
        CHECK(d.worst_abs < 1e-5);
      }
      ++specs;
    }
  }
  CHECK(specs == 15);
}

TEST_CASE("leaky_relu is x > 0 ? x : alpha * x exactly, on every kernel") {
  // One layer with W = I and b = 0, identity normaliser and action map: the action is the
  // activation of the observation, bit for bit.
  for (std::uint32_t n : {3u, 20u, 130u}) {  // avx512 row form, a 2-vector tile, 8 + 1 vectors
    PolicySpec spec = MakeRandomSpec({n, n}, Activation::kIdentity, 1);
    Layer& l = spec.layers[0];
    l.activation = Activation::kLeakyRelu;
    l.alpha = 0.3f;
    std::fill(l.weight.begin(), l.weight.end(), 0.0f);
    for (std::uint32_t i = 0; i < n; ++i) l.weight[static_cast<std::size_t>(i) * n + i] = 1.0f;
    std::fill(l.bias.begin(), l.bias.end(), 0.0f);
    std::fill(spec.obs_mean.begin(), spec.obs_mean.end(), 0.0f);
    std::fill(spec.obs_inv_std.begin(), spec.obs_inv_std.end(), 1.0f);
    spec.obs_clip = 1e30f;
    std::fill(spec.action_scale.begin(), spec.action_scale.end(), 1.0f);
    std::fill(spec.action_low.begin(), spec.action_low.end(), -1e30f);
    std::fill(spec.action_high.begin(), spec.action_high.end(), 1e30f);
    for (Kernel k : AvailableKernels()) {
      CAPTURE(n);
      const std::string kernel_name = ToString(k);
      CAPTURE(kernel_name);
      const auto run = pbppo::test::OnKernel(spec, k);
      const PolicyModel* model = &run->model;
      PolicyData* data = &*run->data;
      pbppo::Rng rng(n);
      for (int r = 0; r < 20; ++r) {
        auto obs = data->observation();
        for (float& o : obs) o = static_cast<float>(rng.Normal() * std::exp(8.0 * rng.Normal()));
        obs[0] = 0.0f;
        if (n > 1) obs[1] = -1e-40f;  // subnormal
        if (n > 2) obs[2] = 1e-40f;
        REQUIRE(Forward(*model, *data) == ForwardStatus::kOk);
        for (std::uint32_t i = 0; i < n; ++i) {
          const float x = obs[i];
          const float want = x > 0.0f ? x : 0.3f * x;
          CHECK_MESSAGE(data->action()[i] == want, "x " << x << " got " << data->action()[i] << " want " << want);
        }
      }
    }
  }
}

TEST_CASE("golden files written by the writer are reproduced from the files") {
  const std::string dir = pbppo::test::ScratchDir("forward_files");
  const PolicySpec spec = MakeRandomSpec({24, 64, 64, 2}, Activation::kTanh, 3);
  REQUIRE(WriteBlobFile(dir + "/p3.blob", spec).ok());
  REQUIRE(WriteGoldenFile(GoldenPathFor(dir + "/p3.blob"), MakeGoldenVectors(spec, 16, 4)).ok());
  auto g = ReadGoldenFile(dir + "/p3.golden");
  REQUIRE(g.ok());
  CHECK(g->observations.size() == 16);
  for (Kernel k : AvailableKernels()) {
    auto model = PolicyModel::FromFile(dir + "/p3.blob", {.kernel = k});
    REQUIRE(model.ok());
    pbppo::test::CheckGolden(*model, *g);
  }
}

TEST_CASE("shipped and reference blobs: every kernel within each golden row's bound and under 1e-5 on every row") {
  int seen = 0;
  for (const char* rel : {"tests/data/blobs/p1.blob", "tests/data/blobs/p2.blob", "tests/data/blobs/p3.blob",
                          "policies/frozen/auv_nav/auv_nav.blob", "policies/frozen/quadruped_walk/flat.blob",
                          "policies/frozen/quadruped_walk/mixed.blob"}) {
    const std::string blob = pbppo::test::SourcePath(rel);
    auto g = ReadGoldenFile(GoldenPathFor(blob));
    REQUIRE_MESSAGE(g.ok(), g.error().message);
    for (Kernel k : AvailableKernels()) {
      const std::string blob_name = rel;
      CAPTURE(blob_name);
      const std::string kernel_name = ToString(k);
      CAPTURE(kernel_name);
      auto model = PolicyModel::FromFile(blob, {.kernel = k});
      REQUIRE_MESSAGE(model.ok(), model.error().message);
      const Deviation d = pbppo::test::CheckGolden(*model, *g);
      MESSAGE(rel << " " << ToString(k) << ": max |error| " << d.worst_abs << ", " << d.worst_ratio << " of the bound");
      CHECK(d.worst_abs < 1e-5);
    }
    ++seen;
  }
  CHECK(seen == 6);
}

TEST_CASE("non-finite observations skip inference and are counted") {
  const PolicySpec spec = MakeRandomSpec({24, 64, 64, 2}, Activation::kTanh, 3);
  for (Kernel k : AvailableKernels()) {
    const std::string kernel_name = ToString(k);
    CAPTURE(kernel_name);
    const auto run = pbppo::test::OnKernel(spec, k);
    const PolicyModel* model = &run->model;
    PolicyData* data = &*run->data;
    for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                      -std::numeric_limits<float>::infinity()}) {
      std::fill(data->observation().begin(), data->observation().end(), 0.5f);
      data->observation()[23] = bad;
      CHECK(Forward(*model, *data) == ForwardStatus::kNonFiniteObservation);
      for (float a : data->action()) CHECK(std::isnan(a));
    }
    CHECK(data->nonfinite_observations == 3);
    std::fill(data->observation().begin(), data->observation().end(), 1e30f);  // finite, clipped
    CHECK(Forward(*model, *data) == ForwardStatus::kOk);
    for (float a : data->action()) CHECK(std::isfinite(a));
    CHECK(data->forward_calls == 4);
  }
}

TEST_CASE("actions stay inside [low, high]") {
  PolicySpec spec = MakeRandomSpec({6, 16, 4}, Activation::kRelu, 8);
  for (std::size_t j = 0; j < 4; ++j) {
    spec.action_scale[j] = 100.0f;
    spec.action_low[j] = -0.25f;
    spec.action_high[j] = 0.5f;
  }
  for (Kernel k : AvailableKernels()) {
    const auto run = pbppo::test::OnKernel(spec, k);
    const PolicyModel* model = &run->model;
    PolicyData* data = &*run->data;
    pbppo::Rng rng(1);
    bool low = false, high = false;
    for (int r = 0; r < 200; ++r) {
      for (float& o : data->observation()) o = static_cast<float>(3.0 * rng.Normal());
      REQUIRE(Forward(*model, *data) == ForwardStatus::kOk);
      for (float a : data->action()) {
        CHECK(a >= -0.25f);
        CHECK(a <= 0.5f);
        low |= a == -0.25f;
        high |= a == 0.5f;
      }
    }
    CHECK(low);
    CHECK(high);
  }
}

TEST_CASE("data made for one model is refused by another") {
  const PolicySpec spec = MakeRandomSpec({4, 8, 2}, Activation::kTanh, 1);
  auto a = PolicyModel::FromSpec(spec);
  auto b = PolicyModel::FromSpec(spec);
  REQUIRE(a.ok());
  REQUIRE(b.ok());
  auto data = MakePolicyData(*a);
  REQUIRE(data.ok());
  CHECK(Forward(*b, *data) == ForwardStatus::kWrongModel);
  CHECK(Forward(*a, *data) == ForwardStatus::kOk);
}

TEST_CASE("an unavailable kernel is refused at load, not at run time") {
  const PolicySpec spec = MakeRandomSpec({4, 8, 2}, Activation::kTanh, 1);
  if (!KernelAvailable(Kernel::kAvx512)) {
    auto m = PolicyModel::FromSpec(spec, {.kernel = Kernel::kAvx512});
    REQUIRE_FALSE(m.ok());
    CHECK(m.error().message == "kernel avx512 is not supported by this CPU");
  } else {
    CHECK(PolicyModel::FromSpec(spec, {.kernel = Kernel::kAvx512}).ok());
  }
  auto m = PolicyModel::FromSpec(spec);
  REQUIRE(m.ok());
  CHECK(m->kernel() == AutoKernel());
  // The packed kernel of this architecture is the automatic choice; the other is refused.
#if defined(__aarch64__)
  CHECK(m->kernel() == Kernel::kNeon);
  CHECK_FALSE(KernelAvailable(Kernel::kAvx512));
#else
  CHECK(m->kernel() == (KernelAvailable(Kernel::kAvx512) ? Kernel::kAvx512 : Kernel::kPortable));
  auto neon = PolicyModel::FromSpec(spec, {.kernel = Kernel::kNeon});
  REQUIRE_FALSE(neon.ok());
  CHECK(neon.error().message == "kernel neon is not supported by this CPU");
#endif
  CHECK(KernelFromName("neon") == Kernel::kNeon);
  CHECK(KernelFromName("avx512") == Kernel::kAvx512);
  CHECK_FALSE(KernelFromName("sse").has_value());
}
