#pragma once
//! @file bounds_file.hpp
//! The bounds file (docs/cli.md): writing it from a run and reading it back.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "leeway/bounds.hpp"
#include "leeway/params.hpp"
#include "leeway/pipeline.hpp"
#include "leeway/safety.hpp"
#include "leeway/scene.hpp"

namespace leeway {

//! The safety stage's record in a bounds file: mode, whether every segment passed, per segment
//! leaves/depth (certified) or samples/rounds (sampled), margin or epsilon, delta and N; certified:
//! the pairs proven apart (link-obstacle and self pairs, counted) and the excluded pairs by name.
nlohmann::json safety_json(const Scene& scene, const SafetyReport& report, const SafetyParams& params);

//! The "format" value of the bounds files bounds_json writes and read_bounds accepts.
inline constexpr const char* kBoundsFormat = "leeway-bounds-1";

//! The bounds file (docs/cli.md): joints, waypoints (q, lower, upper), boxes, max_cells, timing_ms...
nlohmann::json bounds_json(const Scene& scene, const BoundsRun& run, const Params& params);

//! Reads a bounds file written for `scene`: q, lower, upper and collapsed of every waypoint (the
//! guide bounds and checks are not read). A file without "format" is accepted (older files).
//! @throws InputError naming the file and the mismatch (a "format" other than kBoundsFormat, other
//! joints, wrong sizes, NaN, lower > upper, nominal outside its bounds, an unknown collapsed joint).
std::vector<WaypointBounds> read_bounds(const std::string& path, const Scene& scene);

}  // namespace leeway
