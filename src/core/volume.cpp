#include "leeway/core/volume.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "leeway/core/error.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

//! The 8 corners of a box in world coordinates.
std::array<Vector3d, 8> corners(const Box& b) {
  std::array<Vector3d, 8> c;
  for (int k = 0; k < 8; ++k) {
    const Vector3d sign((k & 1) ? 1.0 : -1.0, (k & 2) ? 1.0 : -1.0, (k & 4) ? 1.0 : -1.0);
    c[k] = b.center + b.rotation * sign.cwiseProduct(b.half_size);
  }
  return c;
}

double cross2(const Vector2d& a, const Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

//! A box's footprint: the convex hull of its 8 corners projected onto the floor (z = 0),
//! counter-clockwise. At most 6 vertices for a box; fewer for a flat or zero-size box seen edge-on.
struct Footprint {
  std::array<Vector2d, 8> v;
  std::array<Vector2d, 8> edge;  //!< v[i + 1] - v[i] (cyclic)
  std::array<double, 8> inv_len2;
  int n = 0;
};

//! Andrew's monotone chain over the projected corners; collinear and repeated points are dropped.
Footprint footprint(const Box& b) {
  std::array<Vector2d, 8> p;
  const auto c = corners(b);
  for (int k = 0; k < 8; ++k) p[k] = c[k].head<2>();
  std::sort(p.begin(), p.end(), [](const Vector2d& a, const Vector2d& q) {
    return a.x() < q.x() || (a.x() == q.x() && a.y() < q.y());
  });
  std::array<Vector2d, 16> h;
  int n = 0;
  for (int i = 0; i < 8; ++i) {  // lower hull
    while (n >= 2 && cross2(h[n - 1] - h[n - 2], p[i] - h[n - 2]) <= 0) --n;
    h[n++] = p[i];
  }
  for (int i = 6, lower = n + 1; i >= 0; --i) {  // upper hull
    while (n >= lower && cross2(h[n - 1] - h[n - 2], p[i] - h[n - 2]) <= 0) --n;
    h[n++] = p[i];
  }
  Footprint f;
  f.n = std::max(1, n - 1);  // the last point repeats the first
  for (int i = 0; i < f.n; ++i) f.v[i] = h[i];
  for (int i = 0; i < f.n; ++i) {
    f.edge[i] = h[(i + 1) % f.n] - h[i];
    f.inv_len2[i] = f.n >= 3 ? 1.0 / f.edge[i].squaredNorm() : 0.0;  // hull edges have length > 0
  }
  return f;
}

double segment_distance(const Vector2d& p, const Vector2d& a, const Vector2d& b) {
  const Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

//! Distance in the plane from p to the footprint polygon; 0 inside or on it.
double footprint_distance(const Footprint& f, const Vector2d& p) {
  if (f.n == 1) return (p - f.v[0]).norm();
  if (f.n == 2) return segment_distance(p, f.v[0], f.v[1]);
  // Convex and counter-clockwise: p is inside iff it is on the inner side of every edge. Outside,
  // the nearest point lies on an edge that p is strictly outside of (at a vertex, on at least one
  // of its two edges), so only those edges are measured. This is the hot loop of the height-map.
  double best2 = std::numeric_limits<double>::infinity();
  for (int i = 0; i < f.n; ++i) {
    const Vector2d w = p - f.v[i];
    if (cross2(f.edge[i], w) >= 0) continue;
    const double t = std::clamp(w.dot(f.edge[i]) * f.inv_len2[i], 0.0, 1.0);
    best2 = std::min(best2, (w - t * f.edge[i]).squaredNorm());
  }
  return best2 == std::numeric_limits<double>::infinity() ? 0.0 : std::sqrt(best2);
}

//! Bounding-volume hierarchy over axis-aligned boxes, for "nearest item, but only if nearer than a
//! bound" queries: the height terms saturate beyond their upper bounds, so farther items never
//! matter. The caller supplies the exact distance; the boxes give lower bounds to prune with.
class NearestIndex {
 public:
  explicit NearestIndex(std::vector<Eigen::AlignedBox3d> bounds) : bounds_(std::move(bounds)) {
    order_.resize(bounds_.size());
    for (size_t i = 0; i < order_.size(); ++i) order_[i] = static_cast<int>(i);
    if (!order_.empty()) build(0, static_cast<int>(order_.size()));
  }

  bool empty() const { return bounds_.empty(); }

  //! min(bound, smallest exact(i) over all items). `hint` is an item to try first (the previous
  //! query's answer: neighbouring cells usually share their nearest box); it is updated.
  template <class Exact>
  double nearest(const Vector3d& p, double bound, const Exact& exact, int& hint) const {
    double best = bound;
    int best_item = -1;
    if (hint >= 0) {
      const double d = exact(hint);
      if (d < best) {
        best = d;
        best_item = hint;
      }
    }
    if (!nodes_.empty()) search(0, p, exact, hint, best, best_item);
    if (best_item >= 0) hint = best_item;
    return best;
  }

 private:
  struct Node {
    Eigen::AlignedBox3d bounds;
    int first = 0, count = 0;  // leaf: items order_[first, first + count)
    int left = -1, right = -1;
  };
  static constexpr int kLeafSize = 4;

  int build(int first, int count) {
    const int index = static_cast<int>(nodes_.size());
    nodes_.emplace_back();
    Eigen::AlignedBox3d box, centres;
    for (int k = first; k < first + count; ++k) {
      box.extend(bounds_[order_[k]]);
      centres.extend(bounds_[order_[k]].center());
    }
    nodes_[index].bounds = box;
    nodes_[index].first = first;
    nodes_[index].count = count;
    if (count <= kLeafSize) return index;
    int axis = 0;
    centres.sizes().maxCoeff(&axis);
    const int half = count / 2;
    std::nth_element(order_.begin() + first, order_.begin() + first + half, order_.begin() + first + count,
                     [&](int a, int b) { return bounds_[a].center()[axis] < bounds_[b].center()[axis]; });
    const int left = build(first, half);
    const int right = build(first + half, count - half);
    nodes_[index].left = left;
    nodes_[index].right = right;
    return index;
  }

  template <class Exact>
  void search(int node, const Vector3d& p, const Exact& exact, int skip, double& best, int& best_item) const {
    const Node& n = nodes_[node];
    if (n.left < 0) {
      for (int k = n.first; k < n.first + n.count; ++k) {
        const int item = order_[k];
        if (item == skip || bounds_[item].squaredExteriorDistance(p) >= best * best) continue;
        const double d = exact(item);
        if (d < best) {
          best = d;
          best_item = item;
        }
      }
      return;
    }
    int a = n.left, b = n.right;
    double da = nodes_[a].bounds.squaredExteriorDistance(p), db = nodes_[b].bounds.squaredExteriorDistance(p);
    if (db < da) {
      std::swap(a, b);
      std::swap(da, db);
    }
    if (da < best * best) search(a, p, exact, skip, best, best_item);
    if (db < best * best) search(b, p, exact, skip, best, best_item);
  }

  std::vector<Eigen::AlignedBox3d> bounds_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
};

//! One category's boxes with what the distance queries need, computed once.
class BoxSet {
 public:
  BoxSet(std::vector<Box> boxes, DistanceMode mode)
      : boxes_(std::move(boxes)), mode_(mode), index_(bounds()) {}

  bool empty() const { return boxes_.empty(); }

  //! min(bound, distance from the floor point p to the nearest box), as v.distance says.
  double nearest(const Vector2d& p, double bound, int& hint) const {
    const Vector3d p3(p.x(), p.y(), 0.0);
    if (mode_ == DistanceMode::kPlane)
      return index_.nearest(
          p3, bound, [&](int i) { return footprint_distance(footprints_[i], p); }, hint);
    return index_.nearest(
        p3, bound, [&](int i) { return (closest_point(boxes_[i], p3) - p3).norm(); }, hint);
  }

 private:
  // Plane mode: the footprint's rectangle at z = 0 (a lower bound of the footprint distance);
  // 3D mode: the box's axis-aligned bounds (a lower bound of the 3D distance).
  std::vector<Eigen::AlignedBox3d> bounds() {
    std::vector<Eigen::AlignedBox3d> out;
    for (const Box& b : boxes_) {
      Eigen::AlignedBox3d box;
      for (const Vector3d& c : corners(b)) box.extend(c);
      if (mode_ == DistanceMode::kPlane) {
        box.min().z() = 0;
        box.max().z() = 0;
        footprints_.push_back(footprint(b));
      }
      out.push_back(box);
    }
    return out;
  }

  std::vector<Box> boxes_;
  DistanceMode mode_;
  std::vector<Footprint> footprints_;
  NearestIndex index_;
};

bool valid_box(const Box& b) {
  return b.center.allFinite() && b.rotation.allFinite() && b.half_size.allFinite() &&
         (b.half_size.array() >= 0).all();
}

void check_boxes(const std::vector<Box>& boxes, const char* what) {
  for (size_t i = 0; i < boxes.size(); ++i)
    if (!valid_box(boxes[i]))
      throw InputError(std::string("volume generation: ") + what + " #" + std::to_string(i) +
                       " has a non-finite centre, rotation or half-size, or a negative half-size (a "
                       "collidable plane?)");
}

//! Warm-start hints for the three nearest queries, carried from one cell to the next.
struct Hints {
  int trail = -1, goal = -1, non_goal = -1;
};

//! A normalised fraction of eq. 3.1, clamped to [0, 1] before the exponent (docs/algorithm.md).
double term(double fraction, double alpha) {
  const double f = std::clamp(fraction, 0.0, 1.0);
  return alpha == 1.0 ? f : std::pow(f, alpha);
}

//! The height function with its distance structures built once.
class HeightField {
 public:
  HeightField(const Categories& c, const VolumeParams& v)
      : v_(v),
        trail_(c.trail, v.distance),
        goal_(c.goal ? std::vector<Box>{*c.goal} : std::vector<Box>{}, v.distance),
        non_goal_(c.non_goal, v.distance) {}

  //! h(c) without the activation: eq. 3.1, goal term per eq. 4.1 when v.goal_constant_term.
  double at(const Vector2d& p, Hints& hints) const {
    // Trail: h_max ((d_t - d_t,LB) / (d_t,UB - d_t,LB))^alpha_t; no trail: saturated.
    double trail_fraction = 1.0;
    if (!trail_.empty())
      trail_fraction = (trail_.nearest(p, v_.d_t_ub, hints.trail) - v_.d_t_lb) / (v_.d_t_ub - v_.d_t_lb);
    const double h_trail = v_.h_max * term(trail_fraction, v_.alpha_t);

    // Goal: eq. 3.1's h_max (...)^alpha_g, or eq. 4.1's h_max/3 + 2/3 h_max (...)^alpha_g.
    double goal_fraction = 1.0;
    if (!goal_.empty())
      goal_fraction = (goal_.nearest(p, v_.d_g_ub, hints.goal) - v_.d_g_lb) / (v_.d_g_ub - v_.d_g_lb);
    const double g = term(goal_fraction, v_.alpha_g);
    const double h_goal = v_.goal_constant_term ? v_.h_max / 3.0 + 2.0 / 3.0 * v_.h_max * g : v_.h_max * g;

    // Non-goal: h_max ((d_ng,UB - d_ng) / d_ng,UB)^alpha_ng for the nearest one; none: 0.
    double h_non_goal = 0.0;
    if (!non_goal_.empty()) {
      const double d = non_goal_.nearest(p, v_.d_ng_ub, hints.non_goal);
      h_non_goal = v_.h_max * term((v_.d_ng_ub - d) / v_.d_ng_ub, v_.alpha_ng);
    }
    return h_trail + h_goal + h_non_goal;
  }

 private:
  VolumeParams v_;
  BoxSet trail_, goal_, non_goal_;
};

//! Checks the volume parameters with Params::validate's messages.
void validate_volume_params(const HeightMapParams* hm, const VolumeParams& v) {
  Params p;
  if (hm) p.height_map = *hm;
  p.volume = v;
  p.validate();
}

void check_categories(const Categories& c) {
  check_boxes(c.trail, "trail box");
  check_boxes(c.non_goal, "non-goal obstacle");
  if (c.goal && !valid_box(*c.goal))
    throw InputError(
        "volume generation: the goal obstacle has a non-finite centre, rotation or half-size, or a negative "
        "half-size");
  for (size_t i = 0; i < c.arm_base.size(); ++i)
    if (!c.arm_base[i].allFinite())
      throw InputError("volume generation: arm-base position #" + std::to_string(i) + " is not finite");
}

//! The activation's test of section 4.1 ("checking if any box in the trail would collide with a max
//! height box instantiated in the cell"; leeway's max height is 3 h_max), precomputed per trail box.
//! The prisms of all cells differ only by a translation, so
//! each of the 15 separating axes of box_penetration(prism, trail box) and its radius sum ra + rb are
//! fixed per trail box; per cell only the centre offset is projected. Same axes, same formula, same
//! ">= 0 means touching" as box_penetration().
class PrismTrailTest {
 public:
  PrismTrailTest(const Box& trail, double side, double max_height)
      : center_(trail.center), z_(max_height / 2) {
    Box prism;
    prism.half_size = Vector3d(side / 2, side / 2, max_height / 2);
    auto add = [&](const Vector3d& axis_in) {
      const double n = axis_in.norm();
      if (n < 1e-9) return;  // parallel edges: as box_penetration, the face axes cover this case
      const Vector3d axis = axis_in / n;
      const double ra = (prism.rotation.transpose() * axis).cwiseAbs().dot(prism.half_size);
      const double rb = (trail.rotation.transpose() * axis).cwiseAbs().dot(trail.half_size);
      axes_[count_] = axis;
      radii_[count_] = ra + rb;
      ++count_;
    };
    for (int i = 0; i < 3; ++i) add(prism.rotation.col(i));
    for (int i = 0; i < 3; ++i) add(trail.rotation.col(i));
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) add(prism.rotation.col(i).cross(trail.rotation.col(j)));
  }

  //! True when the prism over the cell centred at (x, y) touches or overlaps the trail box.
  bool touches(double x, double y) const {
    const Vector3d d = center_ - Vector3d(x, y, z_);
    for (int k = 0; k < count_; ++k)
      if (radii_[k] - std::abs(d.dot(axes_[k])) < 0) return false;
    return true;
  }

 private:
  Vector3d center_;
  double z_;
  std::array<Vector3d, 15> axes_;
  std::array<double, 15> radii_;
  int count_ = 0;
};

}  // namespace

