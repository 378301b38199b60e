#pragma once
//! @file confidence.hpp
//! The Confidence Factor (thesis section 4.1): the share of random configurations within the
//! bounds, along the path, that do not hit the real obstacles.

#include <Eigen/Core>
#include <vector>

#include "leeway/bounds.hpp"
#include "leeway/params.hpp"
#include "leeway/scene.hpp"

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
  long collisions = 0;            //!< of which in collision
};

//! Section 4.1, as leeway reads it: the path (waypoints joined linearly in joint space, parameter s from 0 to
//! waypoints - 1) is split into `windows` equal windows; in each, `samples` configurations are drawn:
//! s uniform in the window, then every joint uniform within the bounds linearly interpolated at s.
//! Each is checked against the real obstacles (not the volume). Window w uses its own random
//! stream seeded from (seed, w), so the result is deterministic for any thread count.
//! @throws InputError on fewer than 1 window or sample, or bounds that do not match the scene.
CfResult confidence_factor(const Scene& scene, const std::vector<WaypointBounds>& bounds,
                           const CfParams& params, int threads);

//! 95 % Wilson score interval of a binomial proportion (successes of n).
std::pair<double, double> wilson_interval(long successes, long n);

}  // namespace leeway
