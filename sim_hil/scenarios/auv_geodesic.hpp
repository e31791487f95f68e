// Shortest-path ("geodesic") distance to a goal through the free space of a World2d, for the
// AUV task's optional progress term (task.progress: geodesic). The paper's progress term rewards
// the decrease of the straight-line distance to the target, which pays a vehicle for running into
// a dead end that points at the target; the geodesic distance decreases only along paths that
// lead there.
//
// The route signal (auv_nav_task.hpp, task.route_map) is planned with it too, over the chart's
// obstacles plus the points of the sonar map (AddPoint).
//
// A grid of nodes spaced `cell_m` over the arena; a node is free when its clearance is at least
// `keep_m` (l_safe: where the vehicle may be without colliding). Dijkstra over the 8-neighbour
// graph (edge lengths cell and cell * sqrt 2, optionally weighted near obstacles) from the free
// nodes within reach of the goal gives each free node its distance. Storage is allocated once;
// Compute, AddPoint and Solve reuse it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "sim_hil/scenarios/auv_sonar.hpp"

namespace pbppo::sim {

class GeodesicField {
 public:
  // Sizes the grid for the arena; cell_m > 0.
  GeodesicField(const Arena& arena, double cell_m);

  // Distances to (goal_x, goal_y) through the free nodes of `world`: SetObstacles(world), then
  // Solve.
  void Compute(const World2d& world, double keep_m, double goal_x, double goal_y, double margin_m = 0.0,
               double margin_cost = 0.0);

  // Every node's clearance from `world` (Clearance: distance to the nearest surface or wall).
  void SetObstacles(const World2d& world);
  // Every node's clearance from another field over the same arena and cell size.
  void CopyObstacles(const GeodesicField& other) noexcept;
  // A point obstacle at (x, y), such as a sonar return: each node within reach_m of it takes its
  // distance to the point as clearance where that is less. True when a node changed.
  bool AddPoint(double x, double y, double reach_m) noexcept;

  // Dijkstra over the nodes whose clearance is at least keep_m. The goal's nearest free nodes
  // (within two cells) are the sources, at their straight-line distance from the goal. With
  // margin_m > 0 and margin_cost > 0 a path pays for running close to obstacles: a node whose
  // clearance exceeds keep_m by c < margin_m weighs 1 + margin_cost (1 - c / margin_m), and an
  // edge costs its length times the mean weight of its two nodes. The shortest path then keeps off
  // obstacles where there is room and still takes passages narrower than 2 (keep + margin).
  void Solve(double keep_m, double goal_x, double goal_y, double margin_m = 0.0, double margin_cost = 0.0);

  // The distance from (x, y): the least over the four surrounding nodes of (node's distance +
  // straight-line distance to it); without a reachable node among them, the best reachable
  // node within three cells; otherwise infinity (the point is walled off from the goal).
  double Distance(double x, double y) const noexcept;

  // Where to steer from (x, y) along the shortest path: the point reached by following the
  // steepest descent over `lookahead_m` (the goal when it is nearer). False (aim unchanged) where
  // Distance is infinite.
  //
  // With min_clearance_m > 0 the aim does not cut corners: it is the farthest point of that
  // stretch of path whose straight line from (x, y) keeps a clearance of at least the lesser of
  // min_clearance_m and the path's own clearance up to that point (less half a cell); the path's
  // next node where no point does.
  bool PathAim(double x, double y, double lookahead_m, double min_clearance_m, double* aim_x,
               double* aim_y) const noexcept;
  // The world-frame angle from (x, y) towards PathAim's point (towards the goal when (x, y) is
  // on it); NaN where Distance is infinite.
  double PathAngle(double x, double y, double lookahead_m, double min_clearance_m = 0.0) const noexcept;

  int nx() const noexcept { return nx_; }
  int ny() const noexcept { return ny_; }

 private:
  std::size_t Index(int i, int j) const noexcept { return static_cast<std::size_t>(j * nx_ + i); }
  // The node of least (distance + offset) near (x, y), or -1.
  int BestNode(double x, double y, int radius, double* total) const noexcept;
  // The least node clearance at samples (half a cell apart) of the segment from (x, y) to node.
  double SegmentClearance(double x, double y, int node) const noexcept;

  Arena arena_;
  double cell_ = 0.25;
  int nx_ = 0, ny_ = 0;
  double goal_x_ = 0.0, goal_y_ = 0.0;
  std::vector<float> dist_;
  std::vector<double> clear_;  // the node's clearance (SetObstacles, AddPoint)
  std::vector<std::uint8_t> free_;
  std::vector<float> weight_;  // the node's cost per metre (1 without a margin)
  // Dijkstra's queue: a binary min-heap of node indices keyed by dist_, with each node's place in
  // it (-1: not queued), so a shorter distance moves the node up instead of queuing it again and
  // the heap never holds more than the nodes (no growth after the constructor).
  std::vector<std::int32_t> heap_;
  std::vector<std::int32_t> place_;
  void SiftUp(std::size_t k) noexcept;
  void SiftDown(std::size_t k) noexcept;
};

}  // namespace pbppo::sim
