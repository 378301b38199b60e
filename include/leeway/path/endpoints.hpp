#pragma once
//! @file endpoints.hpp
//! The ends of a nominal path: keyframes, goal sites or gripper points, resolved to configurations
//! (inverse kinematics with the linear-axis policy first).

#include <Eigen/Core>
#include <string>
#include <utility>

#include "leeway/core/kinematics.hpp"
#include "leeway/core/scene.hpp"

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

//! True when `spec` names a gripper goal ("site:NAME" or "xyz:X,Y,Z") rather than a keyframe.
bool is_gripper_goal(const std::string& spec);

//! Why an unreachable end has no configuration, in one line: "start 'xyz:5,5,5' at (5, 5, 5) m: no
//! collision-free configuration with the tool pointing down within the joint limits (closest:
//! position error 4.2 m, orientation error 0)" (the orientation error is the length of the tool
//! axis's difference from straight down, no unit). `start`: the path's first end.
std::string describe_unreachable(const Endpoint& end, bool start);

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

}  // namespace leeway
