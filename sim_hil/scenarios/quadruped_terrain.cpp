#include "sim_hil/scenarios/quadruped_terrain.hpp"

#include <algorithm>

namespace pbppo::sim {

void GenerateBlocks(const BlockField& f, Rng& rng, std::vector<TerrainBlock>& out) {
  out.clear();
  const double half = f.half_size_m, r2 = f.clear_radius_m * f.clear_radius_m;
  for (int b = 0; b < f.blocks; ++b) {
    const double cx = rng.Uniform(-half, half), cy = rng.Uniform(-half, half);
    const double sx = rng.Uniform(f.size_m[0], f.size_m[1]);
    const double sy = rng.Uniform(f.size_m[0], f.size_m[1]);
    const double h = rng.Uniform(f.height_m[0], f.height_m[1]);
    const TerrainBlock k{cx - sx / 2, cx + sx / 2, cy - sy / 2, cy + sy / 2, h};
    // The start area stays flat: a block reaching into it is left out.
    const double dx = std::max({k.x0, -k.x1, 0.0}), dy = std::max({k.y0, -k.y1, 0.0});
    if (dx * dx + dy * dy < r2) continue;
    out.push_back(k);
  }
}

double TerrainHeight(const std::vector<TerrainBlock>& blocks, double x, double y) noexcept {
  double h = 0.0;
  for (const TerrainBlock& b : blocks)
    if (x >= b.x0 && x <= b.x1 && y >= b.y0 && y <= b.y1) h = std::max(h, b.height);
  return h;
}

}  // namespace pbppo::sim
