#include "leeway/core/categorize.hpp"

#include <cmath>

#include "leeway/core/error.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

std::optional<size_t> find_goal_obstacle(const Eigen::Vector3d& goal, const std::vector<Box>& obstacles,
                                         double dz) {
  if (!std::isfinite(dz) || dz <= 0)
    throw InputError("goal search step dz '" + format_number(dz) + "' must be a finite length > 0 m");
  if (!goal.allFinite()) throw InputError("goal point is not finite");
  Eigen::Vector3d point = goal;
  // The loop count is bounded by z / dz; the index form avoids accumulating rounding in point.z.
  for (long step = 0; point.z() > 0; ++step) {
    for (size_t i = 0; i < obstacles.size(); ++i)
      if (contains(obstacles[i], point)) return i;
    point.z() = goal.z() - static_cast<double>(step + 1) * dz;
  }
  return std::nullopt;
}

std::vector<Eigen::VectorXd> trail_poses(const std::vector<Eigen::VectorXd>& path, int densify) {
  std::vector<Eigen::VectorXd> out;
  for (size_t i = 0; i < path.size(); ++i) {
    out.push_back(path[i]);
    if (i + 1 == path.size()) break;
    for (int k = 1; k <= densify; ++k) {
      const double t = static_cast<double>(k) / (densify + 1);
      out.push_back(path[i] + t * (path[i + 1] - path[i]));
    }
  }
  return out;
}

Categories categorize(const Scene& scene, const std::vector<Eigen::VectorXd>& path,
                      const CategorizeParams& params) {
  if (path.empty()) throw InputError(scene.source() + ": the path has no waypoints");
  if (params.trail_densify < 0)
    throw InputError("parameter 'categorize.trail_densify' = " + std::to_string(params.trail_densify) +
                     " must be >= 0");
  for (size_t i = 0; i < path.size(); ++i)
    scene.validate_configuration(path[i], "waypoint " + std::to_string(i));
  const mjModel& m = scene.model();
  RobotState state(scene);
  Categories c;

  // Goal and non-goal obstacles (static: their boxes at any pose).
  const std::vector<int>& obstacles = scene.obstacle_geoms();
  std::vector<Box> boxes;
  std::vector<int> ids;
  state.set(path.back());
  for (int g : obstacles) {
    if (!has_bounding_box(m, g)) continue;  // the plane rule, box.hpp
    boxes.push_back(geom_box(m, state.data(), g));
    ids.push_back(g);
  }
  const auto goal = find_goal_obstacle(state.tool_pose().position, boxes, params.goal_dz);
  for (size_t i = 0; i < boxes.size(); ++i) {
    if (goal && *goal == i) {
      c.goal = boxes[i];
      c.goal_geom = ids[i];
    } else {
      c.non_goal.push_back(boxes[i]);
    }
  }

  // Trail and arm base along the (densified) path.
  int first_hinge = -1;
  for (const auto& j : scene.joints())
    if (!j.prismatic) {
      first_hinge = j.id;
      break;
    }
  for (const Eigen::VectorXd& q : trail_poses(path, params.trail_densify)) {
    state.set(q);
    for (int g : scene.link_geoms()) c.trail.push_back(geom_box(m, state.data(), g));
    const mjtNum* anchor = first_hinge >= 0 ? state.data().xanchor + 3 * first_hinge
                                            : state.data().xpos + 3 * scene.robot_root_body();
    c.arm_base.emplace_back(anchor[0], anchor[1]);
  }
  return c;
}

}  // namespace leeway
