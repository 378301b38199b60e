#pragma once
// `leeway params`: the default parameters as JSON, or a cell's.

#include <CLI/CLI.hpp>
#include <string>

#include "cli/common.hpp"

namespace leeway::cli {

//! The command line of `leeway params`.
struct ParamsArgs {
  std::string cell;               //!< apply this cell's own defaults too; empty: none
  std::string preset = "leeway";  //!< parameter set to print
};

//! Adds the `params` subcommand, parsing into `args`; returns it.
CLI::App* add_params(CLI::App& app, ParamsArgs& args);

//! Runs `leeway params`: prints the parameters and returns kExitOk.
//! @throws InputError on an unknown preset or a bad cell.
int run_params(const ParamsArgs& args);

}  // namespace leeway::cli
