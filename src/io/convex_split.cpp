#include "leeway/io/convex_split.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <random>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "core/random.hpp"
#include "io/convex_hull.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/numbers.hpp"

namespace leeway {
namespace {

using detail::convex_hull;
using detail::Hull;
using Eigen::Vector3d;

// MuJoCo 2.2.2 refuses a mesh whose volume is below about 1e-15 m^3 ("mesh volume is too small");
// pieces are kept a hundred times above that.
constexpr double kMinVolume = 1e-13;
// Merged pieces may touch other pieces but overlap none deeper than this [m] (a tenth of leeway
// check's overlap tolerance).
constexpr double kOverlapDepth = 1e-5;

// ---- The part: distance to its surface (a bounding-volume tree) and, when closed, inside tests.

Vector3d closest_on_triangle(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  // Ericson, Real-Time Collision Detection, 5.1.5: the region of p among the triangle's features.
  const Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) return a;  // a degenerate triangle: its first corner is on it
  return a + ab * (vb / denom) + ac * (vc / denom);
}

// The solid angle of the triangle (a, b, c) seen from the origin [sr], signed by its orientation
// (Van Oosterom and Strackee).
double solid_angle(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const double la = a.norm(), lb = b.norm(), lc = c.norm();
  const double num = a.dot(b.cross(c));
  const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
  return 2 * std::atan2(num, den);
}

class PartSolid {
 public:
  // `triangles` three vertices per triangle, `ids` their welded vertex numbers (equal ids: equal
  // positions).
  PartSolid(std::vector<Vector3d> triangles, const std::vector<int>& ids, bool closed, double eps)
      : tri_(std::move(triangles)), closed_(closed), eps_(eps) {
    std::vector<int> order(tri_.size() / 3);
    std::iota(order.begin(), order.end(), 0);
    root_ = build(order, 0, static_cast<int>(order.size()), ids);
    order_ = std::move(order);
  }

  bool closed() const { return closed_; }

  // Distance from p to the nearest triangle [m].
  double surface_distance(const Vector3d& p) const {
    double best = std::numeric_limits<double>::infinity();
    std::vector<int> stack = {root_};
    while (!stack.empty()) {
      const Node& node = nodes_[stack.back()];
      stack.pop_back();
      const double box = (p - p.cwiseMax(node.lo).cwiseMin(node.hi)).norm();
      if (box >= best) continue;
      if (node.left < 0) {
        for (int i = node.first; i < node.first + node.count; ++i) {
          const int t = order_[i];
          best = std::min(best,
                          (p - closest_on_triangle(p, tri_[3 * t], tri_[3 * t + 1], tri_[3 * t + 2])).norm());
        }
      } else {
        stack.push_back(node.left);
        stack.push_back(node.right);
      }
    }
    return best;
  }

  // Inside the solid a closed mesh bounds: its generalized winding number (the triangles' solid
  // angles over 4 pi) is at least 1/2 in magnitude. A tree node whose box p lies outside (by more
  // than eps) counts by its boundary instead of its triangles, when that is shorter: its triangles
  // and the fan from the box's centre over its boundary edges, reversed, form a closed surface
  // within the box, whose winding number is 0 outside the box, so the triangles' solid angle is
  // the fan's over the edges as they run (exact, not an approximation).
  bool inside(const Vector3d& p) const {
    double omega = 0;
    std::vector<int> stack = {root_};
    while (!stack.empty()) {
      const Node& node = nodes_[stack.back()];
      stack.pop_back();
      const bool outside =
          ((node.lo.array() - eps_ > p.array()) || (p.array() > node.hi.array() + eps_)).any();
      if (outside && node.edge_count < node.triangles) {
        const Vector3d c = 0.5 * (node.lo + node.hi) - p;
        for (int e = node.edge_first; e < node.edge_first + node.edge_count; ++e)
          omega += solid_angle(c, tri_[edges_[e].first] - p, tri_[edges_[e].second] - p);
      } else if (node.left < 0) {
        for (int i = node.first; i < node.first + node.count; ++i) {
          const int t = 3 * order_[i];
          omega += solid_angle(tri_[t] - p, tri_[t + 1] - p, tri_[t + 2] - p);
        }
      } else {
        stack.push_back(node.left);
        stack.push_back(node.right);
      }
    }
    return std::abs(omega) >= 2 * M_PI;
  }

