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
  sub->add_option("--dz", args.options.goal_dz, "Algorithm 1 descent step [m]")->capture_default_str();
  sub->add_option("--seed", args.options.seed, "Seed of the inverse-kinematics restarts")
      ->capture_default_str();
  add_tool_option(sub, args.tool);
  return sub;
}

int run_check(const CheckArgs& args) {
  const auto scene = Scene::load(args.cell, scene_options(args.tool));
  const auto report = check_scene(scene, args.options);
  if (args.json)
    std::cout << to_json(scene, report).dump(2) << "\n";
  else
    std::cout << to_text(scene, report);
  return report.ok() ? kExitOk : kExitFindings;
}

}  // namespace leeway::cli
