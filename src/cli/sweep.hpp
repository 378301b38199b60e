#pragma once
// `leeway sweep`: the thesis's table, boxes, time and CF for each MAX_cells value.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "cli/common.hpp"
#include "leeway/core/confidence.hpp"

namespace leeway::cli {

//! The thesis's 20 MAX_cells values (section 4.1), comma-separated: the default of --max-cells.
extern const char* const kThesisCells;

//! The command line of `leeway sweep`.
struct SweepArgs {
  std::string cell;                      //!< MJCF file of the workcell
  std::string checker = "midphase";      //!< --checker
  std::string from, to;                  //!< keyframes the path starts and ends at
  int waypoints = 2;                     //!< waypoints of the joint-linear path
  bool no_plan = false;                  //!< refuse a colliding straight path instead of planning around it
  std::string max_cells = kThesisCells;  //!< comma-separated MAX_cells values
  std::string params;                    //!< parameter file (JSON)
  std::string preset = "leeway";         //!< parameter set
  std::string safety;                    //!< safety mode; empty: the preset's
  JointBoundsOptions joints;             //!< --bisect, --half-width
  std::string csv;                       //!< CSV file to write too; empty: none
  std::string plot;                      //!< sweep plot to write (.svg or .png); empty: none
  int threads = default_threads();       //!< worker threads
  CfParams cf;                           //!< CF windows, samples, seed (those given on the command line)
  bool windows_given = false, samples_given = false, seed_given = false;  //!< set by the parser
};

//! Parses --max-cells' comma-separated list.
//! @throws InputError on an empty list or a value that is not a whole number from 1 to 1000000.
std::vector<int> parse_cells_list(const std::string& text);

//! Adds the `sweep` subcommand, parsing into `args`; returns it.
CLI::App* add_sweep(CLI::App& app, SweepArgs& args);

//! Runs `leeway sweep`: prints the Markdown table; kExitFindings when the straight path collides.
//! @throws InputError on a bad cell, keyframe, parameter or flag.
int run_sweep(const SweepArgs& args);

}  // namespace leeway::cli
