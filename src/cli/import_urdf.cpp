#include "cli/import_urdf.hpp"

#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "cli/common.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/io/urdf_import.hpp"

namespace leeway::cli {

CLI::App* add_import_urdf(CLI::App& app, ImportUrdfArgs& args) {
  CLI::App* sub = app.add_subcommand(
      "import-urdf",
      "Import a URDF robot as an MJCF robot fragment in leeway's conventions (docs/robots.md)");
  sub->add_option("urdf", args.urdf, "The URDF file (run xacro first for .xacro files)")->required();
  sub->add_option("--out", args.out, "The MJCF fragment to write, e.g. mjcf/robots/NAME.xml")
      ->check(file_name_check())
      ->required();
  sub->add_option("--package-path", args.package_paths,
                  "A folder holding ROS packages, for package:// URIs (repeatable; searched before\n"
                  "ROS_PACKAGE_PATH)");
  sub->add_option("--tool", args.tool, "The tool (flange) link: its frame becomes the site tool0")
      ->capture_default_str();
  sub->add_option("--base-link", args.base_link,
                  "The robot's fixed base link (default: the URDF's root link)");
  sub->add_flag("--continuous-full-turn", args.continuous_full_turn,
                "Import continuous joints with the range -2 pi .. 2 pi rad (default: refuse them)");
  sub->add_option("--srdf", args.srdf,
                  "An SRDF file (MoveIt): its <disable_collisions> link pairs are excluded from\n"
                  "self-collision too");
  sub->add_option("--link-geometry", args.link_geometry,
                  "What each <collision> element becomes: mesh (its own shape: a box, cylinder or sphere\n"
                  "as such, an STL mesh as a mesh geom, collided as its convex hull, on a binary STL copy\n"
                  "in STEM_meshes/ beside --out) or box (one box that contains it)")
      ->check(CLI::IsMember({"mesh", "box"}))
      ->capture_default_str();
  return sub;
}

namespace {

// The mesh copies, into `folder` (created when missing), each checked against the inputs and the
// other outputs first; a folder created here is removed again when a check fails.
void write_mesh_copies(const UrdfImport& robot, const std::string& folder, std::vector<OutputFile> outputs,
                       const std::vector<std::string>& read) {
  if (robot.meshes.empty()) return;
  namespace fs = std::filesystem;
  const fs::path dir(folder);
  std::error_code ec;
  const bool created = fs::create_directory(dir, ec);
  if (ec)
    throw InputError("--out " + folder + ": cannot create the folder of the mesh copies: " + ec.message());
  try {
    for (const UrdfMeshFile& m : robot.meshes)
      outputs.push_back({(dir / fs::path(m.file).filename()).string(), "--out (a mesh copy)", {".stl"}});
    require_outputs(outputs, read);
  } catch (...) {
    if (created) fs::remove(dir, ec);
    throw;
  }
  for (const UrdfMeshFile& m : robot.meshes)
    write_file_atomic((dir / fs::path(m.file).filename()).string(), m.bytes);
}

}  // namespace

int run_import_urdf(const ImportUrdfArgs& args) {
  // The excludes fragment goes beside the robot fragment, where new-cell looks for it.
  const std::string excludes = excludes_path(args.out);
  std::vector<std::string> read = {args.urdf};
  if (!args.srdf.empty()) read.push_back(args.srdf);
  const std::vector<OutputFile> outputs = {{args.out, "--out", {}},
                                           {excludes, "--out (its excludes fragment)", {}}};
  require_outputs(outputs, read);
  UrdfImportOptions options;
  options.package_paths = args.package_paths;
  if (const char* env = std::getenv("ROS_PACKAGE_PATH")) options.ros_package_path = env;
  options.tool_link = args.tool;
  options.base_link = args.base_link;
  options.continuous_full_turn = args.continuous_full_turn;
  options.srdf = args.srdf;
  options.link_geometry = parse_link_geometry(args.link_geometry);
  const std::string mesh_folder = mesh_folder_path(args.out);
  options.mesh_folder = std::filesystem::path(mesh_folder).filename().string();
  UrdfImport robot;
  try {
    robot = import_urdf(args.urdf, options);
  } catch (const UrdfOptionError& e) {
    // The library names the data; name the option that changes it.
    const std::string& f = e.field();
    const std::string flag = f == "continuous_full_turn" ? "--continuous-full-turn"
                             : f == "tool_link"          ? "--tool LINK"
                             : f == "link_geometry"      ? "--link-geometry box"
                                                         : "--base-link LINK";
    throw InputError(std::string(e.what()) + " (see " + flag + ")");
  }
  // The meshes the URDF names are known once it is read: the outputs may replace none of them.
  read.insert(read.end(), robot.inputs.begin(), robot.inputs.end());
  require_outputs(outputs, read);
  write_mesh_copies(robot, mesh_folder, outputs, read);
  write_file_atomic(excludes, robot.excludes_mjcf);
  write_file_atomic(args.out, robot.mjcf);
  std::cout << "wrote " << args.out << ": robot '" << robot.robot_name << "', " << robot.joints.size()
            << " joints (";
  for (size_t i = 0; i < robot.joints.size(); ++i) std::cout << (i ? ", " : "") << robot.joints[i];
  if (options.link_geometry == LinkGeometry::kBox)
    std::cout << "), " << robot.boxes << " collision boxes\n";
  else
    std::cout << "), " << robot.boxes << " collision geoms, " << robot.meshes.size() << " of them meshes\n";
  if (!robot.meshes.empty())
    std::cout << "wrote " << robot.meshes.size() << " binary STL mesh copies in " << mesh_folder
              << " (a cell in another folder needs <compiler meshdir> naming the robot's folder; new-cell "
                 "writes it)\n";
  std::cout << "wrote " << excludes << ": " << robot.excludes.size()
            << (options.link_geometry == LinkGeometry::kBox ? " box" : " geom")
            << " pair(s) excluded from self-collision, " << robot.self_pairs
            << " checked (include it at the top level of the cell; new-cell does)\n";
  for (const auto& e : robot.excludes)
    std::cout << "excluded: '" << e.geom1 << "' and '" << e.geom2 << "': " << e.reason << "\n";
  for (const auto& n : robot.notes) std::cout << "note: " << n << "\n";
  return kExitOk;
}

}  // namespace leeway::cli
