#include "leeway/path/path_check.hpp"

#include <algorithm>
#include <cmath>

#include "leeway/core/error.hpp"
#include "leeway/core/kinematics.hpp"

namespace leeway {
namespace {

// Segments of the edge a -> b such that no joint moves more than its step between samples; the
// same criterion as the planner's edge check (planner.cpp), with the 1e-9 keeping 3 / 0.01 at 300.
long edge_segments(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const Eigen::VectorXd& step) {
  const double m = ((b - a).cwiseAbs().array() / step.array()).maxCoeff();
  return std::max(1L, static_cast<long>(std::ceil(m - 1e-9)));
}

std::string three_decimals(double s) { return format_number(std::round(s * 1000.0) / 1000.0); }

}  // namespace

PathCheckResult check_path(const Scene& scene, const std::vector<Eigen::VectorXd>& path,
                           const PathCheckOptions& options) {
  if (path.empty()) throw InputError(scene.source() + ": path check: the path has no waypoints");
  for (const auto& [value, unit] : {std::pair{options.resolution, "rad"}, {options.slide_resolution, "m"}})
    if (!(std::isfinite(value) && value > 0))
      throw InputError("path check: the resolution " + format_number(value) + " " + unit +
                       " must be a finite number > 0");
  for (std::size_t i = 0; i < path.size(); ++i)
    scene.validate_configuration(path[i], "path waypoint " + std::to_string(i));

  Eigen::VectorXd step(scene.dof());
  for (int j = 0; j < scene.dof(); ++j)
    step[j] =
        scene.joints()[static_cast<std::size_t>(j)].prismatic ? options.slide_resolution : options.resolution;
  RobotState state(scene);
  PathCheckResult result;
  const double edges = static_cast<double>(path.size() - 1);

  // Checks q; on a collision fills result.collision and returns false.
  auto free = [&](const Eigen::VectorXd& q, long edge, double s, long waypoint) {
    ++result.checks;
    const auto outside = scene.joints_outside_limits(q);
    // Limits before contacts: a configuration outside the limits is not one the robot can take.
    if (outside.empty() && !state.in_collision(q)) return true;
    PathCollision c;
    c.waypoint = waypoint;
    c.edge = edge;
    c.s = s;
    c.path_parameter = static_cast<double>(edge) + s;
    c.path_fraction = edges > 0 ? c.path_parameter / edges : 0.0;
    c.q = q;
    if (!outside.empty()) {
      c.joint = outside.front();
    } else {
      const auto contacts = state.contacts(q);
      if (!contacts.empty()) {
        c.link_geom = contacts.front().link_geom;
        c.obstacle_geom = contacts.front().obstacle_geom;
        c.depth = contacts.front().depth;
        c.contacts = static_cast<int>(contacts.size());
      } else {
        const auto self = state.self_contacts(q);
        LEEWAY_DEMAND(!self.empty());
        c.self = true;
        c.link_geom = self.front().geom2;
        c.obstacle_geom = self.front().geom1;
        c.depth = self.front().depth;
        c.contacts = static_cast<int>(self.size());
      }
      c.link = scene.geom_label(c.link_geom);
      c.obstacle = scene.geom_label(c.obstacle_geom);
    }
    result.collision = std::move(c);
    return false;
  };

  if (!free(path.front(), 0, 0.0, 0)) return result;
  for (std::size_t e = 0; e + 1 < path.size(); ++e) {
    const Eigen::VectorXd& a = path[e];
    const Eigen::VectorXd& b = path[e + 1];
    const long n = edge_segments(a, b, step);
    for (long k = 1; k <= n; ++k) {
      // The edge's end is the next waypoint exactly, not a rounded interpolation.
      const bool end = k == n;
      const double s = end ? 1.0 : static_cast<double>(k) / static_cast<double>(n);
      const Eigen::VectorXd q = end ? b : Eigen::VectorXd(a + (b - a) * s);
      if (!free(q, static_cast<long>(e), s, end ? static_cast<long>(e + 1) : -1L)) return result;
    }
  }
  return result;
}

std::string describe_collision(const Scene& scene, const PathCollision& c, bool whole_path) {
  std::string where;
  if (whole_path)
    where = "at s = " + three_decimals(c.path_fraction);
  else if (c.waypoint >= 0)
    where = "at waypoint " + std::to_string(c.waypoint);
  else
    where = "on edge " + std::to_string(c.edge) + " -> " + std::to_string(c.edge + 1) +
            " at s = " + three_decimals(c.s);
  if (c.joint >= 0) {
    const RobotJoint& j = scene.joints().at(static_cast<std::size_t>(c.joint));
    const std::string unit = j.prismatic ? " m" : " rad";
    return "leaves the limits of joint '" + j.name + "' (" + format_number(c.q[c.joint]) + unit +
           ", limits [" + format_number(j.lower) + ", " + format_number(j.upper) + "]" + unit + ") " + where;
  }
  if (c.self)
    return "hits itself " + where + ": robot geoms '" + c.obstacle + "' and '" + c.link + "' (depth " +
           format_number(c.depth) + " m" +
           (c.contacts > 1 ? ", and " + std::to_string(c.contacts - 1) + " more self pairs" : std::string()) +
           ")";
  return "hits '" + c.obstacle + "' " + where + " (link '" + c.link + "', depth " + format_number(c.depth) +
         " m" +
         (c.contacts > 1 ? ", and " + std::to_string(c.contacts - 1) + " more contacts" : std::string()) +
         ")";
}

}  // namespace leeway
