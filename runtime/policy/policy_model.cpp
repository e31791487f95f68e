#include "runtime/policy/policy_model.hpp"

#include <algorithm>
#include <cstring>

#include "runtime/core/enum_name.hpp"
#include "runtime/policy/blob.hpp"

#ifdef EIGEN_RUNTIME_NO_MALLOC
#include <Eigen/Core>
#endif

namespace pbppo::policy {
namespace {

std::uint32_t Pad(std::uint32_t n) {
  return (n + detail::kLanes - 1) / detail::kLanes * detail::kLanes;
}

// Copies W (row-major [out][in]) into AVX-512 tiles: for each tile of up to 8 output vectors,
// [in][vectors * 16] so the kernel streams it front to back. Padding rows are zero.
void PackTiles(const DenseLayer& l, std::uint32_t out_pad, float* dst) {
  const std::uint32_t vectors = out_pad / detail::kLanes;
  for (std::uint32_t v0 = 0; v0 < vectors; v0 += detail::kTileVectors) {
    const std::uint32_t nv = std::min(detail::kTileVectors, vectors - v0);
    const std::uint32_t width = nv * detail::kLanes;
    for (std::uint32_t i = 0; i < l.in; ++i) {
      for (std::uint32_t k = 0; k < width; ++k) {
        const std::uint32_t o = v0 * detail::kLanes + k;
        dst[static_cast<std::size_t>(i) * width + k] =
            o < l.out ? l.weight[static_cast<std::size_t>(o) * l.in + i] : 0.0f;
      }
    }
    dst += static_cast<std::size_t>(l.in) * width;
  }
}

// Row-major [out][in rounded up to 16]; the padding columns stay zero.
void PackRows(const DenseLayer& l, float* dst) {
  const std::uint32_t in_pad = Pad(l.in);
  for (std::uint32_t o = 0; o < l.out; ++o) {
    std::memcpy(dst + static_cast<std::size_t>(o) * in_pad, l.weight.data() + static_cast<std::size_t>(o) * l.in,
                l.in * sizeof(float));
  }
}

}  // namespace

const char* ToString(Kernel k) noexcept {
  return EnumName(k, {"auto", "portable", "avx512", "neon"});
}

std::optional<Kernel> KernelFromName(std::string_view name) noexcept {
  for (Kernel k : {Kernel::kAuto, Kernel::kPortable, Kernel::kAvx512, Kernel::kNeon})
    if (name == ToString(k)) return k;
  return std::nullopt;
}

Kernel AutoKernel() noexcept {
  if (KernelAvailable(Kernel::kAvx512)) return Kernel::kAvx512;
  if (KernelAvailable(Kernel::kNeon)) return Kernel::kNeon;
  return Kernel::kPortable;
}

bool KernelAvailable(Kernel k) noexcept {
  switch (k) {
    case Kernel::kAuto:
    case Kernel::kPortable: return true;
    case Kernel::kAvx512: return detail::CpuHasAvx512();
    case Kernel::kNeon:
#if defined(__aarch64__)
      return true;  // Advanced SIMD is part of every ARMv8-A CPU
#else
      return false;
#endif
  }
  return false;
}

std::vector<Kernel> AvailableKernels() {
  std::vector<Kernel> v{Kernel::kPortable};
  if (KernelAvailable(Kernel::kAvx512)) v.push_back(Kernel::kAvx512);
  if (KernelAvailable(Kernel::kNeon)) v.push_back(Kernel::kNeon);
  return v;
}

const char* ToString(ForwardStatus s) noexcept {
  switch (s) {
    case ForwardStatus::kOk: return "ok";
    case ForwardStatus::kNonFiniteObservation: return "non-finite observation";
    case ForwardStatus::kNonFiniteAction: return "non-finite action";
    case ForwardStatus::kWrongModel: return "data made for another model";
  }
  return "unknown";
}

Result<PolicyModel> PolicyModel::FromSpec(const PolicySpec& spec, const LoadOptions& options) {
  if (auto st = ValidateSpec(spec, options.limits); !st) return st.error();
  Kernel kernel = options.kernel;
  if (kernel == Kernel::kAuto) kernel = AutoKernel();
  const bool packed = kernel == Kernel::kAvx512 || kernel == Kernel::kNeon;  // kernel_view.hpp's packed layout
  if (!KernelAvailable(kernel)) {
    return MakeError(ErrorCode::kUnsupported,
                     std::string("kernel ") + ToString(kernel) + " is not supported by this CPU");
  }

  PolicyModel m;
  m.kernel_ = kernel;
  const std::uint32_t in_pad = Pad(spec.input_size), out_pad = Pad(spec.output_size);

  // Parameter block layout.
  ArenaPlan plan;
  const std::size_t off_mean = plan.Floats(in_pad), off_inv_std = plan.Floats(in_pad);
  const std::size_t off_scale = plan.Floats(out_pad), off_offset = plan.Floats(out_pad);
  const std::size_t off_low = plan.Floats(out_pad), off_high = plan.Floats(out_pad);
  std::vector<std::size_t> off_w, off_b;
  std::uint32_t max_pad = in_pad;
  for (const DenseLayer& l : spec.layers) {
    const std::uint32_t lp = Pad(l.out);
    max_pad = std::max(max_pad, lp);
    std::size_t floats = static_cast<std::size_t>(l.out) * l.in;
    if (packed) {
      floats = l.out <= detail::kRowFormMaxOut ? static_cast<std::size_t>(l.out) * Pad(l.in)
                                               : static_cast<std::size_t>(lp) * l.in;
    }
    off_w.push_back(plan.Floats(floats));
    off_b.push_back(plan.Floats(lp));
  }
  m.params_ = AlignedBlock(plan.bytes());
  m.parameter_bytes_ = spec.ParameterCount() * sizeof(float);
  std::byte* base = m.params_.data();
  auto at = [base](std::size_t off) { return reinterpret_cast<float*>(base + off); };
  auto copy = [](const std::vector<float>& v, float* dst) { std::memcpy(dst, v.data(), v.size() * sizeof(float)); };

  copy(spec.obs_mean, at(off_mean));
  copy(spec.obs_inv_std, at(off_inv_std));
  copy(spec.action_scale, at(off_scale));
  copy(spec.action_offset, at(off_offset));
  copy(spec.action_low, at(off_low));
  copy(spec.action_high, at(off_high));
  for (std::size_t li = 0; li < spec.layers.size(); ++li) {
    const DenseLayer& l = spec.layers[li];
    const std::uint32_t lp = Pad(l.out);
    if (packed && l.out <= detail::kRowFormMaxOut) {
      PackRows(l, at(off_w[li]));
    } else if (packed) {
      PackTiles(l, lp, at(off_w[li]));
    } else {
      copy(l.weight, at(off_w[li]));
    }
    copy(l.bias, at(off_b[li]));
    m.layers_.push_back(detail::KernelLayer{at(off_w[li]), at(off_b[li]), l.in, l.out, lp,
                                            static_cast<std::uint32_t>(l.activation), l.alpha});
  }
  m.max_width_pad_ = max_pad;
  m.view_ = detail::ModelView{m.layers_.data(),
                              static_cast<std::uint32_t>(m.layers_.size()),
                              spec.input_size,
                              in_pad,
                              spec.output_size,
                              out_pad,
                              static_cast<std::uint32_t>(spec.action_head),
                              spec.obs_clip,
                              at(off_mean),
                              at(off_inv_std),
                              at(off_scale),
                              at(off_offset),
                              at(off_low),
                              at(off_high)};

  m.description_ = spec;
  for (DenseLayer& l : m.description_.layers) {
    l.weight.clear();
    l.weight.shrink_to_fit();
    l.bias.clear();
    l.bias.shrink_to_fit();
  }
  return m;
}

Result<PolicyModel> PolicyModel::FromBlob(std::span<const std::uint8_t> bytes, const LoadOptions& options) {
  auto spec = DecodeBlob(bytes, options.limits);
  if (!spec) return std::move(spec).error();
  return FromSpec(*spec, options);
}

Result<PolicyModel> PolicyModel::FromFile(const std::string& path, const LoadOptions& options) {
  auto spec = ReadBlobFile(path, options.limits);
  if (!spec) return std::move(spec).error();
  auto m = FromSpec(*spec, options);
  if (!m) return MakeError(m.error().code, path + ": " + m.error().message);
  return m;
}

Result<PolicyData> MakePolicyData(const PolicyModel& model) {
  const detail::ModelView& mv = model.view();
  ArenaPlan plan;
  const std::size_t off_obs = plan.Floats(mv.input_pad), off_x = plan.Floats(mv.input_pad);
  const std::size_t off_ping = plan.Floats(model.max_width_pad()), off_pong = plan.Floats(model.max_width_pad());
  const std::size_t off_act = plan.Floats(mv.output_pad);
  PolicyData d;
  d.arena_ = AlignedBlock(plan.bytes());
  std::byte* base = d.arena_.data();
  auto at = [base](std::size_t off) { return reinterpret_cast<float*>(base + off); };
  d.view_ = detail::DataView{at(off_obs), at(off_x), at(off_ping), at(off_pong), at(off_act)};
  d.model_ = &model;
  d.input_size_ = mv.input_size;
  d.output_size_ = mv.output_size;
  return d;
}

ForwardStatus Forward(const PolicyModel& model, PolicyData& data) noexcept {
  if (data.model_ != &model) return ForwardStatus::kWrongModel;
  ++data.forward_calls;
  std::uint32_t bad = 0;
  switch (model.kernel()) {
    case Kernel::kAvx512: bad = detail::ForwardAvx512(model.view(), data.view_); break;
    case Kernel::kNeon: bad = detail::ForwardNeon(model.view(), data.view_); break;
    default: bad = detail::ForwardPortable(model.view(), data.view_); break;
  }
  if (bad & detail::kBadObservation) {
    ++data.nonfinite_observations;
    return ForwardStatus::kNonFiniteObservation;
  }
  if (bad & detail::kBadAction) {
    ++data.nonfinite_actions;
    return ForwardStatus::kNonFiniteAction;
  }
  return ForwardStatus::kOk;
}

void SetEigenMallocAllowed(bool allowed) noexcept {
#ifdef EIGEN_RUNTIME_NO_MALLOC
  Eigen::internal::set_is_malloc_allowed(allowed);
#else
  (void)allowed;
#endif
}

}  // namespace pbppo::policy
