#include "cli/new_cell.hpp"

#include <filesystem>
#include <iostream>

#include "cli/common.hpp"
#include "leeway/error.hpp"
#include "leeway/file_io.hpp"
#include "leeway/new_cell.hpp"

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
  return sub;
}

int run_new_cell(const NewCellArgs& args) {
  // The files the robot includes and its meshes are checked by write_new_cell, resolved from the
  // cell's folder as MuJoCo will.
  require_outputs({{args.out, "--out", {}}}, {args.robot});
  const std::string name = args.name.empty() ? std::filesystem::path(args.out).stem().string() : args.name;
  const NewCell cell = write_new_cell(args.robot, args.out, name);
  std::cout << "wrote " << args.out << ": includes " << cell.robot_include << ", " << cell.joints
            << " joints, keyframe home = [" << cell.home << "] (rad or m), leeway_reach_radius "
            << cell.reach_radius << " m; leeway check: ok\n";
  return kExitOk;
}

}  // namespace leeway::cli