  // The generalized winding number at p summed over every triangle (the reference inside() must
  // equal; for tests).
  double winding_number_brute(const Vector3d& p) const {
    double omega = 0;
    for (size_t t = 0; t < tri_.size(); t += 3)
      omega += solid_angle(tri_[t] - p, tri_[t + 1] - p, tri_[t + 2] - p);
    return omega / (4 * M_PI);
  }

  // Distance to the solid (closed) or to the surface (open) [m].
  double distance(const Vector3d& p) const {
    const double d = surface_distance(p);
    return d > 0 && closed_ && inside(p) ? 0 : d;
  }

 private:
  struct Node {
    Vector3d lo, hi;
    int left = -1, right = -1, first = 0, count = 0;  // children, or the leaf's triangles in order_
    int triangles = 0;                                // below this node
    int edge_first = 0, edge_count = 0;               // its boundary's directed edges in edges_
  };

  // The node's boundary: its triangles' directed edges (corner indices into tri_) less those that
  // run both ways (by welded vertex), each left once per uncancelled use.
  std::vector<std::pair<int, int>> boundary(const std::vector<std::pair<int, int>>& edges,
                                            const std::vector<int>& ids) const {
    std::unordered_map<std::uint64_t, std::vector<std::pair<int, int>>> net;  // by (low id, high id)
    std::vector<std::uint64_t> keys;
    for (const auto& e : edges) {
      const std::uint64_t a = static_cast<std::uint32_t>(ids[e.first]),
                          b = static_cast<std::uint32_t>(ids[e.second]);
      if (a == b) continue;
      const std::uint64_t key = std::min(a, b) << 32 | std::max(a, b);
      auto& list = net[key];
      if (list.empty()) keys.push_back(key);
      if (!list.empty() && ids[list.back().first] != ids[e.first])
        list.pop_back();  // runs the other way: they cancel
      else
        list.push_back(e);
    }
    std::vector<std::pair<int, int>> out;
    for (const auto key : keys)
      for (const auto& e : net[key]) out.push_back(e);
    return out;
  }

  int build(std::vector<int>& order, int first, int last, const std::vector<int>& ids) {
    Node node;
    node.lo = Vector3d::Constant(std::numeric_limits<double>::infinity());
    node.hi = -node.lo;
    node.triangles = last - first;
    for (int i = first; i < last; ++i)
      for (int k = 0; k < 3; ++k) {
        node.lo = node.lo.cwiseMin(tri_[3 * order[i] + k]);
        node.hi = node.hi.cwiseMax(tri_[3 * order[i] + k]);
      }
    std::vector<std::pair<int, int>> edges;
    if (last - first > 4) {
      int axis = 0;
      (node.hi - node.lo).maxCoeff(&axis);
      const int mid = (first + last) / 2;
      auto centre = [&](int t) { return tri_[3 * t][axis] + tri_[3 * t + 1][axis] + tri_[3 * t + 2][axis]; };
      std::nth_element(order.begin() + first, order.begin() + mid, order.begin() + last,
                       [&](int a, int b) { return centre(a) < centre(b); });
      node.left = build(order, first, mid, ids);
      node.right = build(order, mid, last, ids);
      for (const int child : {node.left, node.right}) {
        const Node& c = nodes_[child];
        if (!closed_) break;
        edges.insert(edges.end(), edges_.begin() + c.edge_first,
                     edges_.begin() + c.edge_first + c.edge_count);
      }
    } else {
      node.first = first;
      node.count = last - first;
      for (int i = first; i < last; ++i)
        for (int k = 0; k < 3; ++k) edges.emplace_back(3 * order[i] + k, 3 * order[i] + (k + 1) % 3);
    }
    if (closed_) {
      edges = boundary(edges, ids);
      node.edge_first = static_cast<int>(edges_.size());
      node.edge_count = static_cast<int>(edges.size());
      edges_.insert(edges_.end(), edges.begin(), edges.end());
    } else {
      node.edge_count = std::numeric_limits<int>::max();
    }
    nodes_.push_back(node);
    return static_cast<int>(nodes_.size()) - 1;
  }

