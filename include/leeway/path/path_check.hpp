#pragma once
//! @file path_check.hpp
//! The dense check of a nominal path ("the nominal path is checked first"): the thesis's
//! method (chapter 3) bounds the joints around a nominal path that, in our reading, it assumes
//! collision-free, so
//! every configuration along the path, not only the waypoints, is checked against the real
//! obstacles before anything is bounded.

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "leeway/core/scene.hpp"

namespace leeway {

//! Parameters of check_path(). The defaults are five times finer than the planner's (PlanOptions),
//! so that a path the planner found is checked again between its own samples.
struct PathCheckOptions {
  double resolution = 0.002;        //!< [rad] hinge motion between consecutive checks along an edge
  double slide_resolution = 0.002;  //!< [m] slide motion between consecutive checks along an edge
};

//! The first configuration along a path that collides with an obstacle or leaves the joint limits.
struct PathCollision {
  //! The waypoint when the colliding configuration is a waypoint itself, else -1.
  long waypoint = -1;
  //! The edge (from waypoint `edge` to `edge` + 1) of the colliding configuration; a colliding
  //! waypoint w > 0 lies on edge w - 1 at s = 1, waypoint 0 on edge 0 at s = 0.
  long edge = 0;
  //! Fraction along the edge [0, 1] of the first colliding sample; the collision starts within one
  //! resolution step before it.
  double s = 0.0;
  //! Path parameter edge + s, from 0 (first waypoint) to waypoints - 1 (last).
  double path_parameter = 0.0;
  //! path_parameter / (waypoints - 1) in [0, 1] (0 for a one-waypoint path): for equally spaced
  //! waypoints on one straight line (keyframe_path()) the fraction of the whole straight path.
  double path_fraction = 0.0;
  Eigen::VectorXd q;  //!< the colliding configuration [rad, m]
  //! The deepest contact's robot link and obstacle geoms (-1 when a joint is outside its limits).
  int link_geom = -1;
  int obstacle_geom = -1;
  std::string link;      //!< Scene::geom_label(link_geom), or "" (limits)
  std::string obstacle;  //!< Scene::geom_label(obstacle_geom), or "" (limits)
  double depth = 0.0;    //!< penetration depth of the deepest contact [m] (RobotState::contacts)
  int contacts = 0;      //!< link-obstacle pairs in contact at q (self pairs when `self`)
  //! The robot hits itself at q: link_geom and obstacle_geom are then two robot geoms (a
  //! Scene::self_pairs() pair, geom1 as obstacle_geom), and no obstacle is touched.
  bool self = false;
  //! A joint outside its limits at q (then there is no contact data), else -1.
  int joint = -1;
};

//! Outcome of check_path(). A colliding path is an outcome, not an error.
struct PathCheckResult {
  std::optional<PathCollision> collision;  //!< the first collision along the path, if any
  long checks = 0;                         //!< configurations checked
  bool free() const { return !collision.has_value(); }
};

//! Checks a nominal path, its waypoints joined linearly in joint space, in order from the first
//! waypoint: the first waypoint, then each edge at samples no more than `options.resolution` [rad]
//! apart in every hinge joint and `options.slide_resolution` [m] in every slide joint (the edge's
//! end included), each within the joint limits and contact-free against the real obstacles
//! (RobotState). Stops at the first colliding sample, so the collision returned is the first along
//! the path to within one step. Deterministic; a fresh RobotState, so it may run concurrently on
//! one Scene. A free path costs 1 + sum over edges of max(1, max_j ceil(|dq_j| / step_j)) checks.
//! @throws InputError on an empty path, a waypoint of the wrong size or not finite, or resolutions
//! that are not finite numbers > 0.
PathCheckResult check_path(const Scene& scene, const std::vector<Eigen::VectorXd>& path,
                           const PathCheckOptions& options = {});

//! One line saying what was hit where, for messages: "hits 'wall' on edge 2 -> 3 at s = 0.412 (link
//! 'link_box', depth 0.0004 m)" or "hits 'wall' at waypoint 3 (...)"; a joint outside its limits:
//! "leaves the limits of joint 'j2' (3.2 rad, limits [-3, 3]) at waypoint 0". With `whole_path`,
//! the place is path_fraction instead ("hits 'wall' at s = 0.35 (...)"), for a straight path.
//! s is rounded to three decimals. `scene` names joints and units.
std::string describe_collision(const Scene& scene, const PathCollision& collision, bool whole_path = false);

}  // namespace leeway
