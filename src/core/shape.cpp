#include "leeway/core/shape.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace leeway {
namespace {

Eigen::Vector3d vertex(const Shape& s, int k) {
  const int v = s.ids ? s.ids[k] : k;
  return Eigen::Vector3d(s.vertices[3 * v], s.vertices[3 * v + 1], s.vertices[3 * v + 2]);
}

// The support point in the geom frame along the local direction n.
Eigen::Vector3d local_support(const Shape& s, const Eigen::Vector3d& n, int* hint) {
  const Eigen::Vector3d& z = s.size;
  auto sign = [](double v) { return v < 0 ? -1.0 : 1.0; };
  switch (s.type) {
    case mjGEOM_SPHERE: {
      const double len = n.norm();
      return len > 0 ? Eigen::Vector3d(z[0] * n / len) : Eigen::Vector3d(z[0], 0, 0);
    }
    case mjGEOM_CAPSULE: {
      const double len = n.norm();
      const Eigen::Vector3d ball = len > 0 ? Eigen::Vector3d(z[0] * n / len) : Eigen::Vector3d::Zero();
      return ball + Eigen::Vector3d(0, 0, sign(n[2]) * z[1]);
    }
    case mjGEOM_CYLINDER: {
      const double radial = std::hypot(n[0], n[1]);
      Eigen::Vector3d p(0, 0, sign(n[2]) * z[1]);
      if (radial > 0) p.head<2>() = z[0] * n.head<2>() / radial;
      return p;
    }
    case mjGEOM_ELLIPSOID: {
      const Eigen::Vector3d scaled = z.cwiseProduct(n);
      const double len = scaled.norm();
      return len > 0 ? Eigen::Vector3d(z.cwiseProduct(scaled) / len) : Eigen::Vector3d(z[0], 0, 0);
    }
    case mjGEOM_MESH: {
      int best = hint && *hint >= 0 && *hint < s.count ? *hint : 0;
      double top = n.dot(vertex(s, best));
      if (s.edges) {  // climb the hull's edges: a linear function has no other local maximum on it
        for (int from = -1; from != best;) {
          from = best;
          for (int e = s.edge_adr[from]; s.edges[e] >= 0; ++e) {
            const double v = n.dot(vertex(s, s.edges[e]));
            if (v > top) {
              top = v;
              best = s.edges[e];
            }
          }
        }
        if (hint) *hint = best;
        return vertex(s, best);
      }
      for (int k = 1; k < s.count; ++k) {
        const double v = n.dot(vertex(s, k));
        if (v > top) {
          top = v;
          best = k;
        }
      }
      return vertex(s, best);
    }
    default:  // a box (and a height field as its bounding box): the box's own corner
      break;
  }
  return Eigen::Vector3d::Zero();
}

// The world-frame box of a height field: x, y within +-size[0], +-size[1], z from -size[3] to
// size[2] (MuJoCo's hfield_size: radius x, radius y, elevation z, base z).
Box hfield_box(const mjModel& m, int geom, const Eigen::Vector3d& origin, const Eigen::Matrix3d& rot) {
  const mjtNum* hs = m.hfield_size + 4 * m.geom_dataid[geom];
  Box b;
  b.rotation = rot;
  b.half_size = Eigen::Vector3d(hs[0], hs[1], (hs[2] + hs[3]) / 2);
  b.center = origin + rot * Eigen::Vector3d(0, 0, (hs[2] - hs[3]) / 2);
  return b;
}

// The tight box of a mesh's vertices: the box in the geom frame, or for a geom that never moves the
// smaller (by volume) of that and the world-aligned box (MuJoCo re-orients a mesh to its inertial
// frame, which may be tilted against the part's own faces). A moving geom keeps the box in its own
// frame, which moves with it (the certificate's bound follows the box rigidly).
Box mesh_box(const Shape& s, bool fixed) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  Eigen::Vector3d wlo = lo, whi = hi;
  for (int k = 0; k < s.count; ++k) {
    const Eigen::Vector3d v = vertex(s, k);
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
    const Eigen::Vector3d w = s.rotation * v;
    wlo = wlo.cwiseMin(w);
    whi = whi.cwiseMax(w);
  }
  Box local;
  local.rotation = s.rotation;
  local.half_size = (hi - lo) / 2;
  local.center = s.origin + s.rotation * ((hi + lo) / 2);
  Box world;
  world.half_size = (whi - wlo) / 2;
  world.center = s.origin + (whi + wlo) / 2;
  return fixed && world.half_size.prod() < local.half_size.prod() ? world : local;
}

