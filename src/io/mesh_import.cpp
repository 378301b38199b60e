#include "leeway/io/mesh_import.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <locale>
#include <sstream>

#include "io/mjcf_text.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/numbers.hpp"
#include "leeway/io/obj.hpp"
#include "leeway/io/stl.hpp"

namespace leeway {
namespace {

// Tolerances below this are refused: MuJoCo keeps mesh vertices as single-precision floats, and a
// piece is thickened to a tenth of the tolerance, which must stay a volume MuJoCo accepts.
constexpr double kMinTolerance = 1e-4;
constexpr int kMaxPieces = 1024;

// A coordinate with 9 significant digits (MuJoCo stores mesh vertices as floats, about 7).
std::string coordinate(double v) {
  if (std::abs(v) < 1e-12) v = 0;
  std::ostringstream os;
  os.imbue(std::locale::classic());
  os.precision(9);
  os << v;
  return os.str();
}

std::string triple(const Eigen::Vector3d& p, const char* separator = " ") {
  return coordinate(p.x()) + separator + coordinate(p.y()) + separator + coordinate(p.z());
}

bool valid_name(const std::string& name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](unsigned char c) {
    return std::isalnum(c) || c == '_' || c == '-' || c == '.';
  });
}

void check_options(const MeshImportOptions& options) {
  if (!(options.scale > 0) || !std::isfinite(options.scale))
    throw InputError("scale " + format_number(options.scale) +
                     " is not a finite number above 0 (file units to metres)");
  const double tolerance = options.split.tolerance;
  if (!std::isfinite(tolerance) || !(tolerance >= kMinTolerance))
    throw InputError("tolerance " + format_number(tolerance) + " m is not a finite number of at least " +
                     format_number(kMinTolerance) + " m");
  if (options.split.max_pieces < 1 || options.split.max_pieces > kMaxPieces)
    throw InputError("max pieces " + std::to_string(options.split.max_pieces) + " is not within 1.." +
                     std::to_string(kMaxPieces));
  if (!options.name.empty() && !valid_name(options.name))
    throw InputError("name '" + detail::xml_escape(options.name) +
                     "' has characters other than letters, digits, '_', '-' and '.'");
}

std::string header(const std::string& path, const std::string& format, const MeshImportOptions& options,
                   const ConvexSplit& split) {
  const auto& o = options.split;
  std::string text;
  text += detail::wrapped_comment(
      "leeway import-mesh: the convex pieces of a CAD part, as MuJoCo collides them (every mesh geom "
      "as its convex hull). Units: metres.",
      0);
  text += detail::wrapped_comment(
      "source: " + path + " (" + format + ", " + std::to_string(split.triangles) + " triangles" +
          (split.closed ? ", closed" : ", not closed: excess measured to its surface") + "), scale " +
          format_number(options.scale) + " (file units to metres)",
      0);
  text += detail::wrapped_comment(
      "pieces: " + std::to_string(split.pieces.size()) + " (at most " + std::to_string(o.max_pieces) +
          "), tolerance " + format_number(o.tolerance) + " m, worst excess " +
          format_number(split.worst_excess) + " m" + (split.reached ? "" : " (TOLERANCE NOT REACHED)"),
      0);
  text += detail::wrapped_comment(
      "method: recursive hull split (docs/mjcf-conventions.md, \"CAD meshes\"): the part's hull is cut by "
      "the plane along the coordinate or principal axes that minimises the two halves' hull volumes, "
      "until every piece's hull lies within the tolerance of the part, then pieces are merged while "
      "their joint hull stays within it and overlaps no other piece; excess = the largest distance "
      "from the hull's vertices and " +
          std::to_string(o.samples) + " points sampled on and in it (seed " + std::to_string(o.seed) +
          ") to the part's solid; pieces thinner than tolerance / 10 are thickened to it.",
      0);
  text += detail::wrapped_comment(
      "Include it at the top level of a cell, beside <worldbody>: <include file=\"FILE.xml\"/>; move the "
      "part with the body's pos and quat.",
      0);
  return text;
}

}  // namespace

std::vector<Eigen::Vector3d> read_mesh_file(const std::string& path, std::string& format) {
  std::string ending = std::filesystem::path(path).extension().string();
  std::transform(ending.begin(), ending.end(), ending.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ending == ".obj") {
    format = "OBJ";
    return read_obj(path);
  }
  if (ending == ".stl") {
    StlMesh mesh = read_stl(path);
    format = mesh.binary ? "binary STL" : "ASCII STL";
    return std::move(mesh.vertices);
  }
  throw InputError(path + ": not an STL or OBJ file (the name ends in '" + ending +
                   "'; expected .stl or .obj)");
}

std::string mesh_body_name(const std::string& path) {
  std::string name = std::filesystem::path(path).stem().string();
  for (char& c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) c = '_';
  return name.empty() ? "part" : name;
}

MeshImport import_mesh(const std::string& path, const MeshImportOptions& options) {
  check_options(options);
  MeshImport out;
  std::vector<Eigen::Vector3d> triangles = read_mesh_file(path, out.format);
  for (size_t i = 0; i < triangles.size(); ++i) {
    triangles[i] *= options.scale;
    if (!triangles[i].allFinite() || triangles[i].cwiseAbs().maxCoeff() > kMaxLength)
      throw InputError(path + ": triangle " + std::to_string(i / 3 + 1) + " vertex " +
                       std::to_string(i % 3 + 1) + " at " + triple(triangles[i / 3 * 3 + i % 3], " ") +
                       " m (scale " + format_number(options.scale) + ") goes beyond +-" +
                       format_number(kMaxLength) + " m");
  }
  try {
    out.split = convex_split(triangles, options.split);
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  }
  out.name = options.name.empty() ? mesh_body_name(path) : options.name;
  std::string assets, geoms;
  for (size_t k = 0; k < out.split.pieces.size(); ++k) {
    const ConvexPiece& piece = out.split.pieces[k];
    const std::string id = out.name + "_piece_" + std::to_string(k + 1);
    assets += "    <mesh name=\"" + id + "\" vertex=\"";
    for (size_t v = 0; v < piece.vertices.size(); ++v)
      assets += (v ? "\n" + std::string(26 + id.size(), ' ') : "") + triple(piece.vertices[v]);
    assets += "\"/>\n";
    geoms += detail::wrapped_comment(
        "piece " + std::to_string(k + 1) + ": box [" + triple(piece.lo) + "] .. [" + triple(piece.hi) +
            "] m, excess " + format_number(piece.excess) + " m, " + std::to_string(piece.vertices.size()) +
            " hull vertices" + (piece.thickened ? ", thickened" : ""),
        6);
    geoms += "      <geom name=\"" + id + "\" type=\"mesh\" mesh=\"" + id +
             "\" contype=\"0\" conaffinity=\"1\"/>\n";
  }
  out.mjcf = header(path, out.format, options, out.split) + "<mujoco model=\"" + out.name +
             "\">\n  <asset>\n" + assets + "  </asset>\n  <worldbody>\n    <body name=\"" + out.name +
             "\" pos=\"0 0 0\">\n" + geoms + "    </body>\n  </worldbody>\n</mujoco>\n";
  return out;
}

}  // namespace leeway
