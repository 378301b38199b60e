#include "leeway/categorize.hpp"

#include <cmath>

#include "leeway/error.hpp"
#include "leeway/scene.hpp"

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

}  // namespace leeway
