#pragma once
//! @file bounds_file.hpp
//! The bounds file (docs/cli.md): writing it from a run and reading it back.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "leeway/core/bounds.hpp"
#include "leeway/core/bounds_trajectory.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/core/room.hpp"
#include "leeway/core/safety.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! The safety stage's record in a bounds file: mode, whether every segment passed, per segment
//! leaves/depth (certified) or samples/rounds (sampled), margin or epsilon, delta and N; certified:
//! the pairs proven apart (link-obstacle and self pairs, counted) and the excluded pairs by name.
nlohmann::json safety_json(const Scene& scene, const SafetyReport& report, const SafetyParams& params);

//! The "format" value of the bounds files bounds_json writes: format 2 adds each waypoint's time t
//! and path parameter s, the joint speeds, and the interpolation rule and certified region as data.
inline constexpr const char* kBoundsFormat = "leeway-bounds-2";
//! The format before it (no times), still read.
inline constexpr const char* kBoundsFormat1 = "leeway-bounds-1";

//! True when `format` is a bounds file format leeway reads (kBoundsFormat or kBoundsFormat1).
bool is_bounds_format(const nlohmann::json& format);

//! Refuses JSON that is not a bounds file, naming what it lacks: an object with 'joints' and
//! 'waypoints' and, when it has a 'format' (older files have none), one is_bounds_format accepts.
//! @throws InputError "PATH: not a leeway bounds file: ...".
void require_bounds_shape(const nlohmann::json& j, const std::string& path);

//! The bounds file (docs/cli.md): joints, waypoints (q, lower, upper), boxes, max_cells, timing_ms...
nlohmann::json bounds_json(const Scene& scene, const BoundsRun& run, const Params& params);

//! The room record of a bounds file (docs/algorithm.md, "Room"): what the measure is, per joint the
//! share of its one-joint free range kept (names as keys), their mean, and per waypoint the free
//! ranges, the shares and the tool's room. An undefined share is null. (Its time goes to timing_ms.)
nlohmann::json room_json(const Scene& scene, const RoomReport& room, const RoomOptions& options);

//! Reads a bounds file written for `scene`: q, lower, upper and collapsed of every waypoint (the
//! guide bounds and checks are not read). A file without "format" is accepted (older files).
//! @throws InputError naming the file and the mismatch (a "format" other than kBoundsFormat, other
//! joints, wrong sizes, NaN, lower > upper, nominal outside its bounds, an unknown collapsed joint).
std::vector<WaypointBounds> read_bounds(const std::string& path, const Scene& scene);

//! Reads a bounds file as a trajectory for `scene`: read_bounds(), then each waypoint's time from the
//! file (format 2) or from the scene's joint speeds (format 1 and older, which have none).
//! @throws InputError as read_bounds, and on a format-2 waypoint whose t is missing, not finite or
//! before the previous one, or whose s is not its index.
BoundsTrajectory read_bounds_trajectory(const std::string& path, const Scene& scene);

//! A bounds file read without its cell: the joint names, the cell's file name as recorded, and the
//! trajectory. Needs format 2 (its own times); the joint limits are not checked (no robot).
struct BoundsFile {
  std::vector<std::string> joints;
  std::string cell;
  BoundsTrajectory trajectory;
};

//! Reads a format-2 bounds file without its cell (BoundsFile).
//! @throws InputError as read_bounds_trajectory, and on a file without times (format 1).
BoundsFile read_bounds_file(const std::string& path);

}  // namespace leeway
