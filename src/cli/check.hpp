#pragma once
// `leeway check`: keyframe collisions and limits, goal obstacles, reach and overlaps of a cell.

#include <CLI/CLI.hpp>
#include <string>

#include "cli/common.hpp"
#include "leeway/core/check.hpp"

namespace leeway::cli {

//! The command line of `leeway check`.
struct CheckArgs {
  std::string cell;                 //!< MJCF file of the workcell
  bool json = false;                //!< one JSON object instead of text
  CheckOptions options;             //!< --dz (Algorithm 1's descent step) and --seed
  std::string tool = kDefaultTool;  //!< the robot's tool site
};

//! Adds the `check` subcommand, parsing into `args`; returns it.
CLI::App* add_check(CLI::App& app, CheckArgs& args);

//! Runs `leeway check`: kExitOk when clean, kExitFindings when problems were found.
//! @throws InputError when the cell cannot be used.
int run_check(const CheckArgs& args);

}  // namespace leeway::cli
