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
void PackTiles(const Layer& l, std::uint32_t out_pad, float* dst) {
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
void PackRows(const Layer& l, float* dst) {
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

  // The dense pieces: each dense layer, and each recurrent layer's parts (kernel_view.hpp).
  struct Piece {
    Layer dense;            // kind dense; its weight and bias
    std::size_t owner = 0;  // the spec layer
    std::size_t part = 0;   // 0 for a dense layer or a recurrent layer's input part
  };
  std::vector<Piece> pieces;
  auto rows = [](const std::vector<float>& v, std::size_t width, std::size_t from, std::size_t count) {
    return std::vector<float>(v.begin() + static_cast<std::ptrdiff_t>(from * width),
                              v.begin() + static_cast<std::ptrdiff_t>((from + count) * width));
  };
  for (std::size_t li = 0; li < spec.layers.size(); ++li) {
    const Layer& l = spec.layers[li];
    const std::uint32_t g = l.gates(), n = l.out;
    auto add = [&](std::uint32_t in, std::uint32_t out, std::vector<float> w, std::vector<float> b, std::size_t part) {
      Piece p;
      p.dense.in = in;
      p.dense.out = out;
      p.dense.weight = std::move(w);
      p.dense.bias = std::move(b);
      p.owner = li;
      p.part = part;
      if (l.kind == LayerKind::kDense) {
        p.dense.activation = l.activation;
        p.dense.alpha = l.alpha;
      }
      pieces.push_back(std::move(p));
    };
    add(l.in, g * n, l.weight, l.bias, 0);
    if (l.kind == LayerKind::kLstm) add(n, 4 * n, l.recurrent_weight, l.recurrent_bias, 1);
    if (l.kind == LayerKind::kGru) {
      add(n, 2 * n, rows(l.recurrent_weight, n, 0, 2 * n), rows(l.recurrent_bias, 1, 0, 2 * n), 1);
      add(n, n, rows(l.recurrent_weight, n, 2 * n, n), rows(l.recurrent_bias, 1, 2 * n, n), 2);
    }
  }

  // Parameter block layout.
  ArenaPlan plan;
  const std::size_t off_mean = plan.Floats(in_pad), off_inv_std = plan.Floats(in_pad);
  const std::size_t off_scale = plan.Floats(out_pad), off_offset = plan.Floats(out_pad);
  const std::size_t off_low = plan.Floats(out_pad), off_high = plan.Floats(out_pad);
  std::vector<std::size_t> off_w, off_b;
  std::uint32_t max_pad = in_pad;
  for (const Piece& p : pieces) {
    const Layer& l = p.dense;
    const std::uint32_t lp = Pad(l.out);
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
  std::vector<detail::KernelLayer> kernel_pieces;
  for (std::size_t pi = 0; pi < pieces.size(); ++pi) {
    const Layer& l = pieces[pi].dense;
    const std::uint32_t lp = Pad(l.out);
    if (packed && l.out <= detail::kRowFormMaxOut) {
      PackRows(l, at(off_w[pi]));
    } else if (packed) {
      PackTiles(l, lp, at(off_w[pi]));
    } else {
      copy(l.weight, at(off_w[pi]));
    }
    copy(l.bias, at(off_b[pi]));
    kernel_pieces.push_back(detail::KernelLayer{at(off_w[pi]), at(off_b[pi]), l.in, l.out, lp,
                                                static_cast<std::uint32_t>(l.activation), l.alpha, 0, 0, nullptr, 0});
  }
  // A recurrent layer's parts, in order, in parts_ (which never reallocates after this).
  m.parts_.reserve(pieces.size());
  std::uint32_t state = 0;
  for (std::size_t li = 0; li < spec.layers.size(); ++li) {
    const Layer& l = spec.layers[li];
    std::size_t first = 0;
    while (pieces[first].owner != li) ++first;
    const std::uint32_t lp = Pad(l.out);
    max_pad = std::max(max_pad, lp);
    if (l.kind == LayerKind::kDense) {
      m.layers_.push_back(kernel_pieces[first]);
      continue;
    }
    const std::size_t at_part = m.parts_.size();
    for (std::size_t pi = first; pi < pieces.size() && pieces[pi].owner == li; ++pi) {
      m.parts_.push_back(kernel_pieces[pi]);
      m.max_gate_pad_ = std::max(m.max_gate_pad_, kernel_pieces[pi].out_pad);
    }
    m.max_hidden_pad_ = std::max(m.max_hidden_pad_, lp);
    m.layers_.push_back(detail::KernelLayer{nullptr, nullptr, l.in, l.out, lp, 0, 0.0f,
                                            static_cast<std::uint32_t>(l.kind), l.linear_before_reset ? 1u : 0u,
                                            m.parts_.data() + at_part, state});
    state += (l.kind == LayerKind::kLstm ? 2 : 1) * lp;
  }
  m.state_floats_ = state;
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
  for (Layer& l : m.description_.layers) {
    for (std::vector<float>* v : {&l.weight, &l.bias, &l.recurrent_weight, &l.recurrent_bias}) {
      v->clear();
      v->shrink_to_fit();
    }
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
  const std::size_t off_state = plan.Floats(model.state_size());
  const std::size_t off_gx = plan.Floats(model.max_gate_pad()), off_gh = plan.Floats(model.max_gate_pad());
  const std::size_t off_rh = plan.Floats(model.max_hidden_pad()), off_gt = plan.Floats(model.max_hidden_pad());
  PolicyData d;
  d.arena_ = AlignedBlock(plan.bytes());  // zeroed: the state starts clean, padding stays zero
  std::byte* base = d.arena_.data();
  auto at = [base](std::size_t off) { return reinterpret_cast<float*>(base + off); };
  d.view_ = detail::DataView{at(off_obs),   at(off_x),  at(off_ping), at(off_pong), at(off_act),
                             at(off_state), at(off_gx), at(off_gh),   at(off_rh),   at(off_gt)};
  d.state_size_ = model.state_size();
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

void PolicyData::ResetState() noexcept {
  std::fill_n(view_.state, state_size_, 0.0f);
}

void SetEigenMallocAllowed(bool allowed) noexcept {
#ifdef EIGEN_RUNTIME_NO_MALLOC
  Eigen::internal::set_is_malloc_allowed(allowed);
#else
  (void)allowed;
#endif
}

}  // namespace pbppo::policy
