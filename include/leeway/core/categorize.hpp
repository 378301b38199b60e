#pragma once
//! @file categorize.hpp
//! Obstacle categorisation of thesis section 3.1.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "leeway/core/box.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! The categorised obstacles of section 3.1, as boxes in world coordinates.
struct Categories {
  std::optional<Box> goal;                //!< the goal obstacle (Algorithm 1), if any
  int goal_geom = -1;                     //!< its geom id in the scene (-1 when none or not from a scene)
  std::vector<Box> non_goal;              //!< every other obstacle
  std::vector<Box> trail;                 //!< robot link boxes at every (densified) path pose
  std::vector<Eigen::Vector2d> arm_base;  //!< arm-base position in the floor plane at every path pose
};

//! Algorithm 1 (Identify Goal Obstacle): starting at the end-effector goal point, descend along
//! world z in steps of dz while z > 0 and return the index of the first obstacle box that contains
//! the point, or nothing when the point reaches the floor first.
//! @throws InputError when dz is not a finite positive length or the point is not finite.
std::optional<size_t> find_goal_obstacle(const Eigen::Vector3d& goal, const std::vector<Box>& obstacles,
                                         double dz);

//! The poses the trail is made of: every waypoint, plus `densify` evenly spaced joint-space poses
//! inside each segment between consecutive waypoints.
std::vector<Eigen::VectorXd> trail_poses(const std::vector<Eigen::VectorXd>& path, int densify);

//! Section 3.1 on a scene and a nominal path: the goal obstacle is found by Algorithm 1 below the
//! tool position at the path's last waypoint; every other obstacle is non-goal (collidable planes
//! are left out); the trail holds every robot link box at every trail pose; the arm base is the
//! first hinge joint's anchor, projected on the floor, at every trail pose.
//! @throws InputError on an empty path, a waypoint of the wrong size or a bad goal_dz.
Categories categorize(const Scene& scene, const std::vector<Eigen::VectorXd>& path,
                      const CategorizeParams& params);

}  // namespace leeway