  std::vector<Vector3d> tri_;
  bool closed_;
  double eps_;
  std::vector<Node> nodes_;
  std::vector<int> order_;
  std::vector<std::pair<int, int>> edges_;
  int root_ = 0;
};

// ---- Cells: the part's faces clipped to an intersection of half-spaces.

// The half-space n.x - d >= 0 (n a unit vector).
struct Plane {
  Vector3d n;
  double d = 0;
  double side(const Vector3d& p) const { return n.dot(p) - d; }
  Plane flipped() const { return {-n, -d}; }
};

// A convex polygon of the part's surface and the outward normal of the triangle it was cut from.
struct Face {
  std::vector<Vector3d> polygon;
  Vector3d normal;
};

// A piece before its hull: the part's faces within the cell (the half-spaces `planes`), and the
// cell's corners inside the part's solid (docs/mjcf-conventions.md, "CAD meshes": with the faces,
// they hold the solid within the cell in their hull).
struct Cell {
  std::vector<Face> faces;
  std::vector<Plane> planes;
  std::vector<Vector3d> corners;

  std::vector<Vector3d> points() const {
    std::vector<Vector3d> out = corners;
    for (const auto& f : faces) out.insert(out.end(), f.polygon.begin(), f.polygon.end());
    return out;
  }
};

// Sorts `face` to the sides of `plane` (points within eps of it count as on it), clipping it when
// it crosses. A face in the plane goes to the side its solid lies on (against its outward normal);
// a face on one side that only touches the plane goes to that side alone.
void split_face(const Face& face, const Plane& plane, double eps, std::vector<Face>& plus,
                std::vector<Face>& minus) {
  const size_t m = face.polygon.size();
  std::vector<double> s(m);
  bool any_plus = false, any_minus = false;
  for (size_t i = 0; i < m; ++i) {
    s[i] = plane.side(face.polygon[i]);
    any_plus = any_plus || s[i] > eps;
    any_minus = any_minus || s[i] < -eps;
  }
  if (!any_plus && !any_minus) {
    (face.normal.dot(plane.n) > 0 ? minus : plus).push_back(face);
    return;
  }
  if (!any_minus) return plus.push_back(face);
  if (!any_plus) return minus.push_back(face);
  Face p{{}, face.normal}, q{{}, face.normal};
  for (size_t i = 0; i < m; ++i) {
    const size_t j = (i + 1) % m;
    const Vector3d& a = face.polygon[i];
    if (s[i] >= -eps) p.polygon.push_back(a);
    if (s[i] <= eps) q.polygon.push_back(a);
    if ((s[i] > eps && s[j] < -eps) || (s[i] < -eps && s[j] > eps)) {
      const Vector3d x = a + (face.polygon[j] - a) * (s[i] / (s[i] - s[j]));
      p.polygon.push_back(x);
      q.polygon.push_back(x);
    }
  }
  plus.push_back(std::move(p));
  minus.push_back(std::move(q));
}

// The child of `parent` on the side `plane` keeps (its faces given), with its corners: the parent's
// on that side and the new vertices of the cell (the plane with two others) inside the solid.
Cell child_cell(const Cell& parent, std::vector<Face> faces, const Plane& plane, const PartSolid& solid,
                double eps) {
  Cell cell;
  cell.faces = std::move(faces);
  cell.planes = parent.planes;
  cell.planes.push_back(plane);
  for (const auto& c : parent.corners)
    if (plane.side(c) >= -eps) cell.corners.push_back(c);
  if (!solid.closed()) return cell;
  const size_t n = cell.planes.size();
  for (size_t i = 0; i + 1 < n; ++i)
    for (size_t j = i + 1; j + 1 < n; ++j) {
      Eigen::Matrix3d a;
      a << cell.planes[i].n.transpose(), cell.planes[j].n.transpose(), plane.n.transpose();
      if (std::abs(a.determinant()) < 1e-9) continue;
      const Vector3d x = a.partialPivLu().solve(Vector3d(cell.planes[i].d, cell.planes[j].d, plane.d));
      bool in_cell = true;
      for (const auto& h : cell.planes) in_cell = in_cell && h.side(x) >= -eps;
      if (in_cell && solid.inside(x)) cell.corners.push_back(x);
    }
  return cell;
}

// ---- A piece's hull: thickened when thin, its excess over the part measured on samples.

struct Measured {
  Hull hull;
  bool thickened = false;
  double excess = 0;
};

// The principal axes of points (the columns) and the points' extents along them.
std::pair<Eigen::Matrix3d, Vector3d> principal_axes(const std::vector<Vector3d>& points) {
  Vector3d mean = Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : points) cov += (p - mean) * (p - mean).transpose();
  const Eigen::Matrix3d axes = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors();
  Vector3d lo = Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& p : points) {
    const Vector3d q = axes.transpose() * p;
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  return {axes, hi - lo};
}