Grid make_grid(const HeightMapParams& p, const Categories& c, const VolumeParams& v) {
  if (p.max_cells < 1 || p.max_cells > kMaxCellsLimit)
    throw InputError("parameter 'height_map.max_cells' = " + std::to_string(p.max_cells) +
                     " must be between 1 and " + std::to_string(kMaxCellsLimit));
  double x0 = p.origin_x, y0 = p.origin_y, x_dim = p.x_dim, y_dim = p.y_dim;
  if (p.auto_extent) {
    // Every floor point within reach_radius of an arm-base position: the bases' bounding rectangle
    // grown by the radius. Cells outside it are beyond reach and would hold no box.
    if (c.arm_base.empty())
      throw InputError(
          "parameter 'height_map.auto_extent' = true needs at least one arm-base position (the path is "
          "empty); give the map's origin_x, origin_y, x_dim and y_dim instead");
    if (!std::isfinite(v.reach_radius) || v.reach_radius <= 0)
      throw InputError("parameter 'volume.reach_radius' = " + format_number(v.reach_radius) + " must be > 0");
    Eigen::AlignedBox2d box;
    for (size_t i = 0; i < c.arm_base.size(); ++i) {
      if (!c.arm_base[i].allFinite())
        throw InputError("volume generation: arm-base position #" + std::to_string(i) + " is not finite");
      box.extend(c.arm_base[i]);
    }
    x0 = box.min().x() - v.reach_radius;
    y0 = box.min().y() - v.reach_radius;
    x_dim = box.sizes().x() + 2 * v.reach_radius;
    y_dim = box.sizes().y() + 2 * v.reach_radius;
  } else {
    if (!std::isfinite(x0) || !std::isfinite(y0))
      throw InputError("parameter 'height_map.origin_x'/'origin_y' = " + format_number(x0) + ", " +
                       format_number(y0) + " must be finite");
    if (!std::isfinite(x_dim) || x_dim <= 0)
      throw InputError("parameter 'height_map.x_dim' = " + format_number(x_dim) + " must be > 0");
    if (!std::isfinite(y_dim) || y_dim <= 0)
      throw InputError("parameter 'height_map.y_dim' = " + format_number(y_dim) + " must be > 0");
  }
  Grid g;
  g.origin_x = x0;
  g.origin_y = y0;
  // Section 3.2.1: side = sqrt(x_dim y_dim / MAX_cells); x_L = x_dim / side and y_L = y_dim / side
  // "rounded to an integer value if needed" (at least one cell each).
  g.side = std::sqrt(x_dim * y_dim / p.max_cells);
  // Params::validate bounds the extents; a map this small (or large) could still come from a caller.
  if (!(g.side > 0) || !std::isfinite(g.side) || !(x_dim / g.side < 1e9) || !(y_dim / g.side < 1e9))
    throw InputError("the height-map " + format_number(x_dim) + " x " + format_number(y_dim) +
                     " m cannot be divided into 'height_map.max_cells' = " + std::to_string(p.max_cells) +
                     " cells");
  const double rows = std::max(1.0, std::round(x_dim / g.side));
  const double cols = std::max(1.0, std::round(y_dim / g.side));
  // Only a map thinner than a quarter cell is rounded up this much; refuse rather than allocate.
  if (rows * cols > 4.0 * p.max_cells)
    throw InputError("the height-map " + format_number(x_dim) + " x " + format_number(y_dim) +
                     " m is too elongated for 'height_map.max_cells' = " + std::to_string(p.max_cells) +
                     " (" + format_number(rows) + " x " + format_number(cols) + " cells)");
  g.rows = static_cast<int>(rows);
  g.cols = static_cast<int>(cols);
  return g;
}

