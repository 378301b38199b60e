#include "cli/fk.hpp"

#include <iostream>

#include "leeway/core/kinematics.hpp"

namespace leeway::cli {
namespace {

nlohmann::json pose_json(const Pose& p) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) rows.push_back({p.rotation(r, 0), p.rotation(r, 1), p.rotation(r, 2)});
  return {{"position", {p.position.x(), p.position.y(), p.position.z()}}, {"rotation", rows}};
}

void print_pose(const Pose& p) {
  std::cout.setf(std::ios::fixed);
  std::cout.precision(6);
  std::cout << "position [m]: " << p.position.x() << " " << p.position.y() << " " << p.position.z() << "\n";
  std::cout << "rotation (rows; columns are the tool axes in world):\n";
  for (int r = 0; r < 3; ++r)
    std::cout << "  " << p.rotation(r, 0) << " " << p.rotation(r, 1) << " " << p.rotation(r, 2) << "\n";
}

}  // namespace

CLI::App* add_fk(CLI::App& app, FkArgs& args) {
  CLI::App* sub =
      app.add_subcommand("fk", "Forward kinematics: the tool site's position [m] and orientation");
  sub->add_option("cell", args.cell, "MJCF file of the workcell")->required();
  sub->add_option("--q", args.q, "Joint values in the robot's joint order [rad or m], e.g. \"0 0 0 0 0 0\"");
  sub->add_option("--key", args.key, "Use a keyframe's joint values instead of --q");
  sub->add_flag("--json", args.json, "Print JSON: position [x, y, z] and rotation (3x3 rows)");
  add_tool_option(sub, args.tool);
  return sub;
}

int run_fk(const FkArgs& args) {
  const auto scene = Scene::load(args.cell, scene_options(args.tool));
  const Eigen::VectorXd q = configuration(scene, args.q, args.key, args.cell);
  RobotState state(scene);
  const Pose p = state.fk(q);
  if (args.json) {
    nlohmann::json out = pose_json(p);
    out["q"] = to_array(q);
    out["units"] = "SI: metres, radians";
    std::cout << out.dump(2) << "\n";
  } else {
    print_pose(p);
  }
  return kExitOk;
}

}  // namespace leeway::cli
