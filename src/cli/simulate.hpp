#pragma once
// `leeway simulate`: the closed loop on a cell and its bounds: MuJoCo's physics, a simulated
// co-worker pushing the tool, an admittance law and a controller that keeps the robot inside the
// bounds (docs/simulate.md).

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "cli/common.hpp"
#include "leeway/core/simulate.hpp"

namespace leeway::cli {

//! The command line of `leeway simulate`.
struct SimulateArgs {
  std::string cell;                             //!< MJCF file of the workcell
  std::string bounds;                           //!< --bounds: bounds file written by leeway bounds --out
  std::vector<std::string> human = {"random"};  //!< --human: random | push-toward NAME | file F | none
  std::string controller = "mpc";               //!< --controller: mpc or projection
  SimulateOptions options;                      //!< seed, speed, amplitude, bandwidth, times
  std::string tool = kDefaultTool;              //!< --tool
  bool json = false;                            //!< --json: print the report as JSON
  std::string out;                              //!< --out: write the report (JSON) here
  std::string video;                            //!< --video: an MP4 rendered offscreen, via ffmpeg
  std::string size = "640x480";                 //!< --size WxH of the video
};

//! Adds the `simulate` subcommand, parsing into `args`; returns it.
CLI::App* add_simulate(CLI::App& app, SimulateArgs& args);

//! Runs `leeway simulate`: kExitOk when the run had no contact and never left the bounds,
//! kExitFindings when it had or did.
//! @throws InputError on a bad cell, bounds file, push file, option or output path.
int run_simulate(const SimulateArgs& args);

}  // namespace leeway::cli
