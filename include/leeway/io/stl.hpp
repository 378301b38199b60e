#pragma once
//! @file stl.hpp
//! STL triangle meshes (binary and ASCII), read for the collision geometry of imported robots.

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

namespace leeway {

//! The triangles of an STL file, in the file's own units and frame.
struct StlMesh {
  std::vector<Eigen::Vector3d> vertices;  //!< three per triangle, in file order
  bool binary = false;                    //!< read as binary STL (else ASCII)
  int triangles() const { return static_cast<int>(vertices.size() / 3); }
};

//! Reads a binary or ASCII STL file. A file is binary when its size is 84 + 50 x (its triangle
//! count), else ASCII when it starts with `solid`.
//! @throws InputError naming the file (and the triangle or line) when it cannot be opened, is not
//! STL, is truncated, holds no triangle or a coordinate that is not a finite number.
StlMesh read_stl(const std::string& path);

//! The axis-aligned bounding box of points, as {minimum, maximum}.
//! @throws InputError when there are no points.
std::pair<Eigen::Vector3d, Eigen::Vector3d> bounding_box(const std::vector<Eigen::Vector3d>& points);

}  // namespace leeway
