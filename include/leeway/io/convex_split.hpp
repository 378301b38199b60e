#pragma once
//! @file convex_split.hpp
//! A triangle mesh split into convex pieces within a tolerance, for `leeway import-mesh`: MuJoCo
//! collides a mesh geom as its convex hull, so a concave part becomes several hulls.
//! docs/mjcf-conventions.md ("CAD meshes") gives the method and why the pieces cover the part.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace leeway {

//! Settings of convex_split (lengths in metres).
struct ConvexSplitOptions {
  double tolerance = 0.01;  //!< [m] the largest excess of a piece's hull over the part allowed
  int max_pieces = 32;      //!< the split stops at this many pieces, reached or not
  int samples = 512;        //!< points sampled per piece (half on its hull's surface, half inside)
  std::uint64_t seed = 1;   //!< the sampling's seed (the same seed gives the same pieces)
};

//! One convex piece: the convex hull of its vertices.
struct ConvexPiece {
  std::vector<Eigen::Vector3d> vertices;  //!< the hull's vertices [m]
  Eigen::Vector3d lo, hi;                 //!< its axis-aligned bounding box [m]
  double volume = 0;                      //!< the hull's volume [m^3]
  double excess = 0;       //!< [m] the largest distance to the part (its solid when closed) over the samples
  bool thickened = false;  //!< the hull was thinner than tolerance / 10 and was thickened to it
};

//! The result of convex_split.
struct ConvexSplit {
  std::vector<ConvexPiece> pieces;
  double worst_excess = 0;  //!< [m] the largest piece excess
  bool reached = true;      //!< every piece is within the tolerance
  //! every edge of the mesh, vertices within 1e-6 of its box's diagonal welded, is shared by an even
  //! number of triangles
  bool closed = true;
  int triangles = 0;  //!< the mesh's triangles
};

//! Splits the mesh `triangles` (three vertices per triangle, in metres) into convex pieces by
//! recursive plane cuts until every piece's hull is within `options.tolerance` of the part or
//! `options.max_pieces` is reached. The pieces' hulls cover every triangle and, for a closed mesh,
//! the solid it bounds.
//! @throws InputError when the mesh has no triangle of non-zero extent or a coordinate that is not
//! finite, or the options are out of range (tolerance not above 0, max_pieces below 1).
ConvexSplit convex_split(const std::vector<Eigen::Vector3d>& triangles, const ConvexSplitOptions& options);

}  // namespace leeway
