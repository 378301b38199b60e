#pragma once
// Internal: command-line parsing, error reporting and the helpers shared by the subcommands of the
// leeway program (src/cli/*.cpp) and by leeway-tune (not part of the public API).

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <exception>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "leeway/endpoints.hpp"
#include "leeway/error.hpp"
#include "leeway/params.hpp"
#include "leeway/planner.hpp"
#include "leeway/scene.hpp"

namespace leeway::cli {

//! The tool site's name unless --tool gives another.
inline const char* const kDefaultTool = "tool0";

//! Parses argv into `app`. Returns the exit code the program should return now (0 after --help or
//! --version, kExitBadInput after a parse error, which CLI11 has reported on standard error), or
//! nothing when the program should go on.
inline std::optional<int> parse_cli(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitBadInput;
  }
  return std::nullopt;
}

//! Runs a program's `body` (returning its exit code) and turns an escaping exception into one line
//! on standard error: an InputError gives "PROGRAM: error: ..." and kExitBadInput, anything else
//! "PROGRAM: internal error (please report): ..." and kExitInternal.
template <class Body>
int run_reporting_errors(const char* program, Body&& body) {
  try {
    return body();
  } catch (const InputError& e) {
    std::cerr << program << ": error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << program << ": internal error (please report): " << e.what() << "\n";
    return kExitInternal;
  }
}

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

//! A configuration from --q or --key; `what` starts the error messages.
//! @throws InputError when both or neither are given, or --q is malformed or outside the limits.
Eigen::VectorXd configuration(const Scene& scene, const std::string& q, const std::string& key,
                              const std::string& what);

//! Parameters: the preset, then the cell's own (MJCF custom numerics), then the keys present in a
//! --params file, then --safety (flags such as --max-cells are the caller's).
//! @throws InputError on an unknown preset or safety mode or a bad parameter file.
Params load_params(const Scene& scene, const std::string& preset, const std::string& file,
                   const std::string& safety);

//! Whether a path end needs inverse kinematics (and so a planned path) rather than a keyframe.
bool is_gripper_goal(const std::string& spec);

//! Plans between two path ends (docs/planning.md). On an unreachable goal or no path, prints the
//! one-line reason and returns false: the caller exits with kExitFindings and writes nothing.
bool plan_between(const Scene& scene, const std::string& from, const std::string& to,
                  const std::string& ik_seed_key, const PlanOptions& options, PlanResult& result, Endpoint& a,
                  Endpoint& b);

//! Checks, before any work, that an output file can be written: its folder exists and is writable
//! and, when `extensions` is not empty, its name ends in one of them (".png"). `flag` names the option.
//! @throws InputError naming the flag and the path otherwise.
void require_output(const std::string& path, const std::string& flag,
                    const std::vector<std::string>& extensions = {});

//! Parses an image size "WIDTHxHEIGHT" [pixels]. @throws InputError naming `flag` and the value.
std::pair<int, int> parse_size(const std::string& text, const std::string& flag);

}  // namespace leeway::cli