// Adds the points moved by +-pad along u.
void pad_along(std::vector<Vector3d>& points, const Vector3d& u, double pad) {
  const size_t n = points.size();
  for (size_t i = 0; i < n; ++i) {
    points.push_back(points[i] + pad * u);
    points[i] -= pad * u;
  }
}

// The hull of `points`, thickened (points added at +-pad along its thin directions) until it is at
// least `thickness` wide along each facet normal and holds kMinVolume: MuJoCo's qhull refuses a flat
// mesh, and its inertia a mesh of too small a volume. Sets `thickened` when points were added.
Hull thick_hull(std::vector<Vector3d> points, double thickness, bool& thickened) {
  thickened = false;
  for (int round = 0; round < 64; ++round) {
    Hull hull = convex_hull(points);
    if (hull.ok && hull.volume >= kMinVolume) {
      double thinnest = std::numeric_limits<double>::infinity();
      Vector3d normal = Vector3d::UnitZ();
      for (const auto& plane : hull.planes) {
        const Vector3d n = plane.head<3>();
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (const auto& v : hull.vertices) {
          lo = std::min(lo, n.dot(v));
          hi = std::max(hi, n.dot(v));
        }
        if (hi - lo < thinnest) std::tie(thinnest, normal) = std::make_pair(hi - lo, n);
      }
      if (thinnest >= thickness * (1 - 1e-9)) return hull;
      points = hull.vertices;
      pad_along(points, normal, 0.5 * (thickness - thinnest));
    } else {
      if (hull.ok) points = hull.vertices;
      const auto [axes, extent] = principal_axes(points);
      // A 3-d hull below kMinVolume, or a flat set with no thin axis (never seen): every axis grows.
      const bool all = hull.ok || extent.minCoeff() >= thickness;
      for (int k = 0; k < 3; ++k)
        if (all || extent[k] < thickness) pad_along(points, axes.col(k), 0.5 * thickness);
    }
    thickened = true;
  }
  LEEWAY_DEMAND(false);  // each round widens the hull by `thickness` along a thin direction
  return {};
}

