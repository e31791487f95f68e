#include "sim_hil/scenarios/auv_geodesic.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pbppo::sim {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr int kDi[8] = {1, -1, 0, 0, 1, 1, -1, -1};
constexpr int kDj[8] = {0, 0, 1, -1, 1, -1, 1, -1};

}  // namespace

GeodesicField::GeodesicField(const Arena& arena, double cell_m) : arena_(arena), cell_(cell_m) {
  nx_ = static_cast<int>(std::floor((arena.x_max_m - arena.x_min_m) / cell_m)) + 1;
  ny_ = static_cast<int>(std::floor((arena.y_max_m - arena.y_min_m) / cell_m)) + 1;
  const auto n = static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_);
  dist_.assign(n, kInf);
  clear_.assign(n, std::numeric_limits<double>::infinity());
  free_.assign(n, 0);
  weight_.assign(n, 1.0f);
  heap_.reserve(n);
  place_.assign(n, -1);
}

void GeodesicField::SiftUp(std::size_t k) noexcept {
  const std::int32_t node = heap_[k];
  const float d = dist_[static_cast<std::size_t>(node)];
  while (k > 0) {
    const std::size_t parent = (k - 1) / 2;
    if (!(d < dist_[static_cast<std::size_t>(heap_[parent])])) break;
    heap_[k] = heap_[parent];
    place_[static_cast<std::size_t>(heap_[k])] = static_cast<std::int32_t>(k);
    k = parent;
  }
  heap_[k] = node;
  place_[static_cast<std::size_t>(node)] = static_cast<std::int32_t>(k);
}

void GeodesicField::SiftDown(std::size_t k) noexcept {
  const std::int32_t node = heap_[k];
  const float d = dist_[static_cast<std::size_t>(node)];
  const std::size_t size = heap_.size();
  for (;;) {
    std::size_t child = 2 * k + 1;
    if (child >= size) break;
    if (child + 1 < size &&
        dist_[static_cast<std::size_t>(heap_[child + 1])] < dist_[static_cast<std::size_t>(heap_[child])])
      ++child;
    if (!(dist_[static_cast<std::size_t>(heap_[child])] < d)) break;
    heap_[k] = heap_[child];
    place_[static_cast<std::size_t>(heap_[k])] = static_cast<std::int32_t>(k);
    k = child;
  }
  heap_[k] = node;
  place_[static_cast<std::size_t>(node)] = static_cast<std::int32_t>(k);
}

void GeodesicField::Compute(const World2d& world, double keep_m, double goal_x, double goal_y, double margin_m,
                            double margin_cost) {
  SetObstacles(world);
  Solve(keep_m, goal_x, goal_y, margin_m, margin_cost);
}

void GeodesicField::SetObstacles(const World2d& world) {
  for (int j = 0; j < ny_; ++j)
    for (int i = 0; i < nx_; ++i)
      clear_[Index(i, j)] = Clearance(world, arena_.x_min_m + i * cell_, arena_.y_min_m + j * cell_);
}

void GeodesicField::CopyObstacles(const GeodesicField& other) noexcept {
  std::copy(other.clear_.begin(), other.clear_.end(), clear_.begin());
}

bool GeodesicField::AddPoint(double x, double y, double reach_m) noexcept {
  const int i0 = std::max(0, static_cast<int>(std::floor((x - reach_m - arena_.x_min_m) / cell_)));
  const int i1 = std::min(nx_ - 1, static_cast<int>(std::ceil((x + reach_m - arena_.x_min_m) / cell_)));
  const int j0 = std::max(0, static_cast<int>(std::floor((y - reach_m - arena_.y_min_m) / cell_)));
  const int j1 = std::min(ny_ - 1, static_cast<int>(std::ceil((y + reach_m - arena_.y_min_m) / cell_)));
  bool changed = false;
  for (int j = j0; j <= j1; ++j) {
    for (int i = i0; i <= i1; ++i) {
      const double d = std::hypot(arena_.x_min_m + i * cell_ - x, arena_.y_min_m + j * cell_ - y);
      if (d > reach_m) continue;
      double& c = clear_[Index(i, j)];
      if (d < c) {
        c = d;
        changed = true;
      }
    }
  }
  return changed;
}

