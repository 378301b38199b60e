#include "cli/ik.hpp"

#include <iostream>

namespace leeway::cli {
namespace {

std::string joint_unit(const RobotJoint& j) { return j.prismatic ? "m" : "rad"; }

}  // namespace

CLI::App* add_ik(CLI::App& app, IkArgs& args) {
  CLI::App* sub = app.add_subcommand(
      "ik",
      "Inverse kinematics: joint values that put the tool site at a goal, tool pointing down,\n"
      "within limits and collision-free, nearest the seed. Exit 1 when no solution is found.");
  sub->add_option("cell", args.cell, "MJCF file of the workcell")->required();
  auto* site_opt = sub->add_option("--site", args.site, "Goal site name");
  sub->add_option("--xyz", args.xyz, "Goal position x y z [m]")->expected(3)->excludes(site_opt);
  sub->add_option("--seed-q", args.seed_q, "Seed configuration [rad or m] (default: first keyframe)");
  sub->add_option("--seed-key", args.seed_key, "Seed from a keyframe");
  sub->add_option("--lock", args.lock,
                  "Comma-separated joints kept at the seed value (e.g. the linear axis)");
  sub->add_flag("--free-orientation", args.free_orientation,
                "Position only: do not require the tool to point down");
  sub->add_option("--restarts", args.options.restarts, "Random restarts after the seed")
      ->capture_default_str();
  sub->add_option("--seed", args.options.seed, "Seed of the random restarts")
      ->check(seed_check_for(args.options.seed))
      ->capture_default_str();
  sub->add_flag("--json", args.json, "Print JSON");
  add_tool_option(sub, args.tool);
  return sub;
}

int run_ik(const IkArgs& args) {
  if (args.options.restarts < 0 || args.options.restarts > 100000)
    throw InputError("--restarts " + std::to_string(args.options.restarts) + " must be from 0 to 100000");
  const auto scene = Scene::load(args.cell, scene_options(args.tool));
  Eigen::Vector3d target;
  if (!args.site.empty()) {
    RobotState probe(scene);
    probe.set(scene.lower_limits().cwiseMax(0).cwiseMin(scene.upper_limits()));
    target = probe.site_pose(scene.goal_site(args.site)).position;
  } else if (args.xyz.size() == 3) {
    target = Eigen::Vector3d(args.xyz[0], args.xyz[1], args.xyz[2]);
    if (!target.allFinite()) throw InputError(args.cell + ": --xyz values must be finite numbers");
  } else {
    throw InputError(args.cell + ": give the goal with --site NAME or --xyz X Y Z");
  }
  Eigen::VectorXd seed;
  if (!args.seed_q.empty() || !args.seed_key.empty())
    seed = configuration(scene, args.seed_q, args.seed_key, args.cell + " seed");
  else
    seed = default_ik_seed(scene);
  IkOptions options = args.options;
  options.tool_down = !args.free_orientation;
  options.locked.assign(static_cast<size_t>(scene.dof()), false);
  if (!args.lock.empty()) {
    std::string name;
    auto lock = [&](const std::string& n) {
      const auto names = scene.joint_names();
      for (size_t i = 0; i < names.size(); ++i)
        if (names[i] == n) {
          options.locked[i] = true;
          return;
        }
      throw InputError(args.cell + ": --lock names unknown joint '" + n + "'");
    };
    for (char c : args.lock + ",") {
      if (c == ',') {
        if (!name.empty()) lock(name);
        name.clear();
      } else {
        name += c;
      }
    }
  }
  RobotState state(scene);
  const auto result = solve_ik(state, target, seed, options);
  if (args.json) {
    nlohmann::json out = {{"success", result.success},
                          {"target", {target.x(), target.y(), target.z()}},
                          {"joints", scene.joint_names()},
                          {"q", to_array(result.q)},
                          {"position_error", result.position_error},
                          {"orientation_error", result.orientation_error},
                          {"units", "SI: metres, radians"}};
    std::cout << out.dump(2) << "\n";
  } else {
    std::cout << (result.success ? "solution" : "NO SOLUTION; closest configuration")
              << " (units: rad, m):\n";
    for (int i = 0; i < scene.dof(); ++i) {
      const auto& j = scene.joints()[static_cast<size_t>(i)];
      std::cout << "  " << j.name << " = " << result.q[i] << " " << joint_unit(j) << "\n";
    }
    std::cout << "position error " << result.position_error << " m, orientation error "
              << result.orientation_error << "\n";
  }
  return result.success ? kExitOk : kExitFindings;
}

}  // namespace leeway::cli
