#pragma once
// `leeway plot`: each joint's bounds along the path, as SVG or PNG.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "cli/common.hpp"
#include "leeway/viz/plot.hpp"

namespace leeway::cli {

//! The command line of `leeway plot`.
struct PlotArgs {
  std::vector<std::string> inputs;  //!< one bounds file, or sweep CSV files
  std::string out;                  //!< .svg or .png file to write
  std::string size;                 //!< "WIDTHxHEIGHT" [pixels]; empty: a size for the kind of plot
  std::string thesis;               //!< sweep plots: "CELL/PATH" of the thesis table to add
  std::string x = "t";              //!< bounds plots' x axis: "t" (time [s]) or "s" (path parameter)
};

//! Adds the `plot` subcommand, parsing into `args`; returns it.
CLI::App* add_plot(CLI::App& app, PlotArgs& args);

//! Runs `leeway plot`: writes the plot and returns kExitOk.
//! @throws InputError on a bad bounds file, size or output path.
int run_plot(const PlotArgs& args);

//! Writes a sweep plot (SVG or PNG by the file's extension) for `leeway sweep --plot`.
//! @throws InputError on a bad output path.
void write_sweep_plot(const std::string& path, const std::string& cell, const std::string& from,
                      const std::string& to, const std::string& preset, const SweepSeries& leeway);

}  // namespace leeway::cli
