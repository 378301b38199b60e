#pragma once
//! @file check.hpp
//! The scene checker: what an engineer authoring an MJCF cell wants to know before using it.

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "leeway/core/box.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! Options of the checker.
struct CheckOptions {
  double goal_dz = 0.01;            //!< Algorithm 1 descent step [m]
  double overlap_tolerance = 1e-4;  //!< obstacle overlaps deeper than this are reported [m]
  double reach_tolerance = 1e-3;    //!< a site is reachable when IK gets this close [m]
  std::uint64_t seed = 1;           //!< seed of the IK restarts
};

//! Findings for one keyframe.
struct KeyframeFindings {
  std::string name;
  Eigen::VectorXd q;
  Pose tool;
  std::vector<Contact> collisions;
  std::vector<SelfContact> self_collisions;  //!< robot geoms touching each other
  std::vector<int> limit_violations;         //!< joint indices
  Clearance clearance;                       //!< closest link-obstacle pair
};

//! Findings for one goal site.
struct GoalFindings {
  std::string site;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  int goal_obstacle = -1;            //!< geom id found by Algorithm 1, -1 when none lies below
  bool reachable = false;            //!< some configuration within limits puts the tool site there
  double reach_error = 0;            //!< closest approach of the tool site [m]
  bool reachable_tool_down = false;  //!< ... with the tool pointing down and collision-free
  Eigen::VectorXd q_tool_down;       //!< that configuration (when reachable_tool_down)
};

//! Overlapping pairs listed in a report (and as problems); the rest are counted.
inline constexpr size_t kMaxListedOverlaps = 100;

//! Two collidable geoms (obstacle-obstacle or obstacle-robot base) that overlap.
struct Overlap {
  int geom_a = -1;
  int geom_b = -1;
  double depth = 0;  //!< [m]
};

//! Everything the checker found. problems make the check fail; warnings do not.
struct CheckReport {
  std::vector<std::string> problems;
  std::vector<std::string> warnings;
  std::vector<KeyframeFindings> keyframes;
  std::vector<GoalFindings> goals;
  std::vector<Overlap> overlaps;  //!< the first kMaxListedOverlaps overlapping pairs, in index order
  size_t overlap_count = 0;       //!< every overlapping pair, listed or not
  bool ok() const { return problems.empty(); }
};

//! Runs every check on the scene. Deterministic for a given options.seed.
//! @throws InputError on bad options.
CheckReport check_scene(const Scene& scene, const CheckOptions& options = {});

//! The report as one JSON object (see docs/cli.md for the schema).
nlohmann::json to_json(const Scene& scene, const CheckReport& report);

//! The report as human-readable text (units in every number's label).
std::string to_text(const Scene& scene, const CheckReport& report);

//! World boxes of the scene's obstacles (in obstacle_geoms() order), at the model's rest pose.
std::vector<Box> obstacle_boxes(const Scene& scene);

}  // namespace leeway
