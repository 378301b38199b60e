#pragma once
// `leeway import-urdf`: a URDF robot as an MJCF robot fragment in leeway's conventions.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace leeway::cli {

//! The command line of `leeway import-urdf`.
struct ImportUrdfArgs {
  std::string urdf;                        //!< the URDF file
  std::string out;                         //!< the MJCF fragment to write
  std::vector<std::string> package_paths;  //!< folders searched for package:// before ROS_PACKAGE_PATH
  std::string tool = "tool0";              //!< the tool link
  std::string base_link;                   //!< the base link (default: the URDF's root)
  bool continuous_full_turn = false;       //!< continuous joints as -2 pi .. 2 pi rad
  std::string srdf;                        //!< an SRDF whose disabled collision pairs are excluded too
  std::string link_geometry = "mesh";      //!< "mesh" (the URDF's shapes, meshes as mesh geoms) or "box"
};

//! Adds the `import-urdf` subcommand, parsing into `args`; returns it.
CLI::App* add_import_urdf(CLI::App& app, ImportUrdfArgs& args);

//! Runs `leeway import-urdf`: writes the fragment, its excludes fragment and (mesh geoms) the mesh
//! copies in STEM_meshes beside it (each atomically, the meshes first), prints a summary and every
//! pair excluded with the reason, returns kExitOk.
//! @throws InputError on a bad URDF or mesh; nothing is written then.
int run_import_urdf(const ImportUrdfArgs& args);

}  // namespace leeway::cli
