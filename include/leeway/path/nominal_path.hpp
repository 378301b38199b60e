#pragma once
//! @file nominal_path.hpp
//! The nominal path from outside the planner: joint-linear between two keyframes, or read from a
//! path file (docs/planning.md), and the path file's format; and resolve_nominal_path(), the one
//! policy every command and the tuner use to get a checked nominal path.

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "leeway/core/scene.hpp"
#include "leeway/path/endpoints.hpp"
#include "leeway/path/path_check.hpp"
#include "leeway/path/planner.hpp"

namespace leeway {

//! A path between two keyframes: `waypoints` >= 2 configurations joined linearly in joint space
//! (the thesis's paths are its two end points). @throws InputError on unknown names or waypoints < 2.
std::vector<Eigen::VectorXd> keyframe_path(const Scene& scene, const std::string& from, const std::string& to,
                                           int waypoints);

//! The path file (docs/planning.md): format "leeway-path-1", units, cell, joints, waypoints (each
//! with q), from / to, planner settings and statistics.
nlohmann::json path_json(const Scene& scene, const PlanResult& result, const PlanOptions& options,
                         const Endpoint& from, const Endpoint& to);

//! Reads a path file (written by path_json) for `scene`.
//! @throws InputError naming the file and the mismatch: not a path file, other joints, fewer than
//! two waypoints, a wrong number of values, a value that is not a finite number, outside the limits.
std::vector<Eigen::VectorXd> read_path(const std::string& path, const Scene& scene);

//! What resolve_nominal_path() is asked for: a path file, or two path ends.
struct PathRequest {
  std::string file;      //!< a path file (read_path()); then from and to are not used
  std::string from, to;  //!< keyframes, "site:NAME" or "xyz:X,Y,Z"
  int waypoints = 2;     //!< joint-linear waypoints between two keyframes (>= 2)
  std::string ik_seed;   //!< keyframe seeding the IK of gripper goals ("" = resolve_endpoints()'s policy)
  PlanOptions plan;      //!< the planner, for gripper goals and for planning around
  //! A colliding straight path between two keyframes is planned around (RRT-Connect) when true,
  //! refused when false.
  bool plan_around = true;
  PathCheckOptions check;  //!< the dense check every path gets, whatever its source
};

//! Why resolve_nominal_path() gave no path.
enum class PathRefusal {
  kNone,         //!< a checked, collision-free path
  kCollision,    //!< the path (or a keyframe that cannot be planned around) collides
  kUnreachable,  //!< a gripper goal has no collision-free configuration with the tool down
  kNoPath,       //!< the planner found no path
};

//! A checked nominal path, or why there is none; what happened on the way, for outputs.
struct NominalPath {
  PathRefusal refusal = PathRefusal::kNone;
  //! The refusal in one line, without a prefix: "CELL: the straight path from home to patch hits
  //! 'wall' at s = 0.412 (...)". The commands print "leeway: <refusal_name()>: <message>".
  std::string message;
  std::vector<Eigen::VectorXd> waypoints;  //!< the checked path [rad, m] (empty when refused)
  //! "home -> patch", or the path file; "(planned around 'wall')" appended when it was.
  std::string label;
  bool linear = false;   //!< joint-linear between two keyframes was asked for
  bool planned = false;  //!< planned: between gripper goals, or around a colliding straight path
  //! Planned around a colliding straight path: one line saying what it hit and what replaced it.
  std::string replaced;
  //! The bounds file's `nominal_path` record: checked, resolution, slide_resolution, planned,
  //! checks, and replaced_straight_path when planned around.
  nlohmann::json record;
  bool ok() const { return refusal == PathRefusal::kNone; }
};

//! "collision", "unreachable" or "no path" ("" for kNone).
const char* refusal_name(PathRefusal refusal);

//! The nominal path a request names, checked densely (check_path()): read from the file, planned
//! between gripper goals, or joint-linear between two keyframes and planned around when it collides
//! (unless request.plan_around is false, or a keyframe is not free itself). A colliding, unreachable
//! or unplannable path is an outcome (`refusal`), not an error. Deterministic for a fixed plan seed.
//! @throws InputError on bad input: no path given, unknown keyframes or sites, waypoints < 2, a
//! malformed path file, or waypoints for a path that is not joint-linear.
NominalPath resolve_nominal_path(const Scene& scene, const PathRequest& request);

}  // namespace leeway