void GeodesicField::Solve(double keep_m, double goal_x, double goal_y, double margin_m, double margin_cost) {
  goal_x_ = goal_x;
  goal_y_ = goal_y;
  const bool weighted = margin_m > 0.0 && margin_cost > 0.0;
  for (std::size_t n = 0; n < clear_.size(); ++n) {
    const double c = clear_[n];
    free_[n] = c >= keep_m ? 1 : 0;
    weight_[n] =
        weighted ? static_cast<float>(1.0 + margin_cost * std::clamp(1.0 - (c - keep_m) / margin_m, 0.0, 1.0)) : 1.0f;
  }
  std::fill(dist_.begin(), dist_.end(), kInf);
  heap_.clear();
  std::fill(place_.begin(), place_.end(), -1);
  // Queues the node whose distance was just lowered, or moves it up if it is queued already.
  const auto push = [&](int index) {
    const auto at = place_[static_cast<std::size_t>(index)];
    if (at >= 0) {
      SiftUp(static_cast<std::size_t>(at));
    } else {
      heap_.push_back(index);
      SiftUp(heap_.size() - 1);
    }
  };
  const int gi = static_cast<int>(std::lround((goal_x - arena_.x_min_m) / cell_));
  const int gj = static_cast<int>(std::lround((goal_y - arena_.y_min_m) / cell_));
  for (int j = gj - 2; j <= gj + 2; ++j) {
    for (int i = gi - 2; i <= gi + 2; ++i) {
      if (i < 0 || j < 0 || i >= nx_ || j >= ny_ || !free_[Index(i, j)]) continue;
      const float d =
          static_cast<float>(std::hypot(arena_.x_min_m + i * cell_ - goal_x, arena_.y_min_m + j * cell_ - goal_y));
      if (d < dist_[Index(i, j)]) {
        dist_[Index(i, j)] = d;
        push(Index(i, j));
      }
    }
  }
  const float straight = static_cast<float>(cell_), diagonal = static_cast<float>(cell_ * std::sqrt(2.0));
  while (!heap_.empty()) {
    const std::int32_t index = heap_.front();
    const float d = dist_[static_cast<std::size_t>(index)];
    place_[static_cast<std::size_t>(index)] = -1;
    heap_.front() = heap_.back();
    heap_.pop_back();
    if (!heap_.empty()) SiftDown(0);
    const int i = index % nx_, j = index / nx_;
    for (int k = 0; k < 8; ++k) {
      const int a = i + kDi[k], b = j + kDj[k];
      if (a < 0 || b < 0 || a >= nx_ || b >= ny_) continue;
      const int n = Index(a, b);
      if (!free_[static_cast<std::size_t>(n)]) continue;
      // A diagonal step may not cut the corner of a blocked node.
      if (k >= 4 && (!free_[Index(a, j)] || !free_[Index(i, b)])) continue;
      const float nd = d + (k < 4 ? straight : diagonal) * 0.5f *
                               (weight_[static_cast<std::size_t>(index)] + weight_[static_cast<std::size_t>(n)]);
      if (nd < dist_[static_cast<std::size_t>(n)]) {
        dist_[static_cast<std::size_t>(n)] = nd;
        push(n);
      }
    }
  }
}