double height(const Eigen::Vector2d& cell_center, const Categories& c, const VolumeParams& v) {
  validate_volume_params(nullptr, v);
  check_categories(c);
  Hints hints;
  return HeightField(c, v).at(cell_center, hints);
}

Volume generate_volume(const Categories& c, const HeightMapParams& hm, const VolumeParams& v) {
  validate_volume_params(&hm, v);
  check_categories(c);
  // Reach is measured from the arm base at the path's poses: without any, no cell is in reach.
  if (c.arm_base.empty())
    throw InputError("volume generation needs at least one arm-base position (the path is empty)");
  Volume out;
  const Grid g = make_grid(hm, c, v);
  out.grid = g;
  const size_t rows = static_cast<size_t>(g.rows), cols = static_cast<size_t>(g.cols);
  out.cells_evaluated = g.rows * g.cols;
  auto centre_x = [&](size_t i) { return g.origin_x + (static_cast<double>(i) + 0.5) * g.side; };
  auto centre_y = [&](size_t j) { return g.origin_y + (static_cast<double>(j) + 0.5) * g.side; };

  // A_t, under the trail (section 4.1): a box of the largest possible height on the cell,
  // H = 3 h_max (each term of eq. 3.1 / 4.1 at most h_max), touches a trail box. Only the cells
  // whose squares meet the trail box's footprint rectangle (one cell of margin) are tested.
  const double max_height = 3.0 * v.h_max;
  std::vector<unsigned char> under_trail(rows * cols, 0);
  for (Box t : c.trail) {
    // trail_margin (0 in the thesis): the trail box grown by the margin on every side.
    t.half_size.array() += v.trail_margin;
    Eigen::AlignedBox3d box;
    for (const Vector3d& corner : corners(t)) box.extend(corner);
    if (box.min().z() > max_height || box.max().z() < 0) continue;
    // Cells [first, last) along one axis whose squares may meet [lo, hi]; one cell of margin each
    // side absorbs the rounding of the division, the exact test decides.
    auto cell_range = [&](double lo, double hi, double origin, size_t n) {
      const double a = std::floor((lo - origin) / g.side) - 1, b = std::floor((hi - origin) / g.side) + 1;
      const double last = static_cast<double>(n) - 1;
      if (b < 0 || a > last) return std::make_pair(std::size_t{0}, std::size_t{0});
      return std::make_pair(static_cast<size_t>(std::max(a, 0.0)),
                            static_cast<size_t>(std::min(b, last)) + 1);
    };
    const auto [i0, i1] = cell_range(box.min().x(), box.max().x(), g.origin_x, rows);
    const auto [j0, j1] = cell_range(box.min().y(), box.max().y(), g.origin_y, cols);
    const PrismTrailTest test(t, g.side, max_height);
    for (size_t i = i0; i < i1; ++i)
      for (size_t j = j0; j < j1; ++j) {
        unsigned char& flag = under_trail[i * cols + j];
        if (!flag && test.touches(centre_x(i), centre_y(j))) flag = 1;
      }
  }

  // A_t, reach: zero beyond reach_radius from every arm-base position, in the floor plane. The
  // positions go into the same nearest index as the boxes (as points; duplicates from a fixed base
  // are harmless). Inside reach iff the nearest base is within the radius.
  std::vector<Eigen::AlignedBox3d> base_bounds;
  for (const Vector2d& b : c.arm_base)
    base_bounds.emplace_back(Vector3d(b.x(), b.y(), 0), Vector3d(b.x(), b.y(), 0));
  const NearestIndex bases(std::move(base_bounds));
  const double reach_bound = std::nextafter(v.reach_radius, std::numeric_limits<double>::infinity());

  const HeightField field(c, v);
  Hints hints;
  int base_hint = -1;
  for (size_t i = 0; i < rows; ++i)
    for (size_t j = 0; j < cols; ++j) {
      const Vector2d p(centre_x(i), centre_y(j));
      const double reach = bases.nearest(
          Vector3d(p.x(), p.y(), 0), reach_bound, [&](int k) { return (c.arm_base[k] - p).norm(); },
          base_hint);
      if (!(reach <= v.reach_radius)) {
        ++out.cells_out_of_reach;
        continue;
      }
      if (under_trail[i * cols + j]) {
        ++out.cells_under_trail;
        continue;
      }
      const double h = field.at(p, hints);
      if (h > 0) {
        Box b;
        b.center = Vector3d(p.x(), p.y(), h / 2);
        b.half_size = Vector3d(g.side / 2, g.side / 2, h / 2);
        out.boxes.push_back(b);
      }
    }

  if (v.add_obstacle_boxes) {
    if (c.goal) out.boxes.push_back(*c.goal);
    out.boxes.insert(out.boxes.end(), c.non_goal.begin(), c.non_goal.end());
  }
  return out;
}

}  // namespace leeway
