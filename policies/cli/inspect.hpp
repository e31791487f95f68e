// `pbppo inspect` and `pbppo synth`: look into a blob, make a random one of a given shape.
#pragma once

#include <cstdint>
#include <string>

namespace pbppo::cli {

// `weights`: with `json`, each layer object also carries "weight" (row-major [out][in], flat) and "bias".
int Inspect(const std::string& path, bool json, bool weights = false);

struct SynthOptions {
  std::string widths = "48-512-256-128-12";
  std::string activation = "elu";
  std::uint64_t seed = 1;
  std::string out;
  std::size_t golden_rows = 32;
  std::string layout;  // an io_layout.yaml: its names, hash and action map (widths must fit it)
};
int Synth(const SynthOptions& o);

}  // namespace pbppo::cli
