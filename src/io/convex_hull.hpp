#pragma once
// Internal: the convex hull of points in 3-d through Debian's libqhull_r (the reentrant C API), for
// the convex split of `leeway import-mesh` (not part of the public API).

#include <Eigen/Core>
#include <array>
#include <vector>

namespace leeway::detail {

//! A convex hull: its vertices, its boundary as triangles and its facets' planes.
struct Hull {
  bool ok = false;  //!< qhull built a 3-d hull (false: fewer than 4 points, or all in one plane)
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<Eigen::Vector3d, 3>> triangles;  //!< the facets, triangulated
  std::vector<Eigen::Vector4d> planes;  //!< unit outward normal n and offset o: n.x + o <= 0 inside
  double volume = 0;                    //!< [m^3]
};

//! The convex hull of `points` (qhull "Qt"); qhull's messages are discarded. Not ok for flat or
//! fewer than four points.
Hull convex_hull(const std::vector<Eigen::Vector3d>& points);

}  // namespace leeway::detail
