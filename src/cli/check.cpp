#include "cli/check.hpp"

#include <iostream>

namespace leeway::cli {

CLI::App* add_check(CLI::App& app, CheckArgs& args) {
  CLI::App* sub = app.add_subcommand(
      "check",
      "Check an MJCF cell: keyframe collisions and limits, goal obstacles, reach, overlaps.\n"
      "Exit 0 clean, 1 problems found, 2 the file cannot be used.");
  sub->add_option("cell", args.cell, "MJCF file of the workcell")->required();
  sub->add_flag("--json", args.json, "Print one JSON object instead of text");
  sub->add_option("--dz", args.options.goal_dz, "Algorithm 1 descent step [m]")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--seed", args.options.seed, "Seed of the inverse-kinematics restarts")
      ->check(seed_check_for(args.options.seed))
      ->capture_default_str();
  add_tool_option(sub, args.tool);
  return sub;
}

int run_check(const CheckArgs& args) {
  if (!(args.options.goal_dz >= kMinGoalDz && args.options.goal_dz <= 10))
    throw InputError("--dz " + format_number(args.options.goal_dz) + " must be between " +
                     format_number(kMinGoalDz) + " and 10 m");
  const auto scene = Scene::load(args.cell, scene_options(args.tool));
  const auto report = check_scene(scene, args.options);
  if (args.json)
    std::cout << to_json(scene, report).dump(2) << "\n";
  else
    std::cout << to_text(scene, report);
  return report.ok() ? kExitOk : kExitFindings;
}

}  // namespace leeway::cli
