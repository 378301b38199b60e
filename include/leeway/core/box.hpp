#pragma once
//! @file box.hpp
//! Oriented collision boxes (thesis section 3.1) and the point-in-box test.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

namespace leeway {

//! An oriented box in world coordinates: centre, rotation (columns = box axes), half-sizes [m].
struct Box {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d half_size = Eigen::Vector3d::Zero();
};

//! True when point p lies inside the box or on its surface (section 3.1: transform the point into
//! the box frame and compare each coordinate with the half-size).
bool contains(const Box& box, const Eigen::Vector3d& p);

//! Separating-axis test of two oriented boxes (Gottschalk et al., the test cited in section 3.1)
//! over the 15 candidate axes. Returns the penetration depth [m] (> 0: the boxes overlap by that
//! much along the best axis, which for boxes is the exact minimum translation), 0 when they just
//! touch, and a negative value when they are separated (minus the gap along the best axis, a
//! lower bound of the true distance).
double box_penetration(const Box& a, const Box& b);

//! Closest point of the box to p (p itself when inside).
Eigen::Vector3d closest_point(const Box& box, const Eigen::Vector3d& p);

//! Euclidean distance [m] between two oriented boxes (0 when they touch or overlap), with the
//! closest points when the out-pointers are given. Exact (up to rounding): for disjoint boxes the
//! smallest of every vertex's distance to the other box and every edge pair's segment distance,
//! which covers every feature pair a closest pair of two convex polytopes can lie on.
double box_distance(const Box& a, const Box& b, Eigen::Vector3d* on_a = nullptr,
                    Eigen::Vector3d* on_b = nullptr);

//! The 3-vector at p[0], p[1], p[2] of a MuJoCo array (d.xanchor + 3 * joint, d.xaxis + 3 * joint, ...).
inline Eigen::Vector3d vec3(const mjtNum* p) { return Eigen::Vector3d(p[0], p[1], p[2]); }
//! The rotation matrix MuJoCo stores row-major at p (d.xmat + 9 * body, d.geom_xmat + 9 * geom, ...).
inline Eigen::Matrix3d mat3(const mjtNum* p) {
  return Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>>(p);
}

//! World-frame box of a geom after kinematics: exact for boxes; for other types the box bounds the
//! geom in its own frame (sphere, capsule, cylinder, ellipsoid); a mesh's is the tight box of its
//! convex hull's vertices (in the geom frame or the world's axes, whichever is smaller: shape.hpp),
//! a height field's the box of its extent. Planes have no finite box: the half-size is infinite.
Box geom_box(const mjModel& m, const mjData& d, int geom);

//! The one rule for planes: false for a plane, true for every other geom type. A plane has no
//! finite box, and an infinite box would contain every point above the floor (Algorithm 1 would
//! make it every goal's obstacle) and meet every link (clearance 0). So planes take part in no
//! box-based step: the goal search and categorisation (categorize, check_scene), the volume and
//! the clearance all skip them; check_scene reports a collidable plane as a problem instead (a
//! floor must have contype="0" conaffinity="0", docs/mjcf-conventions.md).
bool has_bounding_box(const mjModel& m, int geom);

//! The 8 corners of a box [m], corner k having coordinate i at +half_size[i] when bit i of k is set.
std::array<Eigen::Vector3d, 8> box_corners(const Box& b);

//! The world-aligned box around an oriented box [m].
Eigen::AlignedBox3d aligned(const Box& b);

}  // namespace leeway
