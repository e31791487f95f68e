// 2-D geometry of the AUV task in the horizontal plane: obstacles (vertical circular columns and
// axis-aligned boxes), the arena's boundary walls, ray casting for the sonar and the clearance
// used for collisions. Pure functions; no allocation.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

namespace pbppo::sim {

struct Circle {
  double x_m = 0.0, y_m = 0.0, radius_m = 0.0;
};

struct Box {
  double x_min_m = 0.0, x_max_m = 0.0, y_min_m = 0.0, y_max_m = 0.0;
};

// The walls enclose [x_min, x_max] x [y_min, y_max].
struct Arena {
  double x_min_m = 0.0, x_max_m = 40.0, y_min_m = 0.0, y_max_m = 40.0;
};

struct World2d {
  Arena arena;
  std::vector<Circle> circles;
  std::vector<Box> boxes;
};

struct SonarParams {
  int beams = 16;
  double fov_rad = 6.283185307179586;  // 2 pi: evenly around; less: a forward fan
  double max_range_m = 15.0;
  // A beam's width: it reports the nearest echo within +-width/2 of its axis, found with
  // rays_per_beam rays at the centres of equal slices of the width. Width 0 (or one ray): a thin
  // ray along the axis.
  double beam_width_rad = 0.0;
  int rays_per_beam = 1;
};

constexpr double kNoHit = std::numeric_limits<double>::infinity();

// Distance along the unit direction (dx, dy) from (ox, oy) to the first surface point; 0 when the
// origin is inside the shape (or on its surface), kNoHit when the ray misses.
double RayCircle(double ox, double oy, double dx, double dy, const Circle& c) noexcept;
double RayBox(double ox, double oy, double dx, double dy, const Box& b) noexcept;
// Distance to the boundary wall from inside the arena; 0 from outside or on a wall.
double RayArena(double ox, double oy, double dx, double dy, const Arena& a) noexcept;
// The nearest hit over walls and obstacles along the world-frame angle, clipped at max_range_m.
double CastRay(const World2d& w, double ox, double oy, double angle_rad, double max_range_m) noexcept;

// Beam i's angle relative to the heading: full circle i * 2 pi / n (beam 0 ahead, counter-
// clockwise); a fan -fov/2 + i * fov / (n - 1) (a single beam looks straight ahead).
double BeamAngle(const SonarParams& p, int i) noexcept;
// A beam's rays: one along the axis for a thin beam (width 0), otherwise rays_per_beam (at least
// one). SonarRayAngle is ray k of beam i's angle relative to the heading: the beam's axis plus
// the centre of the k-th of equal slices of its width.
int SonarRaysPerBeam(const SonarParams& p) noexcept;
double SonarRayAngle(const SonarParams& p, int beam, int ray) noexcept;
// ranges[i] for every beam from pose (x, y, yaw): the shortest of the beam's rays. With ray_ranges,
// also every ray's own range there (beams * SonarRaysPerBeam values, beam by beam): the returns
// of the sonar's narrow receive beams, which the mission computer maps (a range below
// max_range_m is an echo from the surface at that distance along the ray).
void SonarScan(const World2d& w, const SonarParams& p, double x, double y, double yaw, double* ranges,
               double* ray_ranges = nullptr) noexcept;

// Signed distance from the point to the nearest obstacle surface or wall (negative inside an
// obstacle or outside the arena).
double Clearance(const World2d& w, double x, double y) noexcept;

// Wraps an angle to (-pi, pi].
double WrapAngle(double a) noexcept;

}  // namespace pbppo::sim
