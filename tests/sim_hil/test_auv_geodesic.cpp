// The geodesic distance field of the AUV task's optional progress term: the straight line in an
// empty arena, the detour around a wall, the dead end of the hard layout, walled-off points.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "sim_hil/scenarios/auv_geodesic.hpp"
#include "sim_hil/scenarios/auv_layout.hpp"
#include "sim_hil/scenarios/auv_sonar.hpp"

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

using namespace pbppo::sim;

TEST_CASE("geodesic field: in an empty arena it is the straight line, within the 8-neighbour grid's error") {
  World2d w;  // [0, 40] x [0, 40]
  GeodesicField f(w.arena, 0.25);
  CHECK(f.nx() == 161);
  CHECK(f.ny() == 161);
  f.Compute(w, 1.2, 20.0, 20.0);
  for (const auto& [x, y] : {std::pair{5.0, 5.0}, {35.0, 20.0}, {20.0, 33.3}, {8.1, 30.7}, {20.1, 20.0}}) {
    const double straight = std::hypot(x - 20.0, y - 20.0);
    const double g = f.Distance(x, y);
    CAPTURE(x);
    CAPTURE(y);
    CHECK(g >= straight - 1e-6);
    CHECK(g <= straight * 1.0824 + 0.25);  // 8 directions: at most 8.24 % longer
    // The path heads straight for the goal (within the grid's 22.5 degree sectors).
    const double a = f.PathAngle(x, y, 2.0);
    const double direct = std::atan2(20.0 - y, 20.0 - x);
    CHECK(std::abs(std::remainder(a - direct, 2 * 3.14159265358979323846)) < 0.41);
  }
  // Within 2.5 cells of the boundary walls the vehicle would collide: no node there is free,
  // and the nearest reachable node is more than three cells away.
  CHECK(std::isinf(f.Distance(0.2, 20.0)));
  CHECK(std::isnan(f.PathAngle(0.2, 20.0, 2.0)));
}

TEST_CASE("geodesic field: a wall with a gap makes the way round the wall the distance") {
  World2d w;
  w.boxes.push_back(Box{0.0, 30.0, 19.0, 21.0});  // a wall across, open for x in [30, 40]
  GeodesicField f(w.arena, 0.25);
  f.Compute(w, 1.2, 10.0, 30.0);
  // From (10, 10) straight up is 20 m; round the wall's end, 1.2 m off its corners, about 48 m
  // (the grid's 8 directions make it up to 8 % longer).
  const double g = f.Distance(10.0, 10.0);
  CHECK(g > 47.0);
  CHECK(g < 48.0 * 1.0824 + 2.0);  // and round the corners on grid nodes
  // The path leads to the right, towards the gap (the straight line would go up at the wall).
  CHECK(std::cos(f.PathAngle(10.0, 10.0, 2.0)) > 0.7);
  // A point walled in (a closed box around it) is unreachable.
  World2d closed;
  closed.boxes = {Box{5.0, 15.0, 5.0, 6.0}, Box{5.0, 15.0, 14.0, 15.0}, Box{5.0, 6.0, 5.0, 15.0},
                  Box{14.0, 15.0, 5.0, 15.0}};
  f.Compute(closed, 1.2, 30.0, 30.0);
  CHECK(std::isinf(f.Distance(10.0, 10.0)));
  CHECK(std::isfinite(f.Distance(20.0, 20.0)));
}

TEST_CASE("geodesic field: on the hard layout the way from T1 to T2 passes below the circle at (18, 21)") {
  auto layout = LoadAuvLayout(std::string(PBPPO_SOURCE_DIR) + "/models/auv/layouts/hard.yaml");
  REQUIRE_MESSAGE(layout.ok(), (layout.ok() ? std::string() : layout.error().message));
  const auto& t = layout->targets;
  REQUIRE(t.size() == 3);
  GeodesicField f(layout->world.arena, 0.25);
  f.Compute(layout->world, 1.2, t[1][0], t[1][1]);
  // The straight line from T1 (34, 20) to T2 (6, 30) is 29.7 m; the way is along the middle
  // corridor, below the circle, and up through the left gap: about 36 m.
  const double straight = std::hypot(t[0][0] - t[1][0], t[0][1] - t[1][1]);
  const double g = f.Distance(t[0][0], t[0][1]);
  CHECK(g > straight + 4.0);
  CHECK(g < straight + 12.0);
  // At (22, 22.5), where the straight line to T2 points up and to the left, into the 2 m gap
  // between the circle and the upper wall (impassable with l_safe 1.2 m on each side), the path
  // points down and to the left, below the circle.
  CHECK(std::sin(std::atan2(t[1][1] - 22.5, t[1][0] - 22.0)) > 0.3);
  const double a = f.PathAngle(22.0, 22.5, 2.0);
  CHECK(std::sin(a) < 0.0);
  CHECK(std::cos(a) < 0.0);
}

