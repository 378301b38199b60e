#pragma once
// `leeway ik`: inverse kinematics to a goal site or position, tool pointing down.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "cli/common.hpp"
#include "leeway/core/kinematics.hpp"

namespace leeway::cli {

//! The command line of `leeway ik`.
struct IkArgs {
  std::string cell;                 //!< MJCF file of the workcell
  std::string site;                 //!< goal site (or xyz)
  std::vector<double> xyz;          //!< goal position [m] (or site)
  std::string seed_q, seed_key;     //!< the seed configuration (default: the first keyframe)
  std::string lock;                 //!< comma-separated joints kept at the seed value
  bool free_orientation = false;    //!< position only
  bool json = false;                //!< JSON instead of text
  IkOptions options;                //!< --restarts and --seed
  std::string tool = kDefaultTool;  //!< the robot's tool site
};

//! Adds the `ik` subcommand, parsing into `args`; returns it.
CLI::App* add_ik(CLI::App& app, IkArgs& args);

//! Runs `leeway ik`: kExitOk with a solution, kExitFindings without.
//! @throws InputError on a bad cell, goal, seed or --lock.
int run_ik(const IkArgs& args);

}  // namespace leeway::cli
