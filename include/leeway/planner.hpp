#pragma once
//! @file planner.hpp
//! The global planner (issue #4): the nominal path between two gripper positions, as in the thesis
//! (chapter 3: "The development and testing of the algorithm were done using RRT-connect as a
//! global planner"; section 4.1: the global planner takes "into input the starting and the goal
//! position of the robot gripper"). Endpoints are keyframes, goal sites or
//! points (inverse kinematics with the linear-axis policy first); OMPL's RRT-Connect plans in joint
//! space over every robot joint against the real obstacles, OMPL's simplifier shortens the path,
//! and leeway re-checks every edge. The path file format. docs/planning.md explains the guarantees.

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "leeway/kinematics.hpp"
#include "leeway/scene.hpp"

namespace leeway {

//! The linear-axis policy for a gripper goal: returns `q` with every slide joint moved so that the
//! arm base (the first hinge joint's anchor, as in categorize()) is abeam of `goal` along the
//! slide's axis: value = axis . (goal - base at slide value 0), clamped to the slide's limits. For
//! a rail along world x with the arm base at x = 0 when the rail is at 0 (the DLR cell), the rail
//! goes to the goal's x. Slides are placed in model order, so orthogonal slides (a gantry) each
//! take their own component. Without a hinge joint the tool site stands in for the arm base.
//! Hinge joints keep their values from `q`.
//! @throws InputError when `q` has the wrong size or is not finite, or `goal` is not finite.
Eigen::VectorXd place_slides(const Scene& scene, const Eigen::Vector3d& goal, const Eigen::VectorXd& q);

//! Inverse kinematics for a gripper goal: the slides placed by place_slides() and locked, then
//! solve_ik() over the other joints (tool pointing down unless `options.tool_down` is false,
//! within the limits, collision-free, nearest `seed`). `options.locked` is overridden for slides
//! and kept for the other joints. The returned IkResult says whether it converged.
//! @throws InputError as solve_ik().
IkResult gripper_ik(RobotState& state, const Eigen::Vector3d& goal, const Eigen::VectorXd& seed,
                    IkOptions options = {});

//! World position of a goal site [m]. @throws InputError listing the goal sites when unknown.
Eigen::Vector3d site_position(const Scene& scene, const std::string& name);

//! One end of a path, resolved from its text form (resolve_endpoints()).
struct Endpoint {
  std::string spec;                                    //!< as given: "home", "site:mould", "xyz:1,2,0.8"
  std::string keyframe;                                //!< the keyframe's name, or "" for a gripper goal
  std::string site;                                    //!< the goal site's name for "site:NAME", else ""
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  //!< gripper goal [m] (sites and points only)
  bool reachable = true;                               //!< false when inverse kinematics found no solution
  Eigen::VectorXd q;                                   //!< the configuration (the closest one if unreachable)
  IkResult ik;                                         //!< the IK result (sites and points only)
};

//! Options of resolve_endpoints().
struct EndpointOptions {
  std::string ik_seed_key;  //!< keyframe seeding every IK; "" = the policy of resolve_endpoints()
  IkOptions ik;             //!< restarts, RNG seed, tolerances (tool down and collision-free by default)
};

//! Resolves `from` and `to`. Each is a keyframe name, "site:NAME" (a goal site) or "xyz:X,Y,Z" (a
//! gripper position [m]). Gripper goals go through gripper_ik(), seeded (unless
//! options.ik_seed_key names a keyframe) with the other end when that is a keyframe, so the goal
//! configuration is the one nearest the start; when both are gripper goals `from` is seeded with
//! the first keyframe (or the joint values nearest zero within the limits) and `to` with `from`'s
//! solution. An unreachable goal is returned with reachable = false, not thrown.
//! @throws InputError on an unknown keyframe or site, a malformed spec or a bad IK seed key.
std::pair<Endpoint, Endpoint> resolve_endpoints(const Scene& scene, const std::string& from,
                                                const std::string& to, const EndpointOptions& options = {});

//! Parameters of plan_path(). Every value is SI (seconds, radians, metres).
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

//! The path file (docs/planning.md): format "leeway-path-1", units, cell, joints, waypoints (each
//! with q), from / to, planner settings and statistics.
nlohmann::json path_json(const Scene& scene, const PlanResult& result, const PlanOptions& options,
                         const Endpoint& from, const Endpoint& to);

//! Reads a path file (written by path_json) for `scene`.
//! @throws InputError naming the file and the mismatch: not a path file, other joints, fewer than
//! two waypoints, a wrong number of values, a value that is not a finite number, outside the limits.
std::vector<Eigen::VectorXd> read_path(const std::string& path, const Scene& scene);

}  // namespace leeway