// A mesh geom's vertices: its convex hull's, when MuJoCo computed it (mesh_graph: numvert, numface,
// the vertices' edge addresses, their ids, then each vertex's neighbours ending in -1), else all of
// them (the same support).
void take_hull(const mjModel& m, int geom, Shape& s) {
  const int mesh = m.geom_dataid[geom];
  s.vertices = m.mesh_vert + 3 * m.mesh_vertadr[mesh];
  s.count = m.mesh_vertnum[mesh];
  const int graph = m.mesh_graphadr[mesh];
  if (graph >= 0) {
    const int* g = m.mesh_graph + graph;
    s.count = g[0];
    s.edge_adr = g + 2;
    s.ids = g + 2 + s.count;
    s.edges = g + 2 + 2 * s.count;
  }
}

// The point of the segment [a, b] closest to the origin, with its barycentric weight on b.
double segment_weight(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 <= 0) return 0.0;
  return std::clamp(-a.dot(ab) / len2, 0.0, 1.0);
}

// The point of the triangle (a, b, c) closest to the origin, by its Voronoi regions (Ericson,
// Real-Time Collision Detection, 5.1.5), and its barycentric weights.
Eigen::Vector3d triangle_closest(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                 Eigen::Vector3d& w) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = -a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) {
    w = Eigen::Vector3d(1, 0, 0);
    return a;
  }
  const Eigen::Vector3d bp = -b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) {
    w = Eigen::Vector3d(0, 1, 0);
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    {
      w = Eigen::Vector3d(1 - v, v, 0);
      return a + v * ab;
    }
  }
  const Eigen::Vector3d cp = -c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) {
    w = Eigen::Vector3d(0, 0, 1);
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double v = d2 / (d2 - d6);
    {
      w = Eigen::Vector3d(1 - v, 0, v);
      return a + v * ac;
    }
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double v = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    {
      w = Eigen::Vector3d(0, 1 - v, v);
      return b + v * (c - b);
    }
  }
  const double denom = 1 / (va + vb + vc);
  const double v = vb * denom, u = vc * denom;
  {
    w = Eigen::Vector3d(1 - v - u, v, u);
    return a + v * ab + u * ac;
  }
}

// GJK's simplex: up to four points of the Minkowski difference.
struct Simplex {
  std::array<Eigen::Vector3d, 4> p{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                   Eigen::Vector3d::Zero()};
  int n = 0;

  // Replaces the simplex by the smallest face holding its point closest to the origin, and returns
  // that point. A tetrahedron that holds the origin returns zero.
  Eigen::Vector3d reduce() {
    switch (n) {
      case 1:
        return p[0];
      case 2: {
        const double t = segment_weight(p[0], p[1]);
        keep({1 - t, t, 0, 0});
        return (1 - t) * p[0] + t * p[1];
      }
      case 3: {
        Eigen::Vector3d w;
        const Eigen::Vector3d x = triangle_closest(p[0], p[1], p[2], w);
        keep({w[0], w[1], w[2], 0});
        return x;
      }
      default:
        return tetrahedron();
    }
  }

 private:
  void keep(const std::array<double, 4>& weight) {
    int k = 0;
    for (int i = 0; i < n; ++i)
      if (weight[static_cast<size_t>(i)] > 0) p[static_cast<size_t>(k++)] = p[static_cast<size_t>(i)];
    n = std::max(k, 1);
  }

