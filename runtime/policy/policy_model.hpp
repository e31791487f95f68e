// PolicyModel (immutable, built once from a blob) and PolicyData (every buffer a forward pass
// needs, one aligned arena made once from the model). Forward() is noexcept and allocation-free.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/core/aligned_arena.hpp"
#include "runtime/core/result.hpp"
#include "runtime/policy/blob_format.hpp"
#include "runtime/policy/kernel_view.hpp"
#include "runtime/policy/policy_spec.hpp"

namespace pbppo::policy {

// Which forward implementation a model runs. kAuto picks the fastest this CPU supports (AutoKernel):
// avx512 on x86-64 with AVX-512 F/DQ/BW/VL, neon on aarch64, portable otherwise.
enum class Kernel : std::uint8_t { kAuto, kPortable, kAvx512, kNeon };
const char* ToString(Kernel k) noexcept;
// The kernel of a name ToString gives ("auto", "portable", "avx512", "neon"); nullopt for another.
std::optional<Kernel> KernelFromName(std::string_view name) noexcept;
bool KernelAvailable(Kernel k) noexcept;
Kernel AutoKernel() noexcept;
std::vector<Kernel> AvailableKernels();

struct LoadOptions {
  BlobLimits limits{};
  Kernel kernel = Kernel::kAuto;
};

class PolicyModel {
 public:
  static Result<PolicyModel> FromSpec(const PolicySpec& spec, const LoadOptions& options = {});
  static Result<PolicyModel> FromBlob(std::span<const std::uint8_t> bytes, const LoadOptions& options = {});
  static Result<PolicyModel> FromFile(const std::string& path, const LoadOptions& options = {});

  // Everything the blob says except the weights (layer shapes, normaliser, action map, names,
  // layout hash, provenance); layer weight/bias vectors are empty.
  const PolicySpec& description() const noexcept { return description_; }
  std::uint32_t input_size() const noexcept { return view_.input_size; }
  std::uint32_t output_size() const noexcept { return view_.output_size; }
  std::uint32_t max_width_pad() const noexcept { return max_width_pad_; }
  Kernel kernel() const noexcept { return kernel_; }
  std::uint64_t parameter_bytes() const noexcept { return parameter_bytes_; }
  const detail::ModelView& view() const noexcept { return view_; }
  // Whether a layer is recurrent: the data then carries state from one Forward() to the next.
  bool recurrent() const noexcept { return state_floats_ > 0; }
  // Floats of state (each recurrent layer's h, and c for an LSTM, padded to 16; 0 without one).
  std::uint32_t state_size() const noexcept { return state_floats_; }
  // Scratch a recurrent step needs: the widest gate vector and the widest hidden state, padded.
  std::uint32_t max_gate_pad() const noexcept { return max_gate_pad_; }
  std::uint32_t max_hidden_pad() const noexcept { return max_hidden_pad_; }

  PolicyModel(PolicyModel&&) noexcept = default;
  PolicyModel& operator=(PolicyModel&&) noexcept = default;
  PolicyModel(const PolicyModel&) = delete;
  PolicyModel& operator=(const PolicyModel&) = delete;

 private:
  PolicyModel() = default;
  PolicySpec description_;
  AlignedBlock params_;
  std::vector<detail::KernelLayer> layers_;
  std::vector<detail::KernelLayer> parts_;  // recurrent layers' dense parts
  detail::ModelView view_{};
  std::uint32_t max_width_pad_ = 0;
  std::uint32_t max_gate_pad_ = 0;    // widest recurrent part output, padded
  std::uint32_t max_hidden_pad_ = 0;  // widest recurrent layer, padded
  std::uint32_t state_floats_ = 0;
  std::uint64_t parameter_bytes_ = 0;
  Kernel kernel_ = Kernel::kPortable;
};

enum class ForwardStatus : std::uint8_t {
  kOk,
  kNonFiniteObservation,  // inference skipped, every action element is NaN
  kNonFiniteAction,       // the non-finite elements are NaN, the others are valid
  kWrongModel,            // the data was made for another model; nothing computed
};
inline constexpr std::uint32_t kForwardStatusCount = 4;
const char* ToString(ForwardStatus s) noexcept;

class PolicyData {
 public:
  // Observation to fill before Forward(); raw units, the model normalises.
  std::span<float> observation() noexcept { return {view_.observation, input_size_}; }
  // Action after Forward(): scaled, offset and clamped to the blob's limits.
  std::span<const float> action() const noexcept { return {view_.action, output_size_}; }

  // A recurrent policy's state (policy_model.hpp's state_size floats): zero when made, carried
  // from one Forward() to the next; a call with a non-finite observation leaves it unchanged.
  // ResetState() zeroes it (at arming, at a switch to this policy); saved and restored as a whole
  // to record and replay a run. Empty for a feed-forward policy.
  std::span<const float> state() const noexcept { return {view_.state, state_size_}; }
  std::span<float> state() noexcept { return {view_.state, state_size_}; }
  void ResetState() noexcept;

  std::uint64_t forward_calls = 0;
  std::uint64_t nonfinite_observations = 0;
  std::uint64_t nonfinite_actions = 0;

  PolicyData(PolicyData&&) noexcept = default;
  PolicyData& operator=(PolicyData&&) noexcept = default;

 private:
  friend Result<PolicyData> MakePolicyData(const PolicyModel& model);
  friend ForwardStatus Forward(const PolicyModel& model, PolicyData& data) noexcept;
  PolicyData() = default;
  AlignedBlock arena_;
  detail::DataView view_{};
  const PolicyModel* model_ = nullptr;
  std::uint32_t input_size_ = 0;
  std::uint32_t output_size_ = 0;
  std::uint32_t state_size_ = 0;
};

// Makes the data for a model (the only allocation). The data refers to the model, which must
// outlive it and not move.
Result<PolicyData> MakePolicyData(const PolicyModel& model);

// observation -> action. noexcept, allocation-free, lock-free; safe to call from a real-time tick.
ForwardStatus Forward(const PolicyModel& model, PolicyData& data) noexcept;

// Turns Eigen's allocation check on or off (builds with EIGEN_RUNTIME_NO_MALLOC; a no-op
// otherwise): with it off, any heap allocation inside Eigen code aborts.
void SetEigenMallocAllowed(bool allowed) noexcept;

}  // namespace pbppo::policy