namespace {

// Follows the field's path (0.5 m lookahead) from (x, y) in 0.25 m steps until within 1 m of the goal; the least
// clearance on the way (infinity when the goal is not reached in 400 steps).
double PathClearance(const GeodesicField& f, const World2d& w, double x, double y, double gx, double gy) {
  double least = Clearance(w, x, y);
  for (int k = 0; k < 400; ++k) {
    if (std::hypot(gx - x, gy - y) < 1.0) return least;
    const double a = f.PathAngle(x, y, 0.5);
    if (!std::isfinite(a)) break;
    x += 0.25 * std::cos(a);
    y += 0.25 * std::sin(a);
    least = std::min(least, Clearance(w, x, y));
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace

TEST_CASE("geodesic field: a margin keeps the path off obstacles where there is room, and narrow passages open") {
  World2d w;
  w.circles.push_back(Circle{20.0, 20.0, 1.0});  // a column on the straight line
  GeodesicField f(w.arena, 0.25);
  f.Compute(w, 1.2, 35.0, 20.0);
  const double shortest = f.Distance(5.0, 20.3);
  // The shortest path grazes l_safe ...
  const double grazing = PathClearance(f, w, 5.0, 20.3, 35.0, 20.0);
  CAPTURE(grazing);
  CHECK(grazing >= 1.2 - 0.2);
  CHECK(grazing < 1.6);
  // ... the weighted one passes the column with room to spare, and its cost exceeds the length.
  f.Compute(w, 1.2, 35.0, 20.0, 1.5, 2.0);
  const double kept = PathClearance(f, w, 5.0, 20.3, 35.0, 20.0);
  CAPTURE(kept);
  CHECK(kept > 2.2);
  CHECK(f.Distance(5.0, 20.3) > shortest);
  // Far from everything a metre still costs a metre: the weighted distance between two points
  // on the far side of the column grows by their separation.
  CHECK(f.Distance(30.0, 35.0) - f.Distance(30.0, 30.0) == doctest::Approx(5.0).epsilon(0.1));
  // A corridor 4 m wide (1.6 m free between the l_safe bands, narrower than 2 (1.2 + 1.5)) stays
  // open, and the path runs along its middle.
  World2d corridor;
  corridor.boxes = {Box{0.0, 40.0, 0.0, 18.0}, Box{0.0, 40.0, 22.0, 40.0}};
  f.Compute(corridor, 1.2, 35.0, 20.0, 1.5, 2.0);
  CHECK(std::isfinite(f.Distance(5.0, 19.5)));
  CHECK(PathClearance(f, corridor, 5.0, 19.5, 35.0, 20.0) >= 1.2 - 0.2);
  CHECK(std::cos(f.PathAngle(10.0, 20.0, 2.0)) > 0.9);
}

TEST_CASE("geodesic field: points added to the chart's clearances block the path like the obstacle they lie on") {
  World2d chart;  // empty arena: the straight line from (5, 20) to (35, 20)
  World2d real = chart;
  const Circle column{20.0, 20.0, 1.0};
  real.circles.push_back(column);
  GeodesicField truth(chart.arena, 0.25), mapped(chart.arena, 0.25), base(chart.arena, 0.25);
  truth.Compute(real, 1.2, 35.0, 20.0, 2.0, 4.0);
  base.SetObstacles(chart);
  mapped.CopyObstacles(base);
  // SetObstacles + Solve is Compute.
  mapped.Solve(1.2, 35.0, 20.0, 2.0, 4.0);
  GeodesicField computed(chart.arena, 0.25);
  computed.Compute(chart, 1.2, 35.0, 20.0, 2.0, 4.0);
  CHECK(mapped.Distance(5.0, 20.0) == computed.Distance(5.0, 20.0));
  CHECK(mapped.Distance(5.0, 20.0) == doctest::Approx(30.0).epsilon(0.01));
  // The column's near side, as the sonar sees it from the west: points 0.1 rad apart on the
  // half of its surface that faces (5, 20).
  const double reach = 1.2 + 2.0 + 0.25;
  bool changed = false;
  for (int k = -15; k <= 15; ++k) {
    const double a = kPi + 0.1 * k;
    changed = mapped.AddPoint(column.x_m + std::cos(a), column.y_m + std::sin(a), reach) || changed;
  }
  CHECK(changed);
  CHECK_FALSE(mapped.AddPoint(column.x_m - 1.0, column.y_m, reach));  // the same point again changes nothing
  mapped.Solve(1.2, 35.0, 20.0, 2.0, 4.0);
  // The path now goes round: far longer than the straight line, within 10 % of the path round the
  // whole column, and it leaves the line to pass it.
  const double round = mapped.Distance(5.0, 20.0);
  CAPTURE(round);
  CHECK(round > 31.0);
  CHECK(round == doctest::Approx(truth.Distance(5.0, 20.0)).epsilon(0.1));
  CHECK(std::abs(std::sin(mapped.PathAngle(15.0, 20.0, 3.0))) > 0.3);
  // Copying the chart back forgets the points.
  mapped.CopyObstacles(base);
  mapped.Solve(1.2, 35.0, 20.0, 2.0, 4.0);
  CHECK(mapped.Distance(5.0, 20.0) == computed.Distance(5.0, 20.0));
}

TEST_CASE("geodesic field: with a minimum clearance the aim does not cut the corner of an obstacle") {
  // A block rising from the south wall to y = 20; the goal lies beyond it to the south-east, so the
  // shortest path (no margin) from the west runs along its top at l_safe, round its north-east
  // corner and down its east side.
  World2d w;
  w.boxes = {Box{10.0, 20.0, 0.0, 20.0}};
  GeodesicField f(w.arena, 0.25);
  f.Compute(w, 1.2, 30.0, 5.0);
  // The least clearance of the straight line from (x, y) to (ax, ay), sampled every 5 cm.
  const auto line = [&](double x, double y, double ax, double ay) {
    double least = Clearance(w, x, y);
    const int n = static_cast<int>(std::ceil(std::hypot(ax - x, ay - y) / 0.05));
    for (int s = 1; s <= n; ++s) {
      const double t = static_cast<double>(s) / n;
      least = std::min(least, Clearance(w, x + t * (ax - x), y + t * (ay - y)));
    }
    return least;
  };
  // Points just outside l_safe where the path runs: above the block's top, then round its corner.
  std::vector<std::array<double, 2>> points;
  for (double x = 14.0; x < 20.0; x += 0.5) points.push_back({x, 21.3});
  for (int deg = 90; deg >= 0; deg -= 10)
    points.push_back({20.0 + 1.3 * std::cos(deg * kPi / 180), 20.0 + 1.3 * std::sin(deg * kPi / 180)});
  // The path's own clearance is l_safe, so that is what the aim's line keeps, to within half a
  // cell and the distance from a point to its nearest node.
  const double keep = 1.2 - (0.5 * 0.25 + 0.25 * std::sqrt(0.5)) - 0.01;
  int cut = 0;
  for (const auto& [x, y] : points) {
    double ax = 0, ay = 0, bx = 0, by = 0;
    REQUIRE(f.PathAim(x, y, 3.0, 1.2 + 1.0, &ax, &ay));
    REQUIRE(f.PathAim(x, y, 3.0, 0.0, &bx, &by));
    CAPTURE(x);
    CAPTURE(y);
    CHECK(f.Distance(ax, ay) < f.Distance(x, y));  // ahead on the path
    CHECK(line(x, y, ax, ay) >= keep);
    cut += line(x, y, bx, by) < keep ? 1 : 0;
    CHECK(std::hypot(ax - x, ay - y) <= std::hypot(bx - x, by - y) + 1e-9);
  }
  // Without it, the full 3 m look-ahead cuts the corner from the points at the turn (4 of them).
  CAPTURE(cut);
  CHECK(cut >= 3);
}
