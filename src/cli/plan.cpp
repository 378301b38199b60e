#include "cli/plan.hpp"

#include <iomanip>
#include <iostream>

#include "leeway/core/file_io.hpp"
#include "leeway/core/mjcf_source.hpp"
#include "leeway/path/endpoints.hpp"
#include "leeway/path/nominal_path.hpp"
#include "leeway/path/path_check.hpp"
#include "leeway/path/planner.hpp"

namespace leeway::cli {

CLI::App* add_plan(CLI::App& app, PlanArgs& args) {
  CLI::App* sub = app.add_subcommand(
      "plan",
      "Plan a collision-free path (OMPL RRT-Connect in joint space, then simplified) between two\n"
      "keyframes or gripper goals (site:NAME, xyz:X,Y,Z: inverse kinematics first); see docs/planning.md.\n"
      "Exit 0 path found, 1 unreachable goal or no path within the time limit, 2 bad input\n"
      "(also a start or goal in collision).");
  PlanOptions& o = args.options;
  sub->add_option("cell", args.cell, "MJCF file of the workcell")->required();
  add_checker_option(sub, args.checker);
  sub->add_option("--from", args.from, "Start: a keyframe, site:NAME or xyz:X,Y,Z [m]")->required();
  sub->add_option("--to", args.to, "Goal: a keyframe, site:NAME or xyz:X,Y,Z [m]")->required();
  sub->add_option("--seed", o.seed, "Random seed (same seed, same path)")
      ->check(seed_check_for(o.seed))
      ->capture_default_str();
  sub->add_option("--time-limit", o.time_limit, "RRT-Connect's time budget [s]")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--resolution", o.resolution, "Motion resolution of hinge joints [rad]")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--slide-resolution", o.slide_resolution, "Motion resolution of slide joints [m]")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--range", o.range, "RRT-Connect's longest extension [rad]; 0 = OMPL's default")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_option("--clearance", o.clearance, "Clearance margin to the obstacles [m]")
      ->check(finite_check())
      ->capture_default_str();
  sub->add_flag("--no-simplify", args.no_simplify, "Keep RRT-Connect's raw path");
  sub->add_flag("--no-direct", args.no_direct,
                "Run RRT-Connect even when the joint-linear edge from start to goal is free");
  sub->add_option("--ik-seed", args.ik_seed, "Keyframe seeding the inverse kinematics of gripper goals");
  sub->add_option("--out", args.out, "Write the path file here (JSON)")->check(file_name_check());
  sub->add_flag("--json", args.json, "Print the path file to standard output");
  add_tool_option(sub, args.tool);
  return sub;
}

int run_plan(const PlanArgs& args) {
  const auto scene = Scene::load(args.cell, scene_options(args.tool, args.checker));
  require_outputs({{args.out, "--out", {}}}, model_input_files(args.cell));
  PlanOptions options = args.options;
  options.simplify = !args.no_simplify;
  options.try_direct = !args.no_direct;
  PlanResult result;
  Endpoint a, b;
  if (!plan_between(scene, args.from, args.to, args.ik_seed, options, result, a, b)) return kExitFindings;
  // The planner checks its edges at --resolution; a path is written only when it also passes the
  // fine edge check `leeway bounds --path` applies, so that what plan writes bounds reads.
  const PathCheckOptions fine;
  const PathCheckResult checked = check_path(scene, result.waypoints, fine);
  if (!checked.free()) {
    std::cerr << "leeway: collision: " << scene.source() << ": the path planned from " << args.from << " to "
              << args.to << " " << describe_collision(scene, *checked.collision) << " when checked at "
              << format_number(fine.resolution) << " rad (the planner checks at "
              << format_number(options.resolution) << " rad: use a finer --resolution or another --seed)"
              << "; nothing written\n";
    return kExitFindings;
  }
  const nlohmann::json out = path_json(scene, result, options, a, b);
  if (!args.out.empty()) write_file_atomic(args.out, out.dump(2) + "\n");
  if (args.json) {
    std::cout << out.dump(2) << "\n";
    return kExitOk;
  }
  std::cout << scene.source() << " " << args.from << " -> " << args.to << " (units: rad, m, s)\n";
  std::cout << result.waypoints.size() << " waypoints, " << result.method
            << (result.method == "direct" ? " (the joint-linear edge is free)" : "") << ", length "
            << format_number(result.length) << " rad (weighted), " << result.checks << " collision checks, "
            << format_number(result.plan_seconds + result.simplify_seconds) << " s, seed " << options.seed
            << "\n";
  std::cout << "joints:";
  for (const auto& n : scene.joint_names()) std::cout << " " << n;
  std::cout << "\n" << std::fixed << std::setprecision(6);
  for (size_t w = 0; w < result.waypoints.size(); ++w) {
    std::cout << "  " << std::setw(3) << w << ":";
    for (Eigen::Index i = 0; i < result.waypoints[w].size(); ++i) std::cout << " " << result.waypoints[w][i];
    std::cout << "\n";
  }
  if (!args.out.empty()) std::cout << "wrote " << args.out << "\n";
  return kExitOk;
}

}  // namespace leeway::cli
