// Sonar ray casting and clearance against hand-computed geometry.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "sim_hil/scenarios/auv_sonar.hpp"

using namespace pbppo::sim;

namespace {
constexpr double kPi = 3.14159265358979323846;
}

TEST_CASE("sonar: walls of an empty arena at known distances") {
  World2d w;  // arena [0, 40] x [0, 40]
  SonarParams p{16, 2 * kPi, 50.0};
  std::vector<double> r(16);
  SonarScan(w, p, 10.0, 20.0, 0.0, r.data());
  CHECK(r[0] == doctest::Approx(30.0));   // ahead: east wall
  CHECK(r[4] == doctest::Approx(20.0));   // port (90 deg): north wall
  CHECK(r[8] == doctest::Approx(10.0));   // astern: west wall
  CHECK(r[12] == doctest::Approx(20.0));  // starboard: south wall
  // 45 deg: the north wall at 20 / sin 45, nearer than the east wall at 30 / cos 45.
  CHECK(r[2] == doctest::Approx(20.0 * std::sqrt(2.0)));
  // Heading rotates the beams: facing north, beam 0 sees the north wall.
  SonarScan(w, p, 10.0, 20.0, kPi / 2, r.data());
  CHECK(r[0] == doctest::Approx(20.0));
  CHECK(r[4] == doctest::Approx(10.0));
}

TEST_CASE("sonar: ranges are clipped at the maximum range") {
  World2d w;
  SonarParams p{16, 2 * kPi, 15.0};
  std::vector<double> r(16);
  SonarScan(w, p, 10.0, 20.0, 0.0, r.data());
  CHECK(r[0] == 15.0);
  CHECK(r[8] == doctest::Approx(10.0));
  CHECK(CastRay(w, 10.0, 20.0, 0.0, 15.0) == 15.0);
}

TEST_CASE("sonar: an obstacle on a beam") {
  World2d w;
  w.circles.push_back(Circle{15.0, 20.0, 1.0});
  w.boxes.push_back(Box{9.0, 11.0, 24.0, 30.0});
  SonarParams p{16, 2 * kPi, 50.0};
  std::vector<double> r(16);
  SonarScan(w, p, 10.0, 20.0, 0.0, r.data());
  CHECK(r[0] == doctest::Approx(4.0));  // circle surface at x = 14
  CHECK(r[4] == doctest::Approx(4.0));  // box bottom at y = 24
  CHECK(r[8] == doctest::Approx(10.0));
  // A circle off the beam axis: centre 5 m away along (0.6, 0.8), radius 1 -> hit at 4 m.
  CHECK(RayCircle(0.0, 0.0, 0.6, 0.8, Circle{3.0, 4.0, 1.0}) == doctest::Approx(4.0));
  // Grazing at 1 m lateral offset, radius 1: tangent hit at 5 m; further off: a miss.
  CHECK(RayCircle(0.0, 0.0, 1.0, 0.0, Circle{5.0, 1.0, 1.0}) == doctest::Approx(5.0));
  CHECK(RayCircle(0.0, 0.0, 1.0, 0.0, Circle{5.0, 1.01, 1.0}) == kNoHit);
  CHECK(RayCircle(0.0, 0.0, -1.0, 0.0, Circle{5.0, 0.0, 1.0}) == kNoHit);  // behind
  CHECK(RayCircle(5.0, 0.2, 1.0, 0.0, Circle{5.0, 0.0, 1.0}) == 0.0);      // inside
  // Box from a diagonal: (0, 0) towards 45 deg hits the box [2, 3] x [1, 5] at x = 2.
  const double s = std::sqrt(0.5);
  CHECK(RayBox(0.0, 0.0, s, s, Box{2.0, 3.0, 1.0, 5.0}) == doctest::Approx(2.0 * std::sqrt(2.0)));
  CHECK(RayBox(0.0, 0.0, 1.0, 0.0, Box{2.0, 3.0, 1.0, 5.0}) == kNoHit);
  CHECK(RayBox(0.0, 0.0, 0.0, 1.0, Box{-1.0, 1.0, 3.0, 5.0}) == doctest::Approx(3.0));  // axis-parallel
}

