#pragma once
// `leeway import-mesh`: a CAD part (STL or OBJ) as an MJCF fragment of convex mesh pieces.

#include <CLI/CLI.hpp>
#include <string>

namespace leeway::cli {

//! The command line of `leeway import-mesh`.
struct ImportMeshArgs {
  std::string mesh;         //!< the STL or OBJ file
  std::string out;          //!< the MJCF fragment to write
  double scale = 1;         //!< file units to metres
  double tolerance = 0.01;  //!< [m]
  std::string name;         //!< the body's name (default: the mesh file's name)
  int max_pieces = 32;
};

//! Adds the `import-mesh` subcommand, parsing into `args`; returns it.
CLI::App* add_import_mesh(CLI::App& app, ImportMeshArgs& args);

//! Runs `leeway import-mesh`: writes the fragment (atomically), prints a summary and a line per
//! piece, and a warning line when a piece is beyond the tolerance; returns kExitOk.
//! @throws InputError on a bad mesh or option; nothing is written then.
int run_import_mesh(const ImportMeshArgs& args);

}  // namespace leeway::cli
