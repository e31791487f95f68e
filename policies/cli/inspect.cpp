#include "policies/cli/inspect.hpp"

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "runtime/core/crc32.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/reference.hpp"
#include "runtime/robot/io_layout.hpp"

namespace pbppo::cli {
namespace {

using policy::PolicySpec;

std::string Hex64(std::uint64_t v) {
  char b[24];
  std::snprintf(b, sizeof b, "0x%016llx", static_cast<unsigned long long>(v));
  return b;
}

std::string ShapeLine(const PolicySpec& s) {
  std::string t = std::to_string(s.input_size);
  for (const auto& l : s.layers) {
    if (l.kind != policy::LayerKind::kDense) {
      t += " -> " + std::string(policy::ToString(l.kind)) + " " + std::to_string(l.out) +
           (l.linear_before_reset ? "(linear_before_reset)" : "");
      continue;
    }
    t += " -> " + std::to_string(l.out) + " " + policy::ToString(l.activation);
    if (l.activation == policy::Activation::kLeakyRelu) {
      char a[40];
      std::snprintf(a, sizeof a, "(alpha=%g)", static_cast<double>(l.alpha));
      t += a;
    }
  }
  return t;
}

// The format version the file states (the loader checked it).
std::uint32_t FileVersion(const std::vector<std::uint8_t>& bytes) {
  std::uint32_t v = 0;
  std::memcpy(&v, bytes.data() + policy::kOffVersion, 4);
  return v;
}

nlohmann::json ToJson(const PolicySpec& s, std::uint32_t version, std::size_t file_bytes, std::uint32_t crc,
                      bool weights) {
  nlohmann::json j;
  j["format_version"] = version;
  j["file_bytes"] = file_bytes;
  j["crc32"] = crc;
  j["input_size"] = s.input_size;
  j["output_size"] = s.output_size;
  j["parameter_count"] = s.ParameterCount();
  j["layers"] = nlohmann::json::array();
  for (const auto& l : s.layers) {
    j["layers"].push_back({{"kind", policy::ToString(l.kind)},
                           {"in", l.in},
                           {"out", l.out},
                           {"activation", policy::ToString(l.activation)}});
    if (l.activation == policy::Activation::kLeakyRelu) j["layers"].back()["alpha"] = l.alpha;
    if (l.kind == policy::LayerKind::kGru) j["layers"].back()["linear_before_reset"] = l.linear_before_reset;
    if (weights) {
      j["layers"].back()["weight"] = l.weight;  // row-major [gates * out][in]
      j["layers"].back()["bias"] = l.bias;
      if (l.kind != policy::LayerKind::kDense) {
        j["layers"].back()["recurrent_weight"] = l.recurrent_weight;  // row-major [gates * out][out]
        j["layers"].back()["recurrent_bias"] = l.recurrent_bias;
      }
    }
  }
  j["normaliser"] = {{"mean", s.obs_mean}, {"inv_std", s.obs_inv_std}, {"clip", s.obs_clip}};
  j["action_head"] = policy::ToString(s.action_head);
  j["action_map"] = {
      {"scale", s.action_scale}, {"offset", s.action_offset}, {"low", s.action_low}, {"high", s.action_high}};
  j["io_layout_hash"] = Hex64(s.io_layout_hash);
  j["observation_names"] = s.observation_names;
  j["action_names"] = s.action_names;
  const auto& p = s.provenance;
  j["provenance"] = {{"trainer_version", p.trainer_version},
                     {"git_revision", p.git_revision},
                     {"environment", p.environment},
                     {"clip_schedule", p.clip_schedule},
                     {"seed", p.seed},
                     {"env_steps", p.env_steps},
                     {"final_return", p.final_return}};
  return j;
}

}  // namespace

int Inspect(const std::string& path, bool json, bool weights) {
  auto read = policy::ReadFileBytes(path, policy::BlobLimits{}.max_file_bytes);
  if (!read) {
    std::fprintf(stderr, "pbppo inspect: %s\n", read.error().message.c_str());
    return 1;
  }
  const std::vector<std::uint8_t>& bytes = *read;
  auto spec = policy::DecodeBlob(bytes);
  if (!spec) {
    std::fprintf(stderr, "pbppo inspect: %s: %s\n", path.c_str(), spec.error().message.c_str());
    return 1;
  }
  const PolicySpec& s = *spec;
  std::uint32_t crc = 0;
  std::memcpy(&crc, bytes.data() + bytes.size() - 4, 4);
  if (json) {
    std::cout << ToJson(s, FileVersion(bytes), bytes.size(), crc, weights).dump(2) << "\n";
    return 0;
  }
  std::printf("policy blob   %s\n", path.c_str());
  std::printf("  format      v%u, %zu bytes, crc32 0x%08x (verified)\n", FileVersion(bytes), bytes.size(), crc);
  std::printf("  network     %s\n", ShapeLine(s).c_str());
  std::printf("  parameters  %llu (%.1f KiB of float32 weights)\n", static_cast<unsigned long long>(s.ParameterCount()),
              static_cast<double>(s.ParameterCount()) * 4.0 / 1024.0);
  if (s.Recurrent())
    std::printf("  state       %llu floats carried from one step to the next (zero at arming)\n",
                static_cast<unsigned long long>(s.StateSize()));
  std::printf("  head        %s mean, action = clamp(head(y) * scale + offset, low, high)\n",
              policy::ToString(s.action_head));
  std::printf("  io layout   hash %s\n", Hex64(s.io_layout_hash).c_str());
  std::printf("  observations (%u), normalised as clamp((obs - mean) * inv_std, -%g, %g):\n", s.input_size,
              static_cast<double>(s.obs_clip), static_cast<double>(s.obs_clip));
  for (std::size_t i = 0; i < s.input_size; ++i) {
    std::printf("    %3zu %-28s mean %11.5g  inv_std %11.5g\n", i, s.observation_names[i].c_str(),
                static_cast<double>(s.obs_mean[i]), static_cast<double>(s.obs_inv_std[i]));
  }
  std::printf("  actions (%u):\n", s.output_size);
  for (std::size_t i = 0; i < s.output_size; ++i) {
    std::printf("    %3zu %-28s scale %9.4g  offset %9.4g  range [%g, %g]\n", i, s.action_names[i].c_str(),
                static_cast<double>(s.action_scale[i]), static_cast<double>(s.action_offset[i]),
                static_cast<double>(s.action_low[i]), static_cast<double>(s.action_high[i]));
  }
  const auto& p = s.provenance;
  std::printf("  provenance\n");
  std::printf("    trainer     %s (git %s)\n", p.trainer_version.c_str(),
              p.git_revision.empty() ? "-" : p.git_revision.c_str());
  std::printf("    environment %s\n", p.environment.c_str());
  std::printf("    schedule    %s\n", p.clip_schedule.c_str());
  std::printf("    seed        %llu\n", static_cast<unsigned long long>(p.seed));
  std::printf("    env steps   %llu\n", static_cast<unsigned long long>(p.env_steps));
  std::printf("    final return %g\n", p.final_return);
  return 0;
}

int Synth(const SynthOptions& o) {
  std::vector<std::uint32_t> widths;
  std::stringstream ss(o.widths);
  std::string part;
  while (std::getline(ss, part, '-')) {
    char* end = nullptr;
    const unsigned long v = std::strtoul(part.c_str(), &end, 10);
    if (part.empty() || *end != '\0' || v == 0 || v > 100000) {
      std::fprintf(stderr, "pbppo synth: --widths: '%s' is not a positive width in '%s'\n", part.c_str(),
                   o.widths.c_str());
      return 2;
    }
    widths.push_back(static_cast<std::uint32_t>(v));
  }
  if (widths.size() < 2) {
    std::fprintf(stderr, "pbppo synth: --widths '%s' needs at least input and output, e.g. 24-64-64-2\n",
                 o.widths.c_str());
    return 2;
  }
  policy::Activation act{};
  if (!policy::ParseActivation(o.activation, &act)) {
    std::fprintf(stderr, "pbppo synth: --activation '%s' unknown (identity, tanh, elu, relu, leaky_relu)\n",
                 o.activation.c_str());
    return 2;
  }
  PolicySpec spec = policy::MakeRandomSpec(widths, act, o.seed);
  if (!o.layout.empty()) {  // the layout's names, hash and action map: a blob a robot's controller takes
    auto layout = robot::LoadIoLayout(o.layout);
    if (!layout) {
      std::fprintf(stderr, "pbppo synth: --layout: %s\n", layout.error().message.c_str());
      return 2;
    }
    if (widths.front() != layout->observation_size() || widths.back() != layout->action_size()) {
      std::fprintf(stderr,
                   "pbppo synth: --widths '%s': layout '%s' has %u observations and %u actions: the widths must "
                   "start with %u and end with %u\n",
                   o.widths.c_str(), o.layout.c_str(), layout->observation_size(), layout->action_size(),
                   layout->observation_size(), layout->action_size());
      return 2;
    }
    robot::ApplyLayoutToSpec(*layout, spec);
  }
  if (auto st = policy::WritePolicyFiles(o.out, spec, policy::MakeGoldenVectors(spec, o.golden_rows, o.seed + 1));
      !st) {
    std::fprintf(stderr, "pbppo synth: %s\n", st.error().message.c_str());
    return 1;
  }
  std::printf("wrote %s and %s\n", o.out.c_str(), policy::GoldenPathFor(o.out).c_str());
  return 0;
}

}  // namespace pbppo::cli