TEST_CASE("sonar: a beam with a width reports the nearest echo within it - thin rays miss what lies between") {
  World2d w;
  // A 0.4 m column 5 m away, 11.25 deg off the bow: half-way between beams 0 and 1 of a ring of 16.
  const double bearing = kPi / 16, d = 5.0;
  w.circles.push_back(Circle{20.0 + d * std::cos(bearing), 20.0 + d * std::sin(bearing), 0.4});
  SonarParams thin{16, 2 * kPi, 15.0};
  std::vector<double> r(16);
  SonarScan(w, thin, 20.0, 20.0, 0.0, r.data());
  CHECK(r[0] == doctest::Approx(15.0));  // both neighbouring beams pass it by
  CHECK(r[1] == doctest::Approx(15.0));
  SonarParams wide = thin;
  wide.beam_width_rad = 2 * kPi / 16;  // the beams tile the circle
  wide.rays_per_beam = 5;              // rays at -9, -4.5, 0, 4.5, 9 deg off each axis
  SonarScan(w, wide, 20.0, 20.0, 0.0, r.data());
  // Beam 1's ray at -9 deg passes 2.25 deg off the column's centre: 5 sin(2.25 deg) = 0.2 m.
  const double off = d * std::sin(kPi / 16 - 0.4 * kPi / 8);
  CHECK(r[1] == doctest::Approx(d * std::cos(kPi / 16 - 0.4 * kPi / 8) - std::sqrt(0.16 - off * off)));
  CHECK(r[0] == doctest::Approx(r[1]));  // the mirror ray of beam 0, +9 deg
  for (int i = 2; i < 16; ++i) CHECK(r[static_cast<std::size_t>(i)] < 15.0 + 1e-12);
  // Each range is the shortest of the beam's rays; one ray (or width 0) is the thin beam.
  for (int i = 0; i < 16; ++i) {
    double shortest = 15.0;
    for (int k = 0; k < 5; ++k)
      shortest = std::min(shortest, CastRay(w, 20.0, 20.0, BeamAngle(wide, i) + (k - 2) * 0.2 * kPi / 8, 15.0));
    CHECK(r[static_cast<std::size_t>(i)] == shortest);
  }
  wide.rays_per_beam = 1;
  std::vector<double> one(16);
  SonarScan(w, wide, 20.0, 20.0, 0.0, one.data());
  SonarScan(w, thin, 20.0, 20.0, 0.0, r.data());
  CHECK(one == r);
}

namespace {

// The points where the scan's receive rays from (x, y, yaw) found a surface.
std::vector<std::array<double, 2>> ReturnPoints(const World2d& w, const SonarParams& p, double x, double y,
                                                double yaw) {
  const int rays = SonarRaysPerBeam(p);
  std::vector<double> beams(static_cast<std::size_t>(p.beams)), each(static_cast<std::size_t>(p.beams * rays));
  SonarScan(w, p, x, y, yaw, beams.data(), each.data());
  std::vector<std::array<double, 2>> points;
  for (int i = 0; i < p.beams; ++i) {
    double least = p.max_range_m;
    for (int k = 0; k < rays; ++k) {
      const double r = each[static_cast<std::size_t>(i * rays + k)];
      least = std::min(least, r);
      if (r >= p.max_range_m) continue;
      const double a = yaw + SonarRayAngle(p, i, k);
      points.push_back({x + r * std::cos(a), y + r * std::sin(a)});
    }
    CHECK(beams[static_cast<std::size_t>(i)] == least);  // a beam reports its shortest ray
  }
  return points;
}

// How many of the points lie on the circle's surface.
int On(const std::vector<std::array<double, 2>>& points, const Circle& c) {
  int n = 0;
  for (const auto& q : points) n += std::abs(std::hypot(q[0] - c.x_m, q[1] - c.y_m) - c.radius_m) < 1e-9 ? 1 : 0;
  return n;
}

}  // namespace

