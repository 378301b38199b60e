#pragma once
//! @file confidence.hpp
//! The Confidence Factor (thesis section 4.1): the share of random configurations within the
//! bounds, along the path, that do not hit the real obstacles.

#include <Eigen/Core>
#include <vector>

#include "leeway/core/bounds.hpp"
#include "leeway/core/bounds_trajectory.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! Confidence Factor of a bounded path.
struct CfResult {
  double cf = 0;      //!< collision-free share over all samples (= mean of the windows)
  double ci_low = 0;  //!< 95 % Wilson score interval of cf
  double ci_high = 0;
  int worst_window = -1;  //!< window with the lowest collision-free share
  double worst_window_cf = 0;
  std::vector<double> window_cf;  //!< per window
  long samples = 0;               //!< configurations tested
  long collisions = 0;            //!< of which in collision (CfParams::self says what counts)
  long obstacle_collisions = 0;   //!< samples where a link touches an obstacle
  long self_collisions = 0;       //!< samples where two robot geoms touch (Scene::self_pairs())
  long any_collisions = 0;        //!< samples with either
  bool timed = false;             //!< windows cut the path by time (every joint has a nominal speed)
  double duration = 0;            //!< the path's duration [s] when timed, else its segment count
};

//! The nominal path timed by the joints' nominal speeds (joint `user[0]`, RobotJoint::max_speed): a
//! segment lasts as long as its slowest joint needs, max_j |q_j(b) - q_j(a)| / speed_j [s]. When a
//! joint has no speed (0), the path is untimed: every segment lasts 1 (the path parameter).
struct PathTiming {
  bool timed = false;
  std::vector<double> segment;        //!< duration of each segment [s, or 1 when untimed]
  std::vector<double> segment_start;  //!< when each waypoint is reached (0 for the first)
  double total = 0;                   //!< the path's duration
};
PathTiming time_path(const Scene& scene, const std::vector<WaypointBounds>& bounds);

//! Section 4.1, as leeway reads it: the path (waypoints joined linearly in joint space) is split by
//! time into `windows` windows of equal duration (time_path(); the thesis's "time window"); in each,
//! `samples` configurations are drawn: a moment uniform in the window, the segment it falls in and
//! the position t in it, then every joint uniform within the bounds linearly interpolated at t. A
//! segment's share of the samples is its share of the duration, so duplicated waypoints (a segment
//! of zero length) weigh nothing and how the path is sampled does not change the CF. On a
//! two-waypoint path (the thesis's) this is the same as windows of equal path parameter.
//! Each is checked against the real obstacles (not the volume). Window w uses its own random
//! stream seeded from (seed, w), so the result is deterministic for any thread count.
//! @throws InputError on fewer than 1 window or sample, or bounds that do not match the scene.
CfResult confidence_factor(const Scene& scene, const std::vector<WaypointBounds>& bounds,
                           const CfParams& params, int threads);

//! The Confidence Factor of a trajectory, with its own times (a bounds file's): the same draws as
//! above, located by BoundsTrajectory::locate_share.
//! @throws InputError on fewer than 1 window or sample, or bounds of another joint count.
CfResult confidence_factor(const Scene& scene, const BoundsTrajectory& path, const CfParams& params,
                           int threads);

//! 95 % Wilson score interval of a binomial proportion (successes of n).
std::pair<double, double> wilson_interval(long successes, long n);

}  // namespace leeway
