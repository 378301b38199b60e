#pragma once
//! @file nominal_path.hpp
//! The nominal path from outside the planner: joint-linear between two keyframes, or read from a
//! path file (docs/planning.md), and the path file's format.

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "leeway/endpoints.hpp"
#include "leeway/planner.hpp"
#include "leeway/scene.hpp"

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

}  // namespace leeway