TEST_CASE(
    "sonar: per-ray returns lie on the first surface each ray meets - not between thin beams, behind "
    "another obstacle or out of range") {
  World2d w;
  // The column between beams 0 and 1 again, and a second one hidden behind a bigger column.
  const double bearing = kPi / 16, d = 5.0;
  const Circle between{20.0 + d * std::cos(bearing), 20.0 + d * std::sin(bearing), 0.4};
  const Circle screen{20.0, 26.0, 1.5}, hidden{20.0, 30.0, 0.5}, far{20.0, 4.0, 0.5};
  w.circles = {between, screen, hidden, far};
  SonarParams thin{16, 2 * kPi, 15.0};
  SonarParams wide = thin;
  wide.beam_width_rad = 2 * kPi / 16;
  wide.rays_per_beam = 5;
  CHECK(SonarRaysPerBeam(thin) == 1);
  CHECK(SonarRaysPerBeam(wide) == 5);
  CHECK(SonarRayAngle(thin, 3, 0) == BeamAngle(thin, 3));
  CHECK(SonarRayAngle(wide, 0, 2) == doctest::Approx(0.0));  // the middle ray is the axis
  CHECK(SonarRayAngle(wide, 0, 0) == doctest::Approx(-2 * kPi / 16 * 0.4));
  const auto thin_points = ReturnPoints(w, thin, 20.0, 20.0, 0.0);
  const auto wide_points = ReturnPoints(w, wide, 20.0, 20.0, 0.0);
  CHECK(On(thin_points, between) == 0);
  CHECK(On(wide_points, between) >= 1);
  CHECK(On(thin_points, screen) == 1);  // beam 4 (90 deg) hits it at 4.5 m
  CHECK(On(wide_points, screen) >= 5);
  CHECK(On(wide_points, hidden) == 0);                          // behind the screen
  CHECK(On(wide_points, far) == 0);                             // 15.5 m: beyond 15 m
  CHECK(On(ReturnPoints(w, wide, 20.0, 19.0, 0.0), far) >= 1);  // 14.5 m
  // Turning the vehicle moves the thin beams onto the column between them.
  CHECK(On(ReturnPoints(w, thin, 20.0, 20.0, bearing), between) == 1);
  // The walls are 20 m away: every return is from one of the two columns in reach.
  CHECK(On(wide_points, between) + On(wide_points, screen) == static_cast<int>(wide_points.size()));
}

TEST_CASE("sonar: a forward fan spreads its beams evenly across the field of view") {
  SonarParams fan{5, kPi / 2, 20.0};
  CHECK(BeamAngle(fan, 0) == doctest::Approx(-kPi / 4));
  CHECK(BeamAngle(fan, 2) == doctest::Approx(0.0));
  CHECK(BeamAngle(fan, 4) == doctest::Approx(kPi / 4));
  SonarParams ring{16, 2 * kPi, 20.0};
  CHECK(BeamAngle(ring, 1) == doctest::Approx(kPi / 8));
  CHECK(BeamAngle(ring, 12) == doctest::Approx(-kPi / 2));
  World2d w;
  std::vector<double> r(5);
  SonarScan(w, fan, 20.0, 20.0, 0.0, r.data());
  CHECK(r[2] == doctest::Approx(20.0));  // east wall 20 m ahead, at max range
  CHECK(r[0] == doctest::Approx(20.0));  // clipped
  CHECK(CastRay(w, 35.0, 20.0, -kPi / 4, 50.0) == doctest::Approx(5.0 * std::sqrt(2.0)));
}

TEST_CASE("sonar: clearance is the signed distance to the nearest surface") {
  World2d w;
  CHECK(Clearance(w, 1.0, 20.0) == doctest::Approx(1.0));
  CHECK(Clearance(w, 20.0, 39.5) == doctest::Approx(0.5));
  CHECK(Clearance(w, -1.0, 20.0) == doctest::Approx(-1.0));
  w.circles.push_back(Circle{20.0, 20.0, 2.0});
  CHECK(Clearance(w, 25.0, 20.0) == doctest::Approx(3.0));
  CHECK(Clearance(w, 20.5, 20.0) == doctest::Approx(-1.5));
  w.boxes.push_back(Box{5.0, 7.0, 5.0, 7.0});
  CHECK(Clearance(w, 10.0, 11.0) == doctest::Approx(5.0));  // from the corner (7, 7): 3-4-5
  CHECK(Clearance(w, 6.0, 9.0) == doctest::Approx(2.0));    // from the top face
  CHECK(Clearance(w, 6.0, 6.5) == doctest::Approx(-0.5));   // inside, nearest face at y = 7
}

TEST_CASE("sonar: angle wrapping") {
  CHECK(WrapAngle(3 * kPi / 2) == doctest::Approx(-kPi / 2));
  CHECK(WrapAngle(-3 * kPi / 2) == doctest::Approx(kPi / 2));
  CHECK(WrapAngle(kPi) == doctest::Approx(kPi));
  CHECK(WrapAngle(-kPi) == doctest::Approx(kPi));
  CHECK(WrapAngle(0.3) == 0.3);
}
