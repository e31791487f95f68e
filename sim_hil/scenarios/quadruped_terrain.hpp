// The quadruped's discrete terrain: axis-aligned blocks standing on a flat floor (z = 0), drawn
// at random in a square field with the start area kept clear. One generator for the training
// environment (policies/envs/quadruped_walk) and the HIL plant (sim_hil/plants/quadruped_plant),
// so that the same parameters and seed give the same blocks in MuJoCo and in Simbody.
#pragma once

#include <vector>

#include "runtime/core/random.hpp"

namespace pbppo::sim {

struct TerrainBlock {
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;  // footprint, m
  double height = 0;                      // top face, m above the floor
};

struct BlockField {
  double half_size_m = 10.0;          // blocks are centred in [-half, half]^2
  int blocks = 300;                   // drawn (those reaching into the clear start area are left out)
  double size_m[2] = {0.3, 1.0};      // each side U(size)
  double height_m[2] = {0.05, 0.15};  // U(height)
  double clear_radius_m = 0.8;        // no block within this of the origin
};

// Draws the field's blocks with `rng` (appended to `out`, which is cleared first).
void GenerateBlocks(const BlockField& field, Rng& rng, std::vector<TerrainBlock>& out);

// The terrain height at (x, y): the highest block top there, else the floor (0).
double TerrainHeight(const std::vector<TerrainBlock>& blocks, double x, double y) noexcept;

}  // namespace pbppo::sim