// The largest distance to the part over the hull's vertices and `samples` random points, half on
// its surface (uniform by area) and half inside (uniform by volume). A sample nearer the surface
// than the largest so far needs no inside test.
double measure_excess(const Hull& hull, const PartSolid& solid, int samples, std::mt19937_64& rng) {
  double worst = 0;
  auto visit = [&](const Vector3d& p) {
    const double d = solid.surface_distance(p);
    if (d > worst && !(solid.closed() && solid.inside(p))) worst = d;
  };
  for (const auto& v : hull.vertices) visit(v);
  Vector3d centre = Vector3d::Zero();
  for (const auto& v : hull.vertices) centre += v;
  centre /= static_cast<double>(hull.vertices.size());
  std::vector<double> areas, volumes;
  double area = 0, volume = 0;
  for (const auto& t : hull.triangles) {
    area += 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).norm();
    volume += std::abs((t[0] - centre).dot((t[1] - centre).cross(t[2] - centre))) / 6;
    areas.push_back(area);
    volumes.push_back(volume);
  }
  if (hull.triangles.empty() || !(area > 0)) return worst;
  auto pick = [&](const std::vector<double>& cumulative) {
    const double u = detail::unit(rng) * cumulative.back();
    const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), u);
    return std::min<size_t>(it - cumulative.begin(), cumulative.size() - 1);
  };
  for (int i = 0; i < samples / 2; ++i) {
    const auto& t = hull.triangles[pick(areas)];
    double r1 = detail::unit(rng), r2 = detail::unit(rng);
    if (r1 + r2 > 1) std::tie(r1, r2) = std::make_pair(1 - r1, 1 - r2);
    visit(t[0] + r1 * (t[1] - t[0]) + r2 * (t[2] - t[0]));
  }
  if (!(volume > 0)) return worst;
  for (int i = 0; i < samples - samples / 2; ++i) {
    // A point of the tetrahedron (centre, facet) uniform by volume: a uniform point of the facet,
    // moved towards the centre by the cube root of a uniform number.
    const auto& t = hull.triangles[pick(volumes)];
    double r1 = detail::unit(rng), r2 = detail::unit(rng);
    if (r1 + r2 > 1) std::tie(r1, r2) = std::make_pair(1 - r1, 1 - r2);
    const Vector3d on_facet = t[0] + r1 * (t[1] - t[0]) + r2 * (t[2] - t[0]);
    visit(centre + std::cbrt(detail::unit(rng)) * (on_facet - centre));
  }
  return worst;
}

// ---- The split: the plane that minimises the two halves' hull volumes.

// Offsets to try along a direction: 15 evenly spaced between the points' extremes, and the points'
// own distinct offsets (at most 33, evenly chosen), where a part's faces and steps lie.
std::vector<double> candidate_offsets(std::vector<double> along, double margin) {
  std::sort(along.begin(), along.end());
  const double lo = along.front(), hi = along.back();
  std::vector<double> out;
  if (hi - lo <= 2 * margin) return out;
  for (int k = 1; k < 16; ++k) out.push_back(lo + (hi - lo) * k / 16.0);
  std::vector<double> distinct;
  for (const double a : along)
    if (a > lo + margin && a < hi - margin && (distinct.empty() || a - distinct.back() > margin))
      distinct.push_back(a);
  const size_t keep = std::min<size_t>(distinct.size(), 33);
  for (size_t k = 0; k < keep; ++k) out.push_back(distinct[k * distinct.size() / keep]);
  return out;
}

