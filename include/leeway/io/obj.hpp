#pragma once
//! @file obj.hpp
//! Wavefront OBJ meshes (vertices and faces only), read for `leeway import-mesh`.

#include <Eigen/Core>
#include <string>
#include <vector>

namespace leeway {

//! Reads the triangles of a Wavefront OBJ file, three vertices per triangle, in the file's own units
//! and frame. Reads `v x y z [w]` lines (w ignored) and `f` lines of three or more corners, each
//! `i`, `i/j`, `i/j/k` or `i//k` (only the vertex index i is used; a negative i counts back from the
//! last vertex read); a polygon is fan-triangulated from its first corner. Other lines (`vt`, `vn`,
//! `g`, `o`, `s`, `usemtl`, `mtllib`, `l`, comments) are ignored.
//! @throws InputError naming the file and line when it cannot be opened, a `v` line has fewer than
//! three numbers or one that is not finite, an `f` line has fewer than three corners, a corner that
//! is not an index, the index 0 or one outside the vertices read so far, or when the file holds no
//! face.
std::vector<Eigen::Vector3d> read_obj(const std::string& path);

}  // namespace leeway