int GeodesicField::BestNode(double x, double y, int radius, double* total) const noexcept {
  const double fi = (x - arena_.x_min_m) / cell_, fj = (y - arena_.y_min_m) / cell_;
  const int i0 = static_cast<int>(std::floor(fi)), j0 = static_cast<int>(std::floor(fj));
  int best = -1;
  double best_total = std::numeric_limits<double>::infinity();
  for (int j = j0 + 1 - radius; j <= j0 + radius; ++j) {
    for (int i = i0 + 1 - radius; i <= i0 + radius; ++i) {
      if (i < 0 || j < 0 || i >= nx_ || j >= ny_) continue;
      const float d = dist_[Index(i, j)];
      if (!std::isfinite(d)) continue;
      const double t = d + std::hypot(arena_.x_min_m + i * cell_ - x, arena_.y_min_m + j * cell_ - y);
      if (t < best_total) {
        best_total = t;
        best = Index(i, j);
      }
    }
  }
  *total = best_total;
  return best;
}

double GeodesicField::Distance(double x, double y) const noexcept {
  double total = 0;
  if (BestNode(x, y, 1, &total) >= 0) return total;
  BestNode(x, y, 3, &total);
  return total;
}

double GeodesicField::SegmentClearance(double x, double y, int node) const noexcept {
  const double px = arena_.x_min_m + (node % nx_) * cell_, py = arena_.y_min_m + (node / nx_) * cell_;
  const int samples = std::max(1, static_cast<int>(std::ceil(std::hypot(px - x, py - y) / (0.5 * cell_))));
  double least = std::numeric_limits<double>::infinity();
  for (int s = 0; s <= samples; ++s) {
    const double f = static_cast<double>(s) / samples;
    const int i = static_cast<int>(std::lround((x + f * (px - x) - arena_.x_min_m) / cell_));
    const int j = static_cast<int>(std::lround((y + f * (py - y) - arena_.y_min_m) / cell_));
    if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return -std::numeric_limits<double>::infinity();
    least = std::min(least, clear_[Index(i, j)]);
  }
  return least;
}

bool GeodesicField::PathAim(double x, double y, double lookahead_m, double min_clearance_m, double* aim_x,
                            double* aim_y) const noexcept {
  double total = 0;
  int node = BestNode(x, y, 1, &total);
  if (node < 0) node = BestNode(x, y, 3, &total);
  if (node < 0) return false;
  if (total <= lookahead_m) {
    *aim_x = goal_x_;
    *aim_y = goal_y_;
    return true;
  }
  const int steps = std::max(1, static_cast<int>(std::lround(lookahead_m / cell_)));
  int aim = -1, first = -1;
  double path_clearance = clear_[static_cast<std::size_t>(node)];
  for (int s = 0; s < steps; ++s) {
    const int i = node % nx_, j = node / nx_;
    int next = node;
    for (int k = 0; k < 8; ++k) {
      const int a = i + kDi[k], b = j + kDj[k];
      if (a < 0 || b < 0 || a >= nx_ || b >= ny_) continue;
      if (dist_[Index(a, b)] < dist_[next]) next = Index(a, b);
    }
    if (next == node) break;
    node = next;
    if (first < 0) first = node;
    if (min_clearance_m > 0.0) {
      path_clearance = std::min(path_clearance, clear_[static_cast<std::size_t>(node)]);
      const double need = std::min(min_clearance_m, path_clearance) - 0.5 * cell_;
      if (SegmentClearance(x, y, node) >= need) aim = node;
    } else {
      aim = node;
    }
  }
  if (aim < 0) aim = first >= 0 ? first : node;  // no stretch in the clear: the path's next node
  *aim_x = arena_.x_min_m + (aim % nx_) * cell_;
  *aim_y = arena_.y_min_m + (aim / nx_) * cell_;
  return true;
}

double GeodesicField::PathAngle(double x, double y, double lookahead_m, double min_clearance_m) const noexcept {
  double px = 0, py = 0;
  if (!PathAim(x, y, lookahead_m, min_clearance_m, &px, &py)) return std::numeric_limits<double>::quiet_NaN();
  if (std::hypot(px - x, py - y) < 1e-6) return std::atan2(goal_y_ - y, goal_x_ - x);
  return std::atan2(py - y, px - x);
}

}  // namespace pbppo::sim
