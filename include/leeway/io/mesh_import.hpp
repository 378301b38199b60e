#pragma once
//! @file mesh_import.hpp
//! A CAD part (STL or OBJ mesh) as an MJCF fragment of convex mesh pieces: `leeway import-mesh`.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "leeway/io/convex_split.hpp"

namespace leeway {

//! Settings of import_mesh.
struct MeshImportOptions {
  double scale = 1;          //!< file units to metres (0.001 for millimetres)
  std::string name;          //!< the body's name and its pieces' prefix; empty: from the file name
  ConvexSplitOptions split;  //!< tolerance [m], piece cap, samples
};

//! The fragment and what it holds.
struct MeshImport {
  std::string mjcf;    //!< the `<mujoco>` fragment: meshes in `<asset>`, one body in `<worldbody>`
  std::string name;    //!< the body's name
  std::string format;  //!< "binary STL", "ASCII STL" or "OBJ"
  ConvexSplit split;   //!< the pieces [m]
};

//! The triangles of an STL (binary or ASCII) or Wavefront OBJ file, three vertices per triangle, in
//! the file's units; the format is the file name's ending (.stl or .obj, any case). Sets `format`.
//! @throws InputError naming the file when its name ends otherwise or reading fails (read_stl,
//! read_obj).
std::vector<Eigen::Vector3d> read_mesh_file(const std::string& path, std::string& format);

//! The default body name for a mesh file: its name without folder and ending, every character but
//! letters, digits, '_', '-' and '.' replaced by '_' ("part" for none).
std::string mesh_body_name(const std::string& path);

//! Reads the mesh file, scales it to metres, splits it into convex pieces (convex_split) and writes
//! the fragment: a header comment (source, scale, tolerance, pieces, worst excess, method), one
//! `<mesh name="NAME_piece_K" vertex="...">` per piece (its hull's vertices) and a body NAME with one
//! geom `NAME_piece_K` (type mesh, contype 0, conaffinity 1) per piece, each with a comment (its
//! bounding box and excess).
//! @throws InputError naming the file, element and value: the file (read_mesh_file), a scale that
//! is not a finite number above 0, a scaled coordinate beyond +-kMaxLength m, a name with other
//! characters than letters, digits, '_', '-' and '.', a tolerance that is not finite or is below
//! 1e-4 m, a piece cap out of 1..1024.
MeshImport import_mesh(const std::string& path, const MeshImportOptions& options);

}  // namespace leeway
