#pragma once
// `leeway fk`: forward kinematics, the tool site's pose at a configuration.

#include <CLI/CLI.hpp>
#include <string>

#include "cli/common.hpp"

namespace leeway::cli {

//! The command line of `leeway fk`.
struct FkArgs {
  std::string cell;                 //!< MJCF file of the workcell
  std::string q;                    //!< joint values, robot joint order [rad or m]
  std::string key;                  //!< a keyframe instead of q
  bool json = false;                //!< JSON instead of text
  std::string tool = kDefaultTool;  //!< the robot's tool site
};

//! Adds the `fk` subcommand, parsing into `args`; returns it.
CLI::App* add_fk(CLI::App& app, FkArgs& args);

//! Runs `leeway fk`: prints the pose and returns kExitOk.
//! @throws InputError on a bad cell or configuration.
int run_fk(const FkArgs& args);

}  // namespace leeway::cli
