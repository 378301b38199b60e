#pragma once
//! @file room.hpp
//! How much room the bounds leave the co-worker (docs/algorithm.md, "Room"): per joint, the share
//! of its one-joint free range the bounds keep; and the tool's room, the largest translation and
//! rotation of the tool site over configurations inside the bounds (sampled: a lower bound).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "leeway/core/bounds.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! Options of measure_room.
struct RoomOptions {
  //! The free range's ends are found to within this [rad for hinges, m for slides].
  double tolerance = 1e-4;
  //! Random configurations per waypoint for the tool's room, besides the box's corners (all 2^n
  //! when n <= 10 joints, else 1024 random corners).
  int tool_samples = 256;
  std::uint64_t seed = 1;  //!< RNG seed of those samples
  //! A path with more waypoints is measured at this many, evenly spaced, the first and the last
  //! among them (a 1,000-waypoint path's free ranges take about 20 s on one core); 0: every one.
  int max_waypoints = 50;
};

//! The one-joint free range of joint i at configuration q: the largest interval [lower, upper]
//! around q[i], within the joint's limits, over which moving joint i alone (the others at q) keeps
//! the robot free of the obstacles and of itself (RobotState::in_collision). Found by conservative
//! advancement: each step turns joint i by no more than any geom it moves may turn before it can
//! touch an obstacle or the other geom of a self pair (their boxes' gap over that geom's largest
//! distance from the axis), then bisection to `tolerance` once a step collides. Where no such bound
//! exists (a plane obstacle, a self pair whose boxes overlap) the step is at most 0.02 rad (slides:
//! 5 mm); beside a self pair whose boxes are apart it is at least an eighth of that (the sweep is
//! a measure, not a proof: the certificate proves the bounds). {q[i], q[i]} when q itself collides.
struct FreeRange {
  double lower = 0.0, upper = 0.0;  //!< [rad or m]
};
std::vector<FreeRange> one_joint_free_ranges(RobotState& state, const Eigen::VectorXd& q, double tolerance);

//! The room at one waypoint.
struct WaypointRoom {
  size_t waypoint = 0;          //!< index of the waypoint in the path
  std::vector<FreeRange> free;  //!< per joint: the one-joint free range at the nominal value
  //! Per joint: (upper - lower) of the bounds over the free range's width, in [0, 1]; NaN when the
  //! free range is empty (the nominal configuration collides, or the joint is locked by its limits).
  Eigen::VectorXd share;
  double tool_translation = 0.0;  //!< largest |p - p_nominal| of the tool site found [m]
  double tool_rotation = 0.0;     //!< largest rotation angle from the nominal tool orientation found [rad]
};

//! The room of a bounded path.
struct RoomReport {
  std::vector<WaypointRoom> waypoints;  //!< the measured waypoints, in path order
  //! Per joint: the mean of its share over the waypoints where it is defined (NaN when nowhere).
  Eigen::VectorXd joint_share;
  double mean_share = 0.0;  //!< the mean of joint_share over the joints where it is defined
  double ms = 0.0;          //!< wall time [ms]
};

//! Measures the room of `bounds` (waypoints of `scene`), spread over `threads` threads.
//! Deterministic for options.seed, whatever the thread count. @throws InputError on bounds that do
//! not fit the scene.
RoomReport measure_room(const Scene& scene, const std::vector<WaypointBounds>& bounds,
                        const RoomOptions& options = {}, int threads = 1);

}  // namespace leeway