// The two halves of `cell` by the best plane, or nothing when no plane leaves faces on both sides.
std::optional<std::pair<Cell, Cell>> split_cell(const Cell& cell, const PartSolid& solid, double eps) {
  const std::vector<Vector3d> points = cell.points();
  std::vector<Vector3d> directions = {Vector3d::UnitX(), Vector3d::UnitY(), Vector3d::UnitZ()};
  const Eigen::Matrix3d axes = principal_axes(points).first;
  for (int k = 0; k < 3; ++k) {
    bool known = false;
    for (const auto& d : directions) known = known || std::abs(d.dot(axes.col(k))) > 0.999;
    if (!known) directions.push_back(axes.col(k));
  }
  std::vector<std::pair<Plane, double>> scored;  // each plane with its halves' hull volumes
  double best_score = std::numeric_limits<double>::infinity();
  auto halves = [&](const Plane& plane) {
    std::vector<Face> plus, minus;
    for (const auto& f : cell.faces) split_face(f, plane, eps, plus, minus);
    // Without the new corners (they need inside tests; the chosen split adds them).
    return std::make_pair(Cell{std::move(plus), {}, {}}, Cell{std::move(minus), {}, {}});
  };
  for (const auto& u : directions) {
    std::vector<double> along;
    for (const auto& p : points) along.push_back(u.dot(p));
    for (const double offset : candidate_offsets(along, 1e3 * eps)) {
      const auto [a, b] = halves(Plane{u, offset});
      if (a.faces.empty() || b.faces.empty()) continue;
      const double score = convex_hull(a.points()).volume + convex_hull(b.points()).volume;
      scored.emplace_back(Plane{u, offset}, score);
      best_score = std::min(best_score, score);
    }
  }
  // Planes of the same volumes (common in axis-aligned parts: any cut of a table between its legs
  // leaves the same two boxes) are told apart by their halves' excesses, on a few samples.
  std::optional<Plane> best;
  double best_excess = std::numeric_limits<double>::infinity();
  for (const auto& [plane, score] : scored) {
    if (score > best_score * (1 + 1e-9) + 1e-15) continue;
    const auto [a, b] = halves(plane);
    std::mt19937_64 rng(1);
    const double excess = measure_excess(convex_hull(a.points()), solid, 64, rng) +
                          measure_excess(convex_hull(b.points()), solid, 64, rng);
    if (excess < best_excess) std::tie(best_excess, best) = std::make_pair(excess, plane);
  }
  if (!best) return std::nullopt;
  std::vector<Face> plus, minus;
  for (const auto& f : cell.faces) split_face(f, *best, eps, plus, minus);
  return std::make_pair(child_cell(cell, std::move(plus), *best, solid, eps),
                        child_cell(cell, std::move(minus), best->flipped(), solid, eps));
}

// The share of the bounding box's diagonal within which vertices are welded into one.
constexpr double kWeld = 1e-6;

struct CellHash {
  size_t operator()(const std::array<std::int64_t, 3>& c) const {
    std::uint64_t h = 0;
    for (const auto v : c) h = detail::splitmix(h ^ static_cast<std::uint64_t>(v));
    return static_cast<size_t>(h);
  }
};

// Moves every vertex within `radius` of a vertex kept before it onto the nearest such vertex (the
// first kept of equally near ones); the others are kept. Returns each vertex's number among the
// kept ones: equal numbers, equal positions.
std::vector<int> weld(std::vector<Vector3d>& points, double radius) {
  std::unordered_map<std::array<std::int64_t, 3>, std::vector<int>, CellHash> grid;  // kept per cell
  std::vector<Vector3d> kept;
  std::vector<int> ids(points.size());
  auto cell_of = [radius](const Vector3d& p) {
    std::array<std::int64_t, 3> c{};
    for (int k = 0; k < 3; ++k)
      c[k] = static_cast<std::int64_t>(std::clamp(std::floor(p[k] / radius), -4e18, 4e18));
    return c;
  };
  for (size_t i = 0; i < points.size(); ++i) {
    const auto c = cell_of(points[i]);
    int best = -1;
    double nearest = radius;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (const int k : it->second) {
            const double d = (kept[k] - points[i]).norm();
            if (d < nearest || (d == nearest && best >= 0 && k < best) || (d <= nearest && best < 0))
              std::tie(nearest, best) = std::make_pair(d, k);
          }
        }
    if (best < 0) {
      best = static_cast<int>(kept.size());
      kept.push_back(points[i]);
      grid[c].push_back(best);
    }
    ids[i] = best;
    points[i] = kept[best];
  }
  return ids;
}

// Every edge (by welded vertex) shared by an even number of triangles.
bool is_closed(const std::vector<int>& ids) {
  std::unordered_map<std::uint64_t, int> uses;
  for (size_t t = 0; t < ids.size(); t += 3)
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t a = static_cast<std::uint32_t>(ids[t + k]);
      const std::uint64_t b = static_cast<std::uint32_t>(ids[t + (k + 1) % 3]);
      if (a != b) ++uses[std::min(a, b) << 32 | std::max(a, b)];
    }
  for (const auto& [edge, count] : uses)
    if (count % 2) return false;
  return true;
}

