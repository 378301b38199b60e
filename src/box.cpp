#include "leeway/box.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace leeway {
namespace {

// box_distance alternates closest-point projections between the two convex boxes (von Neumann's
// alternating projections), which converge to a closest pair. The run stops when the witnesses
// move less than kProjectionTolerance [m] in one round (far below any collision margin), or after
// kMaxProjectionRounds rounds as a guard: on boxes with parallel faces the convergence can be
// linear but slow, and the last pair is still a valid upper bound of the distance.
constexpr int kMaxProjectionRounds = 100000;
constexpr double kProjectionTolerance = 1e-12;

}  // namespace

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

double box_distance(const Box& a, const Box& b, Eigen::Vector3d* on_a, Eigen::Vector3d* on_b) {
  Eigen::Vector3d pa = closest_point(a, b.center);
  Eigen::Vector3d pb = closest_point(b, pa);
  if (box_penetration(a, b) >= 0) {
    // Touching or overlapping: distance 0 (the points are approximate witnesses).
    if (on_a) *on_a = pa;
    if (on_b) *on_b = pb;
    return 0.0;
  }
  for (int it = 0; it < kMaxProjectionRounds; ++it) {
    const Eigen::Vector3d na = closest_point(a, pb);
    const Eigen::Vector3d nb = closest_point(b, na);
    const double moved = (na - pa).norm() + (nb - pb).norm();
    pa = na;
    pb = nb;
    if (moved < kProjectionTolerance) break;
  }
  if (on_a) *on_a = pa;
  if (on_b) *on_b = pb;
  return (pa - pb).norm();
}

Box geom_box(const mjModel& m, const mjData& d, int geom) {
  Box b;
  b.center = Eigen::Map<const Eigen::Vector3d>(d.geom_xpos + 3 * geom);
  // MuJoCo stores xmat row-major.
  b.rotation = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d.geom_xmat + 9 * geom);
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
    default:
      b.half_size = Eigen::Vector3d::Constant(m.geom_rbound[geom]);
      break;
  }
  return b;
}

bool has_bounding_box(const mjModel& m, int geom) { return m.geom_type[geom] != mjGEOM_PLANE; }

}  // namespace leeway
