#include "cli/new_cell.hpp"

#include <filesystem>
#include <iostream>

#include "cli/common.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/io/new_cell.hpp"

namespace leeway::cli {

CLI::App* add_new_cell(CLI::App& app, NewCellArgs& args) {
  CLI::App* sub = app.add_subcommand(
      "new-cell",
      "Write a minimal cell around a robot fragment (floor, robot, home keyframe) that passes check");
  sub->add_option("--robot", args.robot, "The robot's MJCF fragment, e.g. mjcf/robots/NAME.xml")->required();
  sub->add_option("--out", args.out, "The cell to write, e.g. mjcf/workcells/NAME.xml")
      ->check(file_name_check())
      ->required();
  sub->add_option("--name", args.name,
                  "The cell's model name (default: the file name without its extension)");
  sub->add_option("--excludes", args.excludes,
                  "The robot's self-collision excludes fragment, included at the cell's top level\n"
                  "(default: ROBOT_excludes.xml beside the robot file, when it exists)");
  return sub;
}

int run_new_cell(const NewCellArgs& args) {
  // The files the robot includes and its meshes are checked by write_new_cell, resolved from the
  // cell's folder as MuJoCo will.
  std::vector<std::string> read = {args.robot};
  if (!args.excludes.empty()) read.push_back(args.excludes);
  require_outputs({{args.out, "--out", {}}}, read);
  const std::string name = args.name.empty() ? std::filesystem::path(args.out).stem().string() : args.name;
  const NewCell cell = write_new_cell(args.robot, args.out, name, args.excludes);
  std::cout << "wrote " << args.out << ": includes " << cell.robot_include
            << (cell.excludes_include.empty() ? "" : " and " + cell.excludes_include) << ", " << cell.joints
            << " joints, keyframe home = [" << cell.home << "] (rad or m), leeway_reach_radius "
            << cell.reach_radius << " m; leeway check: ok\n";
  std::cout << "self-collision: " << cell.self_pairs << " robot geom pairs checked, "
            << cell.included_excludes + static_cast<int>(cell.cell_excludes.size()) << " excluded ("
            << cell.included_excludes << " by "
            << (cell.excludes_include.empty() ? std::string("an excludes fragment: none")
                                              : cell.excludes_include)
            << ", " << cell.cell_excludes.size() << " in the cell)\n";
  for (const auto& e : cell.cell_excludes)
    std::cout << "excluded in the cell: '" << e.geom1 << "' and '" << e.geom2 << "': " << e.reason << "\n";
  return kExitOk;
}

}  // namespace leeway::cli
