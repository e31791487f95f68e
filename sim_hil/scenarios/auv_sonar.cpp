#include "sim_hil/scenarios/auv_sonar.hpp"

#include <algorithm>
#include <cmath>

namespace pbppo::sim {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

double RayCircle(double ox, double oy, double dx, double dy, const Circle& c) noexcept {
  // |o + t d - c|^2 = r^2 with |d| = 1: t^2 + 2 b t + k = 0.
  const double px = ox - c.x_m, py = oy - c.y_m;
  const double k = px * px + py * py - c.radius_m * c.radius_m;
  if (k <= 0.0) return 0.0;
  const double b = px * dx + py * dy;
  if (b >= 0.0) return kNoHit;  // outside and moving away
  const double disc = b * b - k;
  if (disc < 0.0) return kNoHit;
  // The nearer root, in the cancellation-free form k / (-b + sqrt(disc)).
  return k / (-b + std::sqrt(disc));
}

double RayBox(double ox, double oy, double dx, double dy, const Box& b) noexcept {
  if (ox >= b.x_min_m && ox <= b.x_max_m && oy >= b.y_min_m && oy <= b.y_max_m) return 0.0;
  double t_near = 0.0, t_far = kNoHit;
  const double o[2] = {ox, oy}, d[2] = {dx, dy}, lo[2] = {b.x_min_m, b.y_min_m}, hi[2] = {b.x_max_m, b.y_max_m};
  for (int a = 0; a < 2; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < lo[a] || o[a] > hi[a]) return kNoHit;
      continue;
    }
    double t0 = (lo[a] - o[a]) / d[a], t1 = (hi[a] - o[a]) / d[a];
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0);
    t_far = std::min(t_far, t1);
    if (t_near > t_far) return kNoHit;
  }
  return t_near;
}

double RayArena(double ox, double oy, double dx, double dy, const Arena& a) noexcept {
  if (!(ox > a.x_min_m && ox < a.x_max_m && oy > a.y_min_m && oy < a.y_max_m)) return 0.0;
  double t = kNoHit;
  if (dx > 0.0) t = std::min(t, (a.x_max_m - ox) / dx);
  if (dx < 0.0) t = std::min(t, (a.x_min_m - ox) / dx);
  if (dy > 0.0) t = std::min(t, (a.y_max_m - oy) / dy);
  if (dy < 0.0) t = std::min(t, (a.y_min_m - oy) / dy);
  return t;
}

double CastRay(const World2d& w, double ox, double oy, double angle_rad, double max_range_m) noexcept {
  const double dx = std::cos(angle_rad), dy = std::sin(angle_rad);
  double t = std::min(max_range_m, RayArena(ox, oy, dx, dy, w.arena));
  for (const Circle& c : w.circles) t = std::min(t, RayCircle(ox, oy, dx, dy, c));
  for (const Box& b : w.boxes) t = std::min(t, RayBox(ox, oy, dx, dy, b));
  return t;
}

double BeamAngle(const SonarParams& p, int i) noexcept {
  if (p.fov_rad >= 2.0 * kPi - 1e-9) return WrapAngle(2.0 * kPi * i / p.beams);
  if (p.beams <= 1) return 0.0;
  return -0.5 * p.fov_rad + p.fov_rad * i / (p.beams - 1);
}

int SonarRaysPerBeam(const SonarParams& p) noexcept {
  return p.beam_width_rad > 0.0 ? std::max(p.rays_per_beam, 1) : 1;
}

namespace {

// Ray k's angle from its beam's axis (0 for a single ray).
double RayOffset(const SonarParams& p, int rays, int k) noexcept {
  return (k + 0.5) * p.beam_width_rad / rays - 0.5 * p.beam_width_rad;
}

}  // namespace

double SonarRayAngle(const SonarParams& p, int beam, int ray) noexcept {
  return BeamAngle(p, beam) + RayOffset(p, SonarRaysPerBeam(p), ray);
}

void SonarScan(const World2d& w, const SonarParams& p, double x, double y, double yaw, double* ranges,
               double* ray_ranges) noexcept {
  const int rays = SonarRaysPerBeam(p);
  for (int i = 0; i < p.beams; ++i) {
    const double axis = yaw + BeamAngle(p, i);
    double r = p.max_range_m;
    for (int k = 0; k < rays; ++k) {
      const double ray = CastRay(w, x, y, axis + RayOffset(p, rays, k), p.max_range_m);
      if (ray_ranges != nullptr) ray_ranges[i * rays + k] = ray;
      r = std::min(r, ray);
    }
    ranges[i] = r;
  }
}

double Clearance(const World2d& w, double x, double y) noexcept {
  const Arena& a = w.arena;
  double d = std::min(std::min(x - a.x_min_m, a.x_max_m - x), std::min(y - a.y_min_m, a.y_max_m - y));
  for (const Circle& c : w.circles) d = std::min(d, std::hypot(x - c.x_m, y - c.y_m) - c.radius_m);
  for (const Box& b : w.boxes) {
    // Signed distance to an axis-aligned box.
    const double qx = std::max(b.x_min_m - x, x - b.x_max_m), qy = std::max(b.y_min_m - y, y - b.y_max_m);
    const double outside = std::hypot(std::max(qx, 0.0), std::max(qy, 0.0));
    const double inside = std::min(std::max(qx, qy), 0.0);
    d = std::min(d, outside + inside);
  }
  return d;
}

double WrapAngle(double a) noexcept {
  a = std::remainder(a, 2.0 * kPi);  // [-pi, pi]
  return a <= -kPi ? a + 2.0 * kPi : a;
}

}  // namespace pbppo::sim