  Eigen::Vector3d tetrahedron() {
    // The origin is inside when it is on the inner side of each face (or on it).
    static constexpr int kFace[4][4] = {{0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 3, 1}, {1, 2, 3, 0}};
    // A flat tetrahedron (its fourth point in the plane of the others, near convergence) holds no
    // volume: its closest point is on a face.
    const double volume = (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]);
    const double scale = (p[1] - p[0]).norm() + (p[2] - p[0]).norm() + (p[3] - p[0]).norm();
    const bool flat = std::abs(volume) <= 1e-12 * scale * scale * scale;
    bool inside = !flat;
    double best = INFINITY;
    Eigen::Vector3d closest = Eigen::Vector3d::Zero();
    std::array<double, 4> weight{};
    for (const auto& f : kFace) {
      const Eigen::Vector3d &a = p[f[0]], &b = p[f[1]], &c = p[f[2]], &opposite = p[f[3]];
      const Eigen::Vector3d normal = (b - a).cross(c - a);
      const double side_origin = normal.dot(-a), side_opposite = normal.dot(opposite - a);
      if (!flat && side_origin * side_opposite >= 0) continue;  // the origin is on the inner side
      inside = false;
      Eigen::Vector3d w;
      const Eigen::Vector3d x = triangle_closest(a, b, c, w);
      if (x.squaredNorm() < best) {
        best = x.squaredNorm();
        closest = x;
        weight = {};
        weight[static_cast<size_t>(f[0])] = w[0];
        weight[static_cast<size_t>(f[1])] = w[1];
        weight[static_cast<size_t>(f[2])] = w[2];
      }
    }
    if (inside) return Eigen::Vector3d::Zero();
    keep(weight);
    return closest;
  }
};

}  // namespace

Eigen::Vector3d Shape::support_point(const Eigen::Vector3d& n, int* hint) const {
  if (type == mjGEOM_BOX || type == mjGEOM_HFIELD) {
    const Eigen::Vector3d local = box.rotation.transpose() * n;
    Eigen::Vector3d corner = box.half_size;
    for (int k = 0; k < 3; ++k)
      if (local[k] < 0) corner[k] = -corner[k];
    return box.center + box.rotation * corner;
  }
  return origin + rotation * local_support(*this, rotation.transpose() * n, hint);
}

double Shape::support(const Eigen::Vector3d& n, int* hint) const {
  if (type == mjGEOM_PLANE) {
    const Eigen::Vector3d normal = rotation.col(2);
    const Eigen::Vector3d along = n.dot(normal) * normal;
    // The half-space below the surface is unbounded in every direction but the normal's.
    if ((n - along).norm() > 1e-12 * n.norm() || n.dot(normal) <= 0) return INFINITY;
    return n.dot(origin);
  }
  if (type == mjGEOM_BOX || type == mjGEOM_HFIELD)
    return n.dot(box.center) + (box.rotation.transpose() * n).cwiseAbs().dot(box.half_size);
  return n.dot(support_point(n, hint));
}

Shape box_shape(const Box& box) {
  Shape s;
  s.type = mjGEOM_BOX;
  s.origin = box.center;
  s.rotation = box.rotation;
  s.size = box.half_size;
  s.box = box;
  s.radius = box.half_size.norm();
  return s;
}

Shape geom_shape(const mjModel& m, const mjData& d, int geom, const HullExtent* extent) {
  Shape s;
  s.type = m.geom_type[geom];
  s.origin = vec3(d.geom_xpos + 3 * geom);
  s.rotation = mat3(d.geom_xmat + 9 * geom);
  s.size = vec3(m.geom_size + 3 * geom);
  switch (s.type) {
    case mjGEOM_MESH: {
      take_hull(m, geom, s);
      if (extent) {  // the box in the geom frame
        s.box.center = s.origin + s.rotation * extent->centre;
        s.box.rotation = s.rotation;
        s.box.half_size = extent->half_size;
        s.radius = extent->radius;
        return s;
      }
      s.box = mesh_box(s, m.body_weldid[m.geom_bodyid[geom]] == 0);
      s.radius = 0;
      for (int k = 0; k < s.count; ++k)
        s.radius = std::max(s.radius, (s.origin + s.rotation * vertex(s, k) - s.box.center).norm());
      return s;
    }
    case mjGEOM_HFIELD:
      s.box = hfield_box(m, geom, s.origin, s.rotation);
      s.radius = s.box.half_size.norm();
      return s;
    default:
      break;
  }
  s.box.center = s.origin;
  s.box.rotation = s.rotation;
  switch (s.type) {
    case mjGEOM_BOX:
      s.box.half_size = s.size;
      s.radius = s.size.norm();
      break;
    case mjGEOM_ELLIPSOID:
      s.box.half_size = s.size;
      s.radius = s.size.maxCoeff();
      break;
    case mjGEOM_SPHERE:
      s.box.half_size = Eigen::Vector3d::Constant(s.size[0]);
      s.radius = s.size[0];
      break;
    case mjGEOM_CAPSULE:
      s.box.half_size = Eigen::Vector3d(s.size[0], s.size[0], s.size[1] + s.size[0]);
      s.radius = s.size[0] + s.size[1];
      break;
    case mjGEOM_CYLINDER:
      s.box.half_size = Eigen::Vector3d(s.size[0], s.size[0], s.size[1]);
      s.radius = std::hypot(s.size[0], s.size[1]);
      break;
    default:  // a plane
      s.box.half_size = Eigen::Vector3d::Constant(INFINITY);
      s.radius = INFINITY;
      break;
  }
  return s;
}

