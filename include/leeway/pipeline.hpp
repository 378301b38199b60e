#pragma once
//! @file pipeline.hpp
//! The whole method on one path: categorise, generate the volume, inject it, bound every waypoint;
//! the bounds file format; atomic output files.

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "leeway/bounds.hpp"
#include "leeway/confidence.hpp"
#include "leeway/params.hpp"
#include "leeway/safety.hpp"
#include "leeway/scene.hpp"
#include "leeway/volume.hpp"
#include "leeway/volume_world.hpp"

namespace leeway {

//! Cell-specific defaults read from MJCF custom numerics (docs/mjcf-conventions.md):
//! `leeway_reach_radius` [m] and `leeway_add_obstacle_boxes` (0 or 1). Applied to `params`.
//! @throws InputError on a non-finite or out-of-range value.
void apply_cell_defaults(const Scene& scene, Params& params);

//! A path between two keyframes: `waypoints` >= 2 configurations joined linearly in joint space
//! (the thesis's paths are its two end points). @throws InputError on unknown names or waypoints < 2.
std::vector<Eigen::VectorXd> keyframe_path(const Scene& scene, const std::string& from, const std::string& to,
                                           int waypoints);

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

//! Runs the method on a path against a prepared VolumeModel (its one-off set-up is not timed), then
//! the safety stage of params.safety.mode against the real obstacles.
//! @throws InputError on invalid parameters or waypoints.
BoundsRun compute_bounds(const Scene& scene, VolumeModel& world, const std::vector<Eigen::VectorXd>& path,
                         const Params& params, int threads);

//! The safety stage's record in a bounds file: mode, whether every segment passed, per segment
//! leaves/depth (certified) or samples/rounds (sampled), margin or epsilon, delta and N.
nlohmann::json safety_json(const SafetyReport& report, const SafetyParams& params);

//! The "format" value of the bounds files bounds_json writes and read_bounds accepts.
inline constexpr const char* kBoundsFormat = "leeway-bounds-1";

//! The bounds file (docs/cli.md): joints, waypoints (q, lower, upper), boxes, max_cells, timing_ms...
nlohmann::json bounds_json(const Scene& scene, const BoundsRun& run, const Params& params);

//! Reads a bounds file written for `scene`: q, lower, upper and collapsed of every waypoint (the
//! guide bounds and checks are not read). A file without "format" is accepted (older files).
//! @throws InputError naming the file and the mismatch (a "format" other than kBoundsFormat, other
//! joints, wrong sizes, NaN, lower > upper, nominal outside its bounds, an unknown collapsed joint).
std::vector<WaypointBounds> read_bounds(const std::string& path, const Scene& scene);

//! Writes text to a temporary file beside `path`, then renames it: no partial file on failure.
//! @throws InputError naming the file when it cannot be written.
void write_file_atomic(const std::string& path, const std::string& text);

}  // namespace leeway