// The mesh welded (kWeld of its box's diagonal), whether it is closed, and, when closed, its
// triangles turned to outward normals (for split_face). Sets `size`, the box's diagonal [m].
std::vector<Vector3d> prepare_mesh(std::vector<Vector3d> mesh, std::vector<int>& ids, bool& closed,
                                   double& size) {
  Vector3d lo = mesh.front(), hi = lo;
  for (const auto& p : mesh) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  size = (hi - lo).norm();
  if (!(size > 0)) throw InputError("the mesh has no extent: every vertex is at the same point");
  ids = weld(mesh, kWeld * size);
  closed = is_closed(ids);
  double signed_volume = 0;
  for (size_t t = 0; t < mesh.size(); t += 3) signed_volume += mesh[t].dot(mesh[t + 1].cross(mesh[t + 2]));
  if (closed && signed_volume < 0)  // inward normals: turned outward
    for (size_t t = 0; t < mesh.size(); t += 3) {
      std::swap(mesh[t + 1], mesh[t + 2]);
      std::swap(ids[t + 1], ids[t + 2]);
    }
  return mesh;
}

struct Piece {
  Cell cell;
  Measured measured;
  bool final = false;  // no plane splits it
};

// The gap between the bounding boxes of two point sets [m] (0 when they overlap).
double box_gap(const std::vector<Vector3d>& a, const std::vector<Vector3d>& b) {
  auto box = [](const std::vector<Vector3d>& points) {
    Vector3d lo = points.front(), hi = lo;
    for (const auto& p : points) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    return std::make_pair(lo, hi);
  };
  const auto [alo, ahi] = box(a);
  const auto [blo, bhi] = box(b);
  return (alo - bhi).cwiseMax(blo - ahi).cwiseMax(0).norm();
}

// Two hulls overlap by more than `depth`: no facet normal of either separates them to within it (a
// conservative test: edge-edge axes are not tried, so a near miss may count as an overlap).
bool hulls_overlap(const Hull& a, const Hull& b, double depth) {
  auto separated = [depth](const Hull& h, const Hull& other) {
    for (const auto& plane : h.planes) {
      double nearest = std::numeric_limits<double>::infinity();
      for (const auto& v : other.vertices) nearest = std::min(nearest, plane.head<3>().dot(v) + plane[3]);
      if (nearest >= -depth) return true;
    }
    return false;
  };
  return !separated(a, b) && !separated(b, a);
}

// Merges pairs of pieces whose joint hull stays within the tolerance and overlaps no other piece
// (leeway check reports obstacles overlapping by more than 1e-4 m), the least added hull volume
// first: a cut chosen for one piece can leave a flat part in strips. Pairs whose boxes lie more than
// the tolerance apart are not tried; each pair is measured once.
void merge_pieces(std::vector<Measured>& pieces, double tolerance,
                  const std::function<Measured(const std::vector<Vector3d>&)>& measure) {
  std::vector<int> ids(pieces.size());
  std::iota(ids.begin(), ids.end(), 0);
  int next_id = static_cast<int>(pieces.size());
  std::map<std::pair<int, int>, std::optional<Measured>> tried;
  while (pieces.size() > 1) {
    int best_i = -1, best_j = -1;
    double best_added = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < pieces.size(); ++i)
      for (size_t j = i + 1; j < pieces.size(); ++j) {
        const auto key = std::make_pair(ids[i], ids[j]);
        auto it = tried.find(key);
        if (it == tried.end()) {
          const auto& a = pieces[i].hull.vertices;
          const auto& b = pieces[j].hull.vertices;
          std::optional<Measured> merged;
          if (box_gap(a, b) <= tolerance) {
            std::vector<Vector3d> points = a;
            points.insert(points.end(), b.begin(), b.end());
            merged = measure(points);
            for (size_t k = 0; merged && k < pieces.size(); ++k)
              if (k != i && k != j && hulls_overlap(merged->hull, pieces[k].hull, kOverlapDepth))
                merged.reset();
            if (merged && merged->excess > tolerance) merged.reset();
          }
          it = tried.emplace(key, std::move(merged)).first;
        }
        if (!it->second) continue;
        const double added = it->second->hull.volume - pieces[i].hull.volume - pieces[j].hull.volume;
        if (added < best_added) std::tie(best_added, best_i, best_j) = std::make_tuple(added, int(i), int(j));
      }
    if (best_i < 0) return;
    pieces[best_i] = *tried.at({ids[best_i], ids[best_j]});
    ids[best_i] = next_id++;
    pieces.erase(pieces.begin() + best_j);
    ids.erase(ids.begin() + best_j);
  }
}

}  // namespace

