// Obstacle layouts of the AUV navigation task (models/auv/layouts/*.yaml): the arena with its
// boundary walls, fixed obstacles, the start region, the targets visited in order, and how many
// random extra obstacles each episode adds. Set-up time only.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "runtime/core/result.hpp"
#include "runtime/robot/yaml_fields.hpp"
#include "sim_hil/scenarios/auv_sonar.hpp"

namespace pbppo::sim {

struct AuvStartRegion {
  std::array<double, 2> x_m{0.0, 0.0};
  std::array<double, 2> y_m{0.0, 0.0};
  std::array<double, 2> yaw_rad{0.0, 0.0};
};

// Per episode: count in [count[0], count[1]] circles of radius in radius_m, each kept
// clearance_m away from the start region, the targets, the walls and every other obstacle.
struct AuvRandomObstacles {
  std::array<int, 2> count{0, 0};
  std::array<double, 2> radius_m{0.5, 1.0};
  double clearance_m = 3.0;
};

struct AuvLayout {
  std::string name;
  World2d world;  // arena and fixed obstacles
  AuvStartRegion start;
  std::vector<std::array<double, 2>> targets;  // (x, y), visited in order
  AuvRandomObstacles random_obstacles;
};

// Parses and validates; errors name the file, the element (obstacles[2]) and the field.
Result<AuvLayout> LoadAuvLayout(const std::string& path);
Result<AuvLayout> ParseAuvLayout(const std::string& yaml_text, const std::string& origin);
Result<AuvLayout> ParseAuvLayout(const YAML::Node& root, const std::string& origin);

}  // namespace pbppo::sim
