#pragma once
// `leeway plan`: a collision-free path between two keyframes or gripper goals (docs/planning.md).

#include <CLI/CLI.hpp>
#include <string>

#include "cli/common.hpp"
#include "leeway/path/planner.hpp"

namespace leeway::cli {

//! The command line of `leeway plan`.
struct PlanArgs {
  std::string cell;                  //!< MJCF file of the workcell
  std::string checker = "midphase";  //!< --checker
  std::string from, to;              //!< path ends: keyframe, site:NAME or xyz:X,Y,Z
  std::string out;                   //!< path file to write (JSON); empty: none
  std::string ik_seed;               //!< keyframe seeding the IK of gripper goals
  bool json = false;                 //!< print the path file instead of text
  bool no_simplify = false;          //!< keep RRT-Connect's raw path
  bool no_direct = false;            //!< plan even when the joint-linear edge is free
  PlanOptions options;               //!< seed, time limit, resolutions, range, clearance
  std::string tool = kDefaultTool;   //!< the robot's tool site
};

//! Adds the `plan` subcommand, parsing into `args`; returns it.
CLI::App* add_plan(CLI::App& app, PlanArgs& args);

//! Runs `leeway plan`: kExitOk with a path, kExitFindings on an unreachable goal or no path.
//! @throws InputError on a bad cell or path end (also one in collision).
int run_plan(const PlanArgs& args);

}  // namespace leeway::cli