HullExtent hull_extent(const mjModel& m, int geom) {
  Shape s;
  take_hull(m, geom, s);
  Eigen::AlignedBox3d box;
  for (int k = 0; k < s.count; ++k) box.extend(vertex(s, k));
  HullExtent out;
  out.centre = box.center();
  out.half_size = box.sizes() / 2;
  for (int k = 0; k < s.count; ++k) out.radius = std::max(out.radius, (vertex(s, k) - out.centre).norm());
  return out;
}

ShapeDistance convex_distance(const Shape& a, const Shape& b, double tolerance, int* hint_a, int* hint_b) {
  ShapeDistance out;
  int own_a = 0, own_b = 0;  // the iteration's directions converge: each support climbs from the last
  if (!hint_a) hint_a = &own_a;
  if (!hint_b) hint_b = &own_b;
  auto support = [&](const Eigen::Vector3d& dir) -> Eigen::Vector3d {  // a value: the terms are temporaries
    return a.support_point(dir, hint_a) - b.support_point(-dir, hint_b);
  };
  Simplex simplex;
  Eigen::Vector3d v = a.box.center - b.box.center;  // a point near the Minkowski difference a - b
  if (v.squaredNorm() == 0) v = Eigen::Vector3d::UnitX();
  simplex.p[0] = support(-v);
  simplex.n = 1;
  v = simplex.p[0];
  double lower = 0;
  for (int iteration = 0; iteration < 64; ++iteration) {
    const double len = v.norm();
    if (len <= tolerance) {  // the origin is (within the tolerance) in a - b: they touch
      out.lower = 0;
      out.upper = len;
      return out;
    }
    const Eigen::Vector3d w = support(-v);
    // Every point x of a - b has x . v >= w . v: the plane normal to v at distance w . v / |v|
    // separates the origin from a - b, so the distance is at least that.
    const double bound = w.dot(v) / len;
    if (bound > lower) {
      lower = bound;
      out.axis = -v / len;  // from a toward b
    }
    if (len - lower <= tolerance) break;
    if (simplex.n == 4) break;  // rounding: a full simplex that does not hold the origin
    simplex.p[static_cast<size_t>(simplex.n++)] = w;
    const Eigen::Vector3d next = simplex.reduce();
    if (next.norm() >= len) break;  // no progress (rounding)
    v = next;
  }
  out.lower = std::max(0.0, lower);
  out.upper = v.norm();
  return out;
}

double shape_distance(const Shape& a, const Shape& b) {
  if (a.is_box() && b.is_box()) return box_distance(a.box, b.box);
  if (a.plane() || b.plane()) {
    const Shape& plane = a.plane() ? a : b;
    const Shape& other = a.plane() ? b : a;
    if (other.plane()) return 0.0;
    const Eigen::Vector3d normal = plane.rotation.col(2);
    // The other shape's lowest point along the normal, above the surface through the origin.
    return std::max(0.0, -other.support(-normal) - normal.dot(plane.origin));
  }
  return convex_distance(a, b).lower;
}

Eigen::AlignedBox3d aligned(const Shape& s) {
  Eigen::AlignedBox3d out;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(k);
    out.max()[k] = s.support(e);
    out.min()[k] = -s.support(-e);
  }
  return out;
}

}  // namespace leeway
