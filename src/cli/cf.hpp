#pragma once
// `leeway cf`: the Confidence Factor of a bounds file (thesis section 4.1).

#include <CLI/CLI.hpp>
#include <string>

#include "cli/common.hpp"
#include "leeway/core/confidence.hpp"

namespace leeway::cli {

//! The command line of `leeway cf`.
struct CfArgs {
  std::string cell;                  //!< MJCF file of the workcell
  std::string checker = "midphase";  //!< --checker
  std::string bounds;                //!< bounds file written by leeway bounds --out
  bool json = false;                 //!< JSON instead of text
  int threads = default_threads();   //!< worker threads
  CfParams params;                   //!< windows, samples, seed
};

//! Adds the `cf` subcommand, parsing into `args`; returns it.
CLI::App* add_cf(CLI::App& app, CfArgs& args);

//! Runs `leeway cf`: prints the CF and returns kExitOk.
//! @throws InputError on a bad cell, bounds file or setting.
int run_cf(const CfArgs& args);

}  // namespace leeway::cli
