#pragma once
//! @file categorize.hpp
//! Obstacle categorisation of thesis section 3.1.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "leeway/box.hpp"

namespace leeway {

//! Algorithm 1 (Identify Goal Obstacle): starting at the end-effector goal point, descend along
//! world z in steps of dz while z > 0 and return the index of the first obstacle box that contains
//! the point, or nothing when the point reaches the floor first.
//! @throws InputError when dz is not a finite positive length or the point is not finite.
std::optional<size_t> find_goal_obstacle(const Eigen::Vector3d& goal, const std::vector<Box>& obstacles,
                                         double dz);

}  // namespace leeway
