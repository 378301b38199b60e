#include "leeway/core/midphase.hpp"

#include <limits>

namespace leeway {

void AabbGrid::build(const std::vector<Aabb>& boxes, double tolerance) {
  *this = AabbGrid();
  boxes_ = boxes;
  tolerance_ = tolerance;
  const int n = static_cast<int>(boxes.size());
  auto finite = [](const Aabb& b) { return b.lo.allFinite() && b.hi.allFinite(); };
  auto footprint = [](const Aabb& b) { return std::max(b.hi.x() - b.lo.x(), b.hi.y() - b.lo.y()); };
  std::vector<double> feet;
  for (const Aabb& b : boxes)
    if (finite(b)) feet.push_back(footprint(b));
  if (feet.empty()) {
    for (int i = 0; i < n; ++i) large_.push_back(i);
    return;
  }
  std::nth_element(feet.begin(), feet.begin() + static_cast<long>(feet.size() / 2), feet.end());
  double side = feet[feet.size() / 2];
  if (!(side > 0)) side = 1e-3;  // point-like boxes: any positive side works
  const double bucket_limit = 2 * side;

  std::vector<int> bucketed;
  Eigen::Vector2d cmin = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d cmax = -cmin;
  for (int i = 0; i < n; ++i) {
    const Aabb& b = boxes[static_cast<size_t>(i)];
    if (!finite(b) || footprint(b) > bucket_limit) {
      large_.push_back(i);
      continue;
    }
    bucketed.push_back(i);
    const Eigen::Vector2d c = ((b.lo + b.hi) / 2).head<2>();
    cmin = cmin.cwiseMin(c);
    cmax = cmax.cwiseMax(c);
    reach_ = reach_.cwiseMax(((b.hi - b.lo) / 2).head<2>());
  }
  if (bucketed.empty()) return;
  const double max_cells = 4.0 * static_cast<double>(bucketed.size()) + 64;
  auto count = [&](double s, int axis) {
    return static_cast<int>(std::floor((cmax[axis] - cmin[axis]) / s)) + 1;
  };
  while (static_cast<double>(count(side, 0)) * count(side, 1) > max_cells) side *= 1.5;
  side_ = side;
  origin_ = cmin;
  Level base;
  base.nx = count(side, 0);
  base.ny = count(side, 1);
  const size_t cells = static_cast<size_t>(base.nx) * static_cast<size_t>(base.ny);
  auto bucket_of = [&](const Aabb& b) {
    const Eigen::Vector2d c = ((b.lo + b.hi) / 2).head<2>();
    const int ix = std::clamp(static_cast<int>(std::floor((c.x() - origin_.x()) / side_)), 0, base.nx - 1);
    const int iy = std::clamp(static_cast<int>(std::floor((c.y() - origin_.y()) / side_)), 0, base.ny - 1);
    return static_cast<size_t>(iy) * static_cast<size_t>(base.nx) + static_cast<size_t>(ix);
  };
  // Counting sort into buckets, indices increasing within each bucket.
  start_.assign(cells + 1, 0);
  for (int i : bucketed) ++start_[bucket_of(boxes[static_cast<size_t>(i)]) + 1];
  for (size_t b = 0; b < cells; ++b) start_[b + 1] += start_[b];
  items_.assign(bucketed.size(), -1);
  std::vector<int> fill(start_.begin(), start_.end() - 1);
  base.zmax.assign(cells, -std::numeric_limits<double>::infinity());
  base.zmin.assign(cells, std::numeric_limits<double>::infinity());
  for (int i : bucketed) {
    const Aabb& b = boxes[static_cast<size_t>(i)];
    const size_t k = bucket_of(b);
    items_[static_cast<size_t>(fill[k]++)] = i;
    base.zmax[k] = std::max(base.zmax[k], b.hi.z());
    base.zmin[k] = std::min(base.zmin[k], b.lo.z());
  }
  levels_.push_back(std::move(base));
  while (levels_.back().nx > 1 || levels_.back().ny > 1) {
    const Level& below = levels_.back();
    Level up;
    up.nx = (below.nx + 1) / 2;
    up.ny = (below.ny + 1) / 2;
    const size_t m = static_cast<size_t>(up.nx) * static_cast<size_t>(up.ny);
    up.zmax.assign(m, -std::numeric_limits<double>::infinity());
    up.zmin.assign(m, std::numeric_limits<double>::infinity());
    for (int y = 0; y < below.ny; ++y)
      for (int x = 0; x < below.nx; ++x) {
        const size_t from = static_cast<size_t>(y) * static_cast<size_t>(below.nx) + static_cast<size_t>(x);
        const size_t to =
            static_cast<size_t>(y / 2) * static_cast<size_t>(up.nx) + static_cast<size_t>(x / 2);
        up.zmax[to] = std::max(up.zmax[to], below.zmax[from]);
        up.zmin[to] = std::min(up.zmin[to], below.zmin[from]);
      }
    levels_.push_back(std::move(up));
  }
}

}  // namespace leeway
