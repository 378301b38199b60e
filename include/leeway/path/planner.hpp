#pragma once
//! @file planner.hpp
//! The global planner: the nominal path between two gripper positions, as in the thesis
//! (chapter 3: "The development and testing of the algorithm were done using RRT-connect as a
//! global planner"; section 4.1: the global planner takes "into input the starting and the goal
//! position of the robot gripper"). OMPL's RRT-Connect plans in joint space over every robot joint
//! against the real obstacles, OMPL's simplifier shortens the path, and leeway re-checks every edge.
//! docs/planning.md explains the guarantees; endpoints.hpp resolves the path's ends.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "leeway/core/kinematics.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! Parameters of plan_path(). Every value is SI (seconds, radians, metres).
//! Largest PlanOptions::max_states: about 3.2 GiB of RRT-Connect trees at ~200 bytes per state.
inline constexpr long kMaxPlanStates = 16L * 1024 * 1024;

struct PlanOptions {
  double time_limit = 5.0;  //!< [s] RRT-Connect's budget; the simplifier and checks come on top
  //! Seed of every random choice (RRT-Connect's samples, the simplifier's shortcuts): the same seed
  //! and inputs give the same path, in one process or across runs.
  std::uint64_t seed = 1;
  //! Motion resolution [rad]: along an edge, consecutive collision checks are at most this far
  //! apart in every hinge joint. It also weights the planner's distance (see slide_resolution).
  double resolution = 0.01;
  //! Motion resolution of slide joints [m]. The planner measures motion in resolution steps, so one
  //! metre of a slide weighs as much as resolution / slide_resolution radians of a hinge.
  double slide_resolution = 0.01;
  //! RRT-Connect's longest extension, in the weighted joint space [rad]; 0 = OMPL's default (a
  //! fifth of the space's diagonal).
  double range = 0.0;
  //! Clearance margin [m]: every checked configuration keeps at least this distance between robot
  //! links and obstacles (RobotState::clearance); 0 = contact-free only.
  double clearance = 0.0;
  bool simplify = true;  //!< run OMPL's PathSimplifier (shortcuts, B-spline smoothing)
  //! Return the joint-linear edge start -> goal without sampling when it is free (it is then the
  //! shortest path in the planner's metric, which RRT-Connect plus simplification would also end
  //! with). false: always run RRT-Connect.
  bool try_direct = true;
  //! Memory guard: RRT-Connect stops (no path, a message saying why) after this many motion
  //! checks, each of which may add one state to its trees. At about 200 bytes per state (OMPL's
  //! motion, state and nearest-neighbour entry, our estimate) the default keeps the trees below
  //! about 3.2 GiB however long the time limit is.
  long max_states = kMaxPlanStates;
};

//! Outcome of plan_path(). Not finding a path is an outcome, not an error.
struct PlanResult {
  bool success = false;
  std::string message;                     //!< why not, when !success
  std::vector<Eigen::VectorXd> waypoints;  //!< start, ..., goal (joint-linear between them)
  //! "direct" when the joint-linear edge from start to goal is free (no sampling needed), else
  //! "rrt_connect".
  std::string method;
  bool simplified = false;        //!< the simplified path passed the re-check and is returned
  std::size_t raw_waypoints = 0;  //!< waypoints of RRT-Connect's path before simplification
  double length = 0.0;            //!< sum of the weighted joint-space lengths of the edges [rad]
  double plan_seconds = 0.0;      //!< RRT-Connect
  double simplify_seconds = 0.0;  //!< simplification and the final re-check
  long checks = 0;                //!< configurations checked for collision
};

//! Plans a collision-free joint-space path from `start` to `goal` with OMPL's RRT-Connect over
//! every robot joint (within the MJCF limits), states checked against the real obstacles with one
//! mjData per thread, edges checked at the motion resolution, then simplified. Every edge of the
//! returned path passes edge_is_free() at the options' resolution and clearance. Thread-safe: plans
//! may run concurrently on one Scene. While it runs, OMPL's process-wide log level is raised to
//! LOG_WARN (progress messages dropped) when it is lower; the caller's level is restored on return.
//! @throws InputError on invalid options, a start or goal of the wrong size, not finite, outside
//! the limits, in collision or closer than the clearance margin (the message names the joint or
//! the link and obstacle, with `start_name` / `goal_name`).
PlanResult plan_path(const Scene& scene, const Eigen::VectorXd& start, const Eigen::VectorXd& goal,
                     const PlanOptions& options = {}, const std::string& start_name = "start",
                     const std::string& goal_name = "goal");

//! Checks the joint-linear edge from `a` to `b`: a and b themselves and intermediate configurations
//! no more than `resolution` [rad] apart in every hinge joint and `slide_resolution` [m] in every
//! slide joint must be within the limits, contact-free and (when clearance > 0) at least
//! `clearance` [m] from the obstacles. `checks` is incremented per configuration checked.
bool edge_is_free(RobotState& state, const Eigen::VectorXd& a, const Eigen::VectorXd& b, double resolution,
                  double slide_resolution, double clearance, long& checks);

//! Throws when a configuration cannot start or end a path: outside the limits, in collision or
//! closer to an obstacle than `clearance`. @throws InputError naming `what`, the joint or the link,
//! obstacle and depth or distance.
void require_free(RobotState& state, const Eigen::VectorXd& q, double clearance, const std::string& what);

}  // namespace leeway
