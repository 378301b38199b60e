#pragma once
// `leeway bounds`: joint bounds along a path (thesis chapter 3).

#include <CLI/CLI.hpp>
#include <string>

#include "cli/common.hpp"
#include "leeway/path/planner.hpp"

namespace leeway::cli {

//! The command line of `leeway bounds`.
struct BoundsArgs {
  std::string cell;                  //!< MJCF file of the workcell
  std::string checker = "midphase";  //!< --checker
  std::string from, to;              //!< path ends: keyframe, site:NAME or xyz:X,Y,Z
  std::string path;                  //!< a path file instead of from/to
  std::string ik_seed;               //!< keyframe seeding the IK of gripper goals
  std::string params;                //!< parameter file (JSON)
  std::string preset = "leeway";     //!< parameter set
  std::string safety;                //!< safety mode; empty: the preset's
  JointBoundsOptions joints;         //!< --bisect, --half-width
  std::string out;                   //!< bounds file to write (JSON); empty: none
  std::string export_mjcf;           //!< the cell with its volume as MJCF; empty: none
  std::string export_mjb;            //!< the same compiled, as MJB; empty: none
  int max_cells = 0;                 //!< MAX_cells, used when max_cells_given
  bool max_cells_given = false;      //!< --max-cells was on the command line (set by the parser)
  int waypoints = 2;                 //!< waypoints of the joint-linear path
  bool waypoints_given = false;      //!< --waypoints was on the command line (set by the parser)
  int threads = default_threads();   //!< worker threads
  bool json = false;                 //!< print the bounds file instead of text
  bool no_plan = false;              //!< exit 1 on a colliding straight path instead of planning
  std::string room;                  //!< measure the room: "on", "off"; empty: the preset's default
  PlanOptions plan;                  //!< planner seed and time limit
};

//! Adds the `bounds` subcommand, parsing into `args`; returns it.
CLI::App* add_bounds(CLI::App& app, BoundsArgs& args);

//! Runs `leeway bounds`: kExitOk with bounds, kExitFindings on a colliding path, an unreachable
//! goal or no path (nothing written).
//! @throws InputError on a bad cell, path, parameter or flag.
int run_bounds(const BoundsArgs& args);

}  // namespace leeway::cli