ConvexSplit convex_split(const std::vector<Eigen::Vector3d>& triangles, const ConvexSplitOptions& options) {
  if (!(options.tolerance > 0) || !std::isfinite(options.tolerance))
    throw InputError("tolerance " + format_number(options.tolerance) + " m is not a finite number above 0");
  if (options.max_pieces < 1)
    throw InputError("max pieces " + std::to_string(options.max_pieces) + " is below 1");
  if (triangles.empty() || triangles.size() % 3 != 0)
    throw InputError("the mesh has " + std::to_string(triangles.size()) +
                     " vertices, not three per triangle");
  for (size_t i = 0; i < triangles.size(); ++i)
    if (!triangles[i].allFinite())
      throw InputError("triangle " + std::to_string(i / 3 + 1) + " vertex " + std::to_string(i % 3 + 1) +
                       " is not finite");
  ConvexSplit result;
  result.triangles = static_cast<int>(triangles.size() / 3);
  std::vector<int> ids;
  double size = 0;
  const std::vector<Vector3d> oriented = prepare_mesh(triangles, ids, result.closed, size);
  const double eps = 1e-9 * size;
  const PartSolid solid(oriented, ids, result.closed, eps);
  const double thickness = options.tolerance / 10;
  std::uint64_t measurements = 0;
  auto measure = [&](const std::vector<Vector3d>& points) {
    Measured m;
    m.hull = thick_hull(points, thickness, m.thickened);
    std::mt19937_64 rng(detail::splitmix(options.seed + measurements++));
    m.excess = measure_excess(m.hull, solid, options.samples, rng);
    return m;
  };
  std::vector<Piece> pieces(1);
  for (size_t t = 0; t < oriented.size(); t += 3) {
    const Vector3d normal = (oriented[t + 1] - oriented[t]).cross(oriented[t + 2] - oriented[t]);
    pieces[0].cell.faces.push_back({{oriented[t], oriented[t + 1], oriented[t + 2]}, normal});
  }
  pieces[0].measured = measure(pieces[0].cell.points());
  while (true) {
    int worst = -1;
    for (size_t i = 0; i < pieces.size(); ++i)
      if (!pieces[i].final && pieces[i].measured.excess > options.tolerance &&
          (worst < 0 || pieces[i].measured.excess > pieces[worst].measured.excess))
        worst = static_cast<int>(i);
    if (worst < 0 || static_cast<int>(pieces.size()) >= options.max_pieces) break;
    auto halves = split_cell(pieces[worst].cell, solid, eps);
    if (!halves) {
      pieces[worst].final = true;
      continue;
    }
    Measured first = measure(halves->first.points()), second = measure(halves->second.points());
    pieces[worst] = Piece{std::move(halves->first), std::move(first), false};
    pieces.push_back(Piece{std::move(halves->second), std::move(second), false});
  }
  std::vector<Measured> measured;
  for (auto& p : pieces) measured.push_back(std::move(p.measured));
  merge_pieces(measured, options.tolerance, measure);
  for (const auto& m : measured) {
    ConvexPiece out;
    out.vertices = m.hull.vertices;
    out.lo = out.hi = out.vertices.front();
    for (const auto& v : out.vertices) {
      out.lo = out.lo.cwiseMin(v);
      out.hi = out.hi.cwiseMax(v);
    }
    out.volume = m.hull.volume;
    out.excess = m.excess;
    out.thickened = m.thickened;
    result.worst_excess = std::max(result.worst_excess, out.excess);
    result.reached = result.reached && out.excess <= options.tolerance;
    result.pieces.push_back(std::move(out));
  }
  return result;
}

}  // namespace leeway
