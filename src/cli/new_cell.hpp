#pragma once
// `leeway new-cell`: a minimal workcell around a robot fragment, ready for obstacles.

#include <CLI/CLI.hpp>
#include <string>

namespace leeway::cli {

//! The command line of `leeway new-cell`.
struct NewCellArgs {
  std::string robot;     //!< the robot fragment (e.g. from import-urdf)
  std::string out;       //!< the cell to write
  std::string name;      //!< the cell's model name (default: the file name without .xml)
  std::string excludes;  //!< the robot's excludes fragment (default: ROBOT_excludes.xml beside it, if any)
};

//! Adds the `new-cell` subcommand, parsing into `args`; returns it.
CLI::App* add_new_cell(CLI::App& app, NewCellArgs& args);

//! Runs `leeway new-cell`: writes the cell once it passes leeway's check, returns kExitOk.
//! @throws InputError on a missing or unusable robot file; nothing is written then.
int run_new_cell(const NewCellArgs& args);

}  // namespace leeway::cli
