#pragma once
//! @file pipeline.hpp
//! The whole method on one path: categorise, generate the volume, inject it, bound every waypoint,
//! then the safety stage.

#include <Eigen/Core>
#include <vector>

#include "leeway/core/bounds.hpp"
#include "leeway/core/categorize.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/safety.hpp"
#include "leeway/core/scene.hpp"
#include "leeway/core/volume.hpp"
#include "leeway/core/volume_world.hpp"

namespace leeway {

//! Everything one run produces, with the time of each stage [ms].
struct BoundsRun {
  Categories categories;
  Volume volume;
  std::vector<WaypointBounds> bounds;
  SafetyReport safety;  //!< the safety stage (params.safety.mode)
  long checks = 0;
  double ms_categorize = 0, ms_volume = 0, ms_inject = 0, ms_bounds = 0, ms_safety = 0;
  double ms_total() const { return ms_categorize + ms_volume + ms_inject + ms_bounds + ms_safety; }
};

//! Checks `params` against the robot of `scene` (Params::validate checks them alone):
//! 'bounds.bisect' must name hinge joints of the robot; 'bounds.half_width' joints of the robot that
//! are not bisected; 'bounds.min_half_width' must be smaller than half the range of every bisected
//! (hinge) joint, or the collapse guard would "widen" an interval to the joint's whole range.
//! @throws InputError naming the parameter, the joint, the file and the values.
void validate_for_scene(const Params& params, const Scene& scene);

//! Runs the method on a path against a prepared VolumeModel (its one-off set-up is not timed), then
//! the safety stage of params.safety.mode against the real obstacles.
//! @throws InputError on invalid parameters or waypoints.
BoundsRun compute_bounds(const Scene& scene, VolumeModel& world, const std::vector<Eigen::VectorXd>& path,
                         const Params& params, int threads);

}  // namespace leeway
