// The writer's float64 reference forward and the golden-vector files built from it.
// Set-up/test time code: allocates freely.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/policy/policy_spec.hpp"

namespace pbppo::policy {

struct ReferenceOutput {
  std::vector<double> action;
  // A first-order bound on |float32 forward - float64 reference| per action element: each dot
  // product of length n rounds within gamma(n+1) * sum|w||x| (Higham), each tanh/ELU within
  // 4 ulp of max(|f|, 1), each leaky_relu multiply within u (|f| + alpha e) for an input error e,
  // errors propagate through |W| (activations are 1-Lipschitz), and the action map adds two
  // roundings. Any summation order and FMA use stay within it.
  std::vector<double> error_bound;
};

// A recurrent policy's state in float64 and the bound on a float32 forward's deviation from it,
// per layer (empty vectors for a dense layer; c and ec for an LSTM only).
struct ReferenceState {
  struct Layer {
    std::vector<double> h, eh, c, ec;
  };
  std::vector<Layer> layers;
};
// The state at the start: zero, exactly.
ReferenceState MakeReferenceState(const PolicySpec& spec);

// Runs the policy in float64 over the spec's float32 parameters, one step from `state` (updated).
// The bound extends to the recurrent layers: their gate products as dot products, sigmoid (as
// 0.5 tanh(0.5 x) + 0.5, slope 1/4) and tanh within the kernels' tanh error, every product and sum
// of the state update one rounding with first- and second-order error terms; the state's bound is
// carried from step to step.
ReferenceOutput ReferenceForward(const PolicySpec& spec, const float* observation, ReferenceState* state);
// The same from the start state (a feed-forward policy has no other).
ReferenceOutput ReferenceForward(const PolicySpec& spec, const float* observation);

struct GoldenVectors {
  std::uint32_t input_size = 0;
  std::uint32_t output_size = 0;
  std::vector<std::vector<float>> observations;
  std::vector<ReferenceOutput> expected;
};

// Observations that exercise the normaliser clip, both signs and every activation region,
// drawn deterministically from `seed`, with the reference outputs for them. For a recurrent policy
// the rows are one sequence from the start state: the self-test runs them in order on fresh data.
GoldenVectors MakeGoldenVectors(const PolicySpec& spec, std::size_t rows, std::uint64_t seed);

Status WriteGoldenFile(const std::string& path, const GoldenVectors& g);
Result<GoldenVectors> ReadGoldenFile(const std::string& path);

// The conventional golden-vector path beside a blob: "x.blob" -> "x.golden".
std::string GoldenPathFor(const std::string& blob_path);

// A policy's files: the blob at `blob_path` and `golden` (vectors of this spec) beside it
// (GoldenPathFor), written together (WriteFilesAtomic: the golden file renamed into place first,
// the blob last), so that a spec that does not encode, golden vectors of another shape or an error
// while writing leave the previous files as they were.
Status WritePolicyFiles(const std::string& blob_path, const PolicySpec& spec, const GoldenVectors& golden);

}  // namespace pbppo::policy
