#pragma once
// Internal: the helpers shared by the subcommands of the leeway program (src/cli/*.cpp; not part of
// the public API). The parsing and error reporting leeway-tune shares are in cli/support.hpp.

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>

#include "cli/support.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/scene.hpp"
#include "leeway/path/endpoints.hpp"
#include "leeway/path/nominal_path.hpp"
#include "leeway/path/planner.hpp"

namespace leeway::cli {

//! The tool site's name unless --tool gives another.
inline const char* const kDefaultTool = "tool0";

//! Scene options with the given tool site and collision checker ("midphase" or "mujoco").
//! @throws InputError on an unknown checker.
SceneOptions scene_options(const std::string& tool, const std::string& checker = "midphase");

//! Adds --checker (the collision checker) to a subcommand.
void add_checker_option(CLI::App* sub, std::string& checker);

//! A vector as a JSON array.
nlohmann::json to_array(const Eigen::VectorXd& v);

//! One worker per hardware thread (at least one): the default of --threads.
int default_threads();

//! Adds --tool (the robot's tool site) to a subcommand.
void add_tool_option(CLI::App* sub, std::string& tool);

//! Adds --preset and --safety to a subcommand that computes bounds.
void add_preset_options(CLI::App* sub, std::string& preset, std::string& safety);

//! --bisect, --half-width, --grow, --max-half-width and --shape as given (empty: not given).
struct JointBoundsOptions {
  std::string bisect;          //!< joint names, comma-separated: 'bounds.bisect'
  std::string half_width;      //!< NAME=VALUE pairs, comma-separated: 'bounds.half_width'
  std::string grow;            //!< all, none or joint names, comma-separated: 'safety.grow'
  std::string max_half_width;  //!< NAME=VALUE pairs, comma-separated: 'safety.max_half_width'
  std::string shape;           //!< greedy or lever: 'safety.shape'
};

//! Adds --bisect, --half-width, --grow, --max-half-width and --shape to a subcommand that computes
//! bounds.
void add_joint_bounds_options(CLI::App* sub, JointBoundsOptions& options);

//! Sets 'bounds.bisect', 'bounds.half_width', 'safety.grow', 'safety.max_half_width' and
//! 'safety.shape' of `p` from
//! the options given (after the preset, the
//! cell's and the file's parameters) and checks the result against `scene` (validate_for_scene).
//! @throws InputError naming the flag, the joint and the value.
void apply_joint_bounds_options(const Scene& scene, const JointBoundsOptions& options, Params& p);

//! A configuration from --q or --key; `what` starts the error messages.
//! @throws InputError when both or neither are given, or --q is malformed or outside the limits.
Eigen::VectorXd configuration(const Scene& scene, const std::string& q, const std::string& key,
                              const std::string& what);

//! Parameters: the preset, then the cell's own (MJCF custom numerics), then the keys present in a
//! --params file, then --safety (flags such as --max-cells are the caller's).
//! @throws InputError on an unknown preset or safety mode or a bad parameter file.
Params load_params(const Scene& scene, const std::string& preset, const std::string& file,
                   const std::string& safety);

//! True for a path; on a refusal prints "leeway: <kind>: <why>; nothing written" and returns false:
//! the caller exits with kExitFindings and writes nothing.
bool report_refusal(const NominalPath& path);

//! Plans between two path ends (docs/planning.md). On an unreachable goal or no path, prints the
//! one-line reason and returns false: the caller exits with kExitFindings and writes nothing.
bool plan_between(const Scene& scene, const std::string& from, const std::string& to,
                  const std::string& ik_seed_key, const PlanOptions& options, PlanResult& result, Endpoint& a,
                  Endpoint& b);

//! Parses an image size "WIDTHxHEIGHT" [pixels]. @throws InputError naming `flag` and the value.
std::pair<int, int> parse_size(const std::string& text, const std::string& flag);

}  // namespace leeway::cli
