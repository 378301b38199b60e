#pragma once
//! @file shape.hpp
//! Collidable geoms as MuJoCo collides them: every geom type as a convex shape given by its support
//! function (a mesh as the convex hull of its vertices, as MuJoCo collides meshes), with the box that
//! bounds it, and the distance of two such shapes (GJK) as a proven lower bound.

#include <mujoco/mujoco.h>

#include <Eigen/Core>

#include "leeway/core/box.hpp"

namespace leeway {

//! A geom's convex shape in world coordinates.
struct Shape {
  //! MuJoCo's geom type (mjGEOM_BOX, mjGEOM_SPHERE, mjGEOM_CAPSULE, mjGEOM_CYLINDER,
  //! mjGEOM_ELLIPSOID, mjGEOM_MESH, mjGEOM_PLANE); a height field is its bounding box (kind box).
  int type = mjGEOM_BOX;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();        //!< the geom frame's origin [m]
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  //!< the geom frame's axes (columns)
  Eigen::Vector3d size = Eigen::Vector3d::Zero();          //!< MuJoCo's geom size [m]
  //! A mesh's vertices in the geom frame (MuJoCo's, single precision), 3 per vertex, and which of
  //! them to use (the convex hull's when MuJoCo computed it; all when `ids` is null).
  const float* vertices = nullptr;
  const int* ids = nullptr;
  int count = 0;
  //! The hull's edges (MuJoCo's mesh_graph, when it computed the hull): the neighbours of hull
  //! vertex k are edges[edge_adr[k]], edges[edge_adr[k] + 1], ... up to a -1. The support then
  //! climbs from vertex to better neighbour, which on a convex polytope ends at the maximum.
  const int* edge_adr = nullptr;
  const int* edges = nullptr;
  //! The box that holds the shape (the shape itself for a box; infinite for a plane) [m].
  Box box;
  //! The radius of a ball about box.center that holds the shape [m] (infinite for a plane).
  double radius = 0.0;

  bool plane() const { return type == mjGEOM_PLANE; }
  //! True when the shape is exactly its box (box.hpp's box routines are then exact for it).
  bool is_box() const { return type == mjGEOM_BOX; }
  //! The point of the shape farthest along n (n need not be unit; not for planes) [m]. For a mesh,
  //! `hint` (optional) is the hull vertex to climb from, and is set to the one it ends at: a caller
  //! asking in nearby directions one after the other starts near the answer.
  Eigen::Vector3d support_point(const Eigen::Vector3d& n, int* hint = nullptr) const;
  //! max over the shape's points x of n . x (for a plane: +infinity unless n is along the normal).
  double support(const Eigen::Vector3d& n, int* hint = nullptr) const;
};

//! A box as a shape.
Shape box_shape(const Box& box);

//! A mesh geom's hull in its own frame: the box of its vertices and the radius of a ball about that
//! box's centre that holds them [m]. Constant for a model: callers that build a moving mesh's shape
//! often (the certificate, the room sweep) compute it once.
struct HullExtent {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d half_size = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

//! A mesh geom's HullExtent.
HullExtent hull_extent(const mjModel& m, int geom);

//! The shape of a geom after kinematics (d.geom_xpos, d.geom_xmat), as MuJoCo's collision sees it.
//! For a mesh, `extent` (its hull_extent, when given) saves the pass over the hull's vertices that
//! its box and radius need; the box is then the one in the geom's frame.
Shape geom_shape(const mjModel& m, const mjData& d, int geom, const HullExtent* extent = nullptr);

//! The result of convex_distance.
struct ShapeDistance {
  //! A lower bound of the Euclidean distance [m]: the gap of a separating plane (0 when the shapes
  //! touch or overlap, within the tolerance).
  double lower = 0.0;
  //! An upper bound: the length of the closest point of the Minkowski difference found [m].
  double upper = 0.0;
  //! The unit direction from a to b across the separating plane (meaningful when lower > 0).
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();
};

//! Distance of two convex shapes (no planes) by the Gilbert-Johnson-Keerthi iteration on their
//! support functions, until the bounds agree within `tolerance` [m] (or 64 iterations). The lower
//! bound is a proof whatever the iteration count: every point of b lies beyond the plane through
//! a's support point normal to `axis`, `lower` further on.
//! `hint_a`, `hint_b` (optional): the mesh supports' climbing hints (Shape::support_point).
ShapeDistance convex_distance(const Shape& a, const Shape& b, double tolerance = 1e-9, int* hint_a = nullptr,
                              int* hint_b = nullptr);

//! Euclidean distance of two geom shapes [m], a lower bound (exact for two boxes and, within 1e-9 m,
//! for others): box.hpp's box_distance for two boxes, the signed gap above a plane (0 when a point
//! is below it), GJK's lower bound otherwise.
double shape_distance(const Shape& a, const Shape& b);

//! The world-aligned box around a shape [m] (tight: its support in the six axis directions).
Eigen::AlignedBox3d aligned(const Shape& s);

}  // namespace leeway
