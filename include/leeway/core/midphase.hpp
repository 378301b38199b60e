#pragma once
//! @file midphase.hpp
//! The midphase over static geoms: their world axis-aligned boxes in a 2D grid over the
//! floor plane with a max/min-height pyramid, so that a query visits only the cells under a link's
//! footprint whose height range meets the link's, and skips every block of lower cells at once.
//! The volume is a height map, so its boxes fill such a grid one per cell; the real obstacles use
//! the same structure. Pure geometry: no MuJoCo types.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <vector>

namespace leeway {

//! An axis-aligned box [lo, hi] in world coordinates [m].
struct Aabb {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero();
  Eigen::Vector3d hi = Eigen::Vector3d::Zero();
};

//! True when the two boxes overlap or are less than `tolerance` [m] apart along every axis.
inline bool overlaps(const Aabb& a, const Aabb& b, double tolerance) {
  return (a.lo.array() <= b.hi.array() + tolerance).all() && (b.lo.array() <= a.hi.array() + tolerance).all();
}

//! A static set of axis-aligned boxes indexed for overlap queries. Boxes whose footprint is at most
//! twice the grid's cell side are bucketed by their centre; larger ones (a big obstacle among small
//! volume boxes) are kept in a list that every query scans. Every query returns exactly the boxes
//! whose AABB overlaps the query's within the tolerance (AabbGridTest in tests/collision_test.cpp), in
//! increasing index order within a bucket.
class AabbGrid {
 public:
  //! Indexes `boxes` (index i = boxes[i]); `tolerance` [m] widens every overlap test. The cell
  //! side is the median footprint (larger of the x and y extents) of the boxes, widened when the
  //! grid would have more than 4 n + 64 cells. Non-finite boxes go to the large list.
  void build(const std::vector<Aabb>& boxes, double tolerance = 1e-9);

  //! Calls `visit(i)` for every indexed box i whose AABB overlaps `query`; stops and returns true as
  //! soon as a call returns true. Returns false when none did.
  template <class Visit>
  bool any(const Aabb& query, Visit&& visit) const;

  //! Number of boxes indexed.
  int size() const { return static_cast<int>(boxes_.size()); }
  //! The grid's cell side [m] (0 when empty).
  double cell_side() const { return side_; }
  //! Boxes kept out of the grid because of their size.
  int large() const { return static_cast<int>(large_.size()); }

 private:
  struct Level {
    int nx = 0, ny = 0;
    std::vector<double> zmax, zmin;  // per node: the height range of the boxes below it
  };
  template <class Visit>
  bool descend(int level, int ix, int iy, int x0, int x1, int y0, int y1, const Aabb& q, Visit& visit) const;

  std::vector<Aabb> boxes_;
  std::vector<int> large_;  // indices of boxes outside the grid
  std::vector<int> start_;  // CSR: bucket b holds items_[start_[b] .. start_[b + 1])
  std::vector<int> items_;
  std::vector<Level> levels_;  // levels_[0] = the buckets; each next level halves both sides
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d reach_ = Eigen::Vector2d::Zero();  // the largest half-extent of a bucketed box
  double side_ = 0;
  double tolerance_ = 0;
};

template <class Visit>
bool AabbGrid::any(const Aabb& q, Visit&& visit) const {
  for (int i : large_)
    if (overlaps(q, boxes_[static_cast<size_t>(i)], tolerance_) && visit(i)) return true;
  if (levels_.empty()) return false;
  // Buckets whose boxes can reach the query: centres within the query widened by the half-extent.
  const Level& base = levels_.front();
  auto cell = [&](double v, int axis, int n) {
    const double c = std::floor((v - origin_[axis]) / side_);
    return static_cast<int>(std::clamp(c, -1.0, static_cast<double>(n)));
  };
  // (1e-6 of a cell more, so that rounding in these sums never drops a bucket)
  const double slack = tolerance_ + 1e-6 * side_;
  const int x0 = std::max(0, cell(q.lo.x() - reach_.x() - slack, 0, base.nx));
  const int x1 = std::min(base.nx - 1, cell(q.hi.x() + reach_.x() + slack, 0, base.nx));
  const int y0 = std::max(0, cell(q.lo.y() - reach_.y() - slack, 1, base.ny));
  const int y1 = std::min(base.ny - 1, cell(q.hi.y() + reach_.y() + slack, 1, base.ny));
  if (x0 > x1 || y0 > y1) return false;
  const int top = static_cast<int>(levels_.size()) - 1;
  const Level& root = levels_.back();
  for (int iy = 0; iy < root.ny; ++iy)
    for (int ix = 0; ix < root.nx; ++ix)
      if (descend(top, ix, iy, x0, x1, y0, y1, q, visit)) return true;
  return false;
}

template <class Visit>
bool AabbGrid::descend(int level, int ix, int iy, int x0, int x1, int y0, int y1, const Aabb& q,
                       Visit& visit) const {
  // The node covers buckets [ix << level, ((ix + 1) << level) - 1] along x, likewise along y.
  if ((ix + 1) << level <= x0 || ix << level > x1 || (iy + 1) << level <= y0 || iy << level > y1)
    return false;
  const Level& l = levels_[static_cast<size_t>(level)];
  const size_t node = static_cast<size_t>(iy) * static_cast<size_t>(l.nx) + static_cast<size_t>(ix);
  if (l.zmax[node] + tolerance_ < q.lo.z() || l.zmin[node] - tolerance_ > q.hi.z()) return false;
  if (level > 0) {
    const Level& below = levels_[static_cast<size_t>(level - 1)];
    for (int cy = 2 * iy; cy <= std::min(2 * iy + 1, below.ny - 1); ++cy)
      for (int cx = 2 * ix; cx <= std::min(2 * ix + 1, below.nx - 1); ++cx)
        if (descend(level - 1, cx, cy, x0, x1, y0, y1, q, visit)) return true;
    return false;
  }
  for (int k = start_[node]; k < start_[node + 1]; ++k) {
    const int i = items_[static_cast<size_t>(k)];
    if (overlaps(q, boxes_[static_cast<size_t>(i)], tolerance_) && visit(i)) return true;
  }
  return false;
}

}  // namespace leeway
