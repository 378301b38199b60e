#include "cli/import_mesh.hpp"

#include <cctype>
#include <chrono>
#include <cmath>
#include <iostream>

#include "cli/common.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/numbers.hpp"
#include "leeway/io/mesh_import.hpp"

namespace leeway::cli {

CLI::App* add_import_mesh(CLI::App& app, ImportMeshArgs& args) {
  CLI::App* sub = app.add_subcommand("import-mesh",
                                     "Import a CAD part (STL or OBJ mesh) as an MJCF fragment of convex mesh "
                                     "pieces (docs/mjcf-conventions.md)");
  sub->add_option("mesh", args.mesh, "The part: binary or ASCII STL (.stl) or Wavefront OBJ (.obj)")
      ->required();
  sub->add_option("--out", args.out, "The MJCF fragment to write (.xml), e.g. mjcf/workcells/fixture.xml")
      ->check(file_name_check())
      ->required();
  sub->add_option("--scale", args.scale, "File units to metres, e.g. 0.001 for millimetres")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--tolerance", args.tolerance,
                  "[m] the largest distance a piece's hull may reach beyond the part (at least 1e-4)")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--name", args.name, "The body's name and its pieces' prefix (default: the file's name)")
      ->check(non_empty_check("a name"));
  sub->add_option("--max-pieces", args.max_pieces, "Stop at this many pieces (1 to 1024)")
      ->capture_default_str();
  return sub;
}

int run_import_mesh(const ImportMeshArgs& args) {
  // The library names the value; the options that give them are named here.
  if (!(args.scale > 0))
    throw InputError("--scale " + format_number(args.scale) +
                     ": not a number above 0 (file units to metres, e.g. 0.001 for millimetres)");
  if (!(args.tolerance >= 1e-4))
    throw InputError("--tolerance " + format_number(args.tolerance) + " m: below the smallest, 1e-4 m");
  if (args.max_pieces < 1 || args.max_pieces > 1024)
    throw InputError("--max-pieces " + std::to_string(args.max_pieces) + ": not within 1 to 1024");
  for (const unsigned char c : args.name)
    if (!(std::isalnum(c) || c == '_' || c == '-' || c == '.'))
      throw InputError("--name '" + args.name + "': only letters, digits, '_', '-' and '.' are allowed");
  require_regular_input(args.mesh, "mesh file");
  require_outputs({{args.out, "--out", {".xml"}}}, {args.mesh});
  MeshImportOptions options;
  options.scale = args.scale;
  options.name = args.name;
  options.split.tolerance = args.tolerance;
  options.split.max_pieces = args.max_pieces;
  const auto start = std::chrono::steady_clock::now();
  const MeshImport result = import_mesh(args.mesh, options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  write_file_atomic(args.out, result.mjcf);
  const ConvexSplit& split = result.split;
  std::cout << "wrote " << args.out << ": body '" << result.name << "', " << split.pieces.size()
            << " convex mesh pieces from " << split.triangles << " triangles (" << result.format << ", "
            << (split.closed ? "closed" : "not closed: excess measured to its surface") << "), worst excess "
            << format_number(split.worst_excess) << " m (tolerance " << format_number(args.tolerance)
            << " m), " << format_number(seconds) << " s; units: metres\n";
  for (size_t k = 0; k < split.pieces.size(); ++k) {
    const ConvexPiece& p = split.pieces[k];
    std::cout << "piece " << k + 1 << ": excess " << format_number(p.excess) << " m, box ["
              << format_number(p.lo.x()) << " " << format_number(p.lo.y()) << " " << format_number(p.lo.z())
              << "] .. [" << format_number(p.hi.x()) << " " << format_number(p.hi.y()) << " "
              << format_number(p.hi.z()) << "] m" << (p.thickened ? ", thickened to tolerance / 10" : "")
              << "\n";
  }
  if (!split.reached)
    std::cerr << "leeway: warning: the tolerance was not reached within " << args.max_pieces
              << " pieces: worst excess " << format_number(split.worst_excess) << " m > "
              << format_number(args.tolerance)
              << " m (the pieces still cover the part; raise --max-pieces or --tolerance)\n";
  return kExitOk;
}

}  // namespace leeway::cli
