#pragma once
// `leeway sample`: a bounds file as stages every dt for a controller (CSV, JSON, .npz), or as Drake
// HPolyhedron regions (docs/cli.md, "Contract for a controller").

#include <CLI/CLI.hpp>
#include <limits>
#include <string>

#include "cli/common.hpp"

namespace leeway::cli {

//! The command line of `leeway sample`.
struct SampleArgs {
  std::string bounds;  //!< bounds file written by leeway bounds --out
  std::string cell;    //!< --cell: check the file against this cell (and time a format-1 file)
  double dt = std::numeric_limits<double>::quiet_NaN();  //!< --dt [s]; NaN: not given
  std::string out;              //!< --out: .csv, .json, .npz, or .yaml with --format drake-yaml
  std::string format = "auto";  //!< --format: auto (by --out's ending), csv, json, npz, drake-yaml
  bool segments = false;        //!< --segments: drake-yaml also gets each segment's region
};

//! Adds the `sample` subcommand, parsing into `args`; returns it.
CLI::App* add_sample(CLI::App& app, SampleArgs& args);

//! Runs `leeway sample`: writes --out and returns kExitOk.
//! @throws InputError on a bad bounds file, cell, step or output.
int run_sample(const SampleArgs& args);

}  // namespace leeway::cli
