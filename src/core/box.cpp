#include "leeway/core/box.hpp"

#include "leeway/core/shape.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace leeway {

bool contains(const Box& box, const Eigen::Vector3d& p) {
  const Eigen::Vector3d local = box.rotation.transpose() * (p - box.center);
  return (local.array().abs() <= box.half_size.array()).all();
}

double box_penetration(const Box& a, const Box& b) {
  const Eigen::Vector3d d = b.center - a.center;
  double best = INFINITY;  // smallest overlap over the axes tried
  auto axis_overlap = [&](const Eigen::Vector3d& axis_in) {
    const double n = axis_in.norm();
    if (n < 1e-9) return;  // parallel edges: the face axes cover this case
    const Eigen::Vector3d axis = axis_in / n;
    const double ra = (a.rotation.transpose() * axis).cwiseAbs().dot(a.half_size);
    const double rb = (b.rotation.transpose() * axis).cwiseAbs().dot(b.half_size);
    best = std::min(best, ra + rb - std::abs(d.dot(axis)));
  };
  for (int i = 0; i < 3; ++i) axis_overlap(a.rotation.col(i));
  for (int i = 0; i < 3; ++i) axis_overlap(b.rotation.col(i));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) axis_overlap(a.rotation.col(i).cross(b.rotation.col(j)));
  return best;
}

Eigen::Vector3d closest_point(const Box& box, const Eigen::Vector3d& p) {
  const Eigen::Vector3d local = box.rotation.transpose() * (p - box.center);
  const Eigen::Vector3d clamped = local.cwiseMax(-box.half_size).cwiseMin(box.half_size);
  return box.center + box.rotation * clamped;
}

std::array<Eigen::Vector3d, 8> box_corners(const Box& b) {
  std::array<Eigen::Vector3d, 8> c;
  for (int k = 0; k < 8; ++k) {
    Eigen::Vector3d s;
    for (int i = 0; i < 3; ++i) s[i] = (k >> i & 1) ? b.half_size[i] : -b.half_size[i];
    c[static_cast<size_t>(k)] = b.center + b.rotation * s;
  }
  return c;
}

namespace {

// Closest points of segments [p1, q1] and [p2, q2] (Ericson, Real-Time Collision Detection, 5.1.9),
// parallel and degenerate segments included.
void closest_on_segments(const Eigen::Vector3d& p1, const Eigen::Vector3d& q1, const Eigen::Vector3d& p2,
                         const Eigen::Vector3d& q2, Eigen::Vector3d& c1, Eigen::Vector3d& c2) {
  const Eigen::Vector3d d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a <= 1e-30 && e <= 1e-30) {
    s = t = 0;
  } else if (a <= 1e-30) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 1e-30) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  c1 = p1 + d1 * s;
  c2 = p2 + d2 * t;
}

}  // namespace

double box_distance(const Box& a, const Box& b, Eigen::Vector3d* on_a, Eigen::Vector3d* on_b) {
  if (box_penetration(a, b) >= 0) {
    // Touching or overlapping: distance 0, witnessed by a point of A in B (or near it).
    const Eigen::Vector3d pa = closest_point(a, b.center);
    if (on_a) *on_a = pa;
    if (on_b) *on_b = closest_point(b, pa);
    return 0.0;
  }
  // Disjoint convex polytopes: a closest pair has a vertex of one box (its closest point on the
  // other box is then exact), or lies on an edge of each (the segments' closest points). Every
  // vertex against the other box and every edge pair covers both cases.
  const auto ca = box_corners(a), cb = box_corners(b);
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector3d best_a = a.center, best_b = b.center;
  auto consider = [&](const Eigen::Vector3d& pa, const Eigen::Vector3d& pb) {
    const double d = (pa - pb).squaredNorm();
    if (d < best) {
      best = d;
      best_a = pa;
      best_b = pb;
    }
  };
  for (const auto& v : ca) consider(v, closest_point(b, v));
  for (const auto& w : cb) consider(closest_point(a, w), w);
  Eigen::Vector3d c1, c2;
  for (int i = 0; i < 8; ++i)
    for (int ai = 0; ai < 3; ++ai) {
      if (i >> ai & 1) continue;  // each edge once: from the corner with bit ai clear
      const Eigen::Vector3d& p1 = ca[static_cast<size_t>(i)];
      const Eigen::Vector3d& q1 = ca[static_cast<size_t>(i | 1 << ai)];
      for (int j = 0; j < 8; ++j)
        for (int bi = 0; bi < 3; ++bi) {
          if (j >> bi & 1) continue;
          closest_on_segments(p1, q1, cb[static_cast<size_t>(j)], cb[static_cast<size_t>(j | 1 << bi)], c1,
                              c2);
          consider(c1, c2);
        }
    }
  if (on_a) *on_a = best_a;
  if (on_b) *on_b = best_b;
  return std::sqrt(best);
}

Box geom_box(const mjModel& m, const mjData& d, int geom) {
  Box b;
  b.center = Eigen::Map<const Eigen::Vector3d>(d.geom_xpos + 3 * geom);
  b.rotation = mat3(d.geom_xmat + 9 * geom);
  const double* s = m.geom_size + 3 * geom;
  switch (m.geom_type[geom]) {
    case mjGEOM_BOX:
    case mjGEOM_ELLIPSOID:
      b.half_size = Eigen::Vector3d(s[0], s[1], s[2]);
      break;
    case mjGEOM_SPHERE:
      b.half_size = Eigen::Vector3d::Constant(s[0]);
      break;
    case mjGEOM_CAPSULE:
      b.half_size = Eigen::Vector3d(s[0], s[0], s[1] + s[0]);
      break;
    case mjGEOM_CYLINDER:
      b.half_size = Eigen::Vector3d(s[0], s[0], s[1]);
      break;
    case mjGEOM_PLANE:
      b.half_size = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
      break;
    default:  // a mesh (its vertices' tight box) or a height field
      return geom_shape(m, d, geom).box;
  }
  return b;
}

bool has_bounding_box(const mjModel& m, int geom) { return m.geom_type[geom] != mjGEOM_PLANE; }

Eigen::AlignedBox3d aligned(const Box& b) {
  const Eigen::Vector3d reach = b.rotation.cwiseAbs() * b.half_size;
  return Eigen::AlignedBox3d(b.center - reach, b.center + reach);
}

}  // namespace leeway
