#pragma once
//! @file params.hpp
//! Every parameter of the joint-boundary algorithm in one plain struct, with JSON I/O.
//! The height function's defaults are the thesis's (section 4.1) in SI units; the others are
//! leeway's choices. docs/algorithm.md documents each and where it comes from.

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "leeway/core/numbers.hpp"

namespace leeway {

//! How the height function measures the distance from a cell to a box.
enum class DistanceMode {
  kPlane,  //!< in the floor plane, from the cell centre to the box's footprint (default)
  k3d,     //!< in 3D, from the cell centre on the floor (z = 0) to the box
};

//! The largest accepted height_map.max_cells: a million cells of 8-byte heights is 8 MB and a
//! million candidate boxes, beyond any cell we have measured (docs/tuning.md tops out at 20000).
//! Params::validate, make_grid and the programs' options all check against this one value.
constexpr int kMaxCellsLimit = 1000000;

//! The smallest height-map side and reach radius [m]: below it the map's cell size underflows.
constexpr double kMinMapSide = 1e-3;
//! The smallest Algorithm-1 descent step 'categorize.goal_dz' [m] (smaller ones run for ever).
constexpr double kMinGoalDz = 1e-5;
//! The smallest Algorithm-2 step 'bounds.resolution' [rad] (smaller ones run for ever).
constexpr double kMinResolution = 1e-6;
//! The most joints 'bounds.bisect' may name: Algorithm 3 bounds the k-th bisected joint from 2^(k-1)
//! bases, so the sixth takes 64 Algorithm-2 runs and a seventh would double that again.
constexpr int kMaxBisected = 6;

//! The height-map of section 3.2.1.
struct HeightMapParams {
  //! When true, the map is the rectangle covering every floor point within reach_radius of every
  //! arm-base position along the path (cells beyond reach hold no box anyway); origin_x/origin_y/
  //! x_dim/y_dim are then ignored.
  bool auto_extent = true;
  double origin_x = 0.0;  //!< lower-left corner of the map [m]
  double origin_y = 0.0;  //!< [m]
  double x_dim = 0.0;     //!< map size along x [m]
  double y_dim = 0.0;     //!< map size along y [m]
  int max_cells = 20000;  //!< MAX_cells: side = sqrt(x_dim * y_dim / MAX_cells); 1..kMaxCellsLimit
};

//! The height function, eq. 3.1 with the goal term of eq. 4.1, and the activation A_t.
struct VolumeParams {
  double d_t_lb = 0.35;            //!< trail term lower bound [m]
  double d_t_ub = 1.50;            //!< trail term upper bound [m]
  double d_g_lb = 0.10;            //!< goal term lower bound [m]
  double d_g_ub = 2.00;            //!< goal term upper bound [m]
  double d_ng_ub = 0.50;           //!< non-goal obstacle term upper bound [m]
  double h_max = 1.50;             //!< largest contribution of one term [m]
  double alpha_t = 1.0;            //!< exponent of the trail term
  double alpha_g = 1.0;            //!< exponent of the goal term
  double alpha_ng = 1.0;           //!< exponent of the non-goal term
  bool goal_constant_term = true;  //!< eq. 4.1: h_max/3 + 2/3 h_max (...)^alpha_g instead of eq. 3.1's term
  double reach_radius = 2.8;       //!< A_t = 0 beyond this distance from the arm's base [m] (DLR: 3.0)
  //! A_t = 0 also where the max-height box comes within this distance of a trail box (the trail
  //! box grown by it on every side) [m]. 0 is section 4.1's test, "right below the trail"; a
  //! positive value reads section 3.2.2's "too close to the trail" as a clearance (docs/algorithm.md).
  double trail_margin = 0.0;
  bool add_obstacle_boxes = false;  //!< DLR option: the obstacles' own boxes join the volume
  DistanceMode distance = DistanceMode::kPlane;
};

//! Categorisation (section 3.1).
struct CategorizeParams {
  double goal_dz = 0.01;  //!< Algorithm 1 descent step ΔZ [m]
  int trail_densify = 0;  //!< extra trail poses per path segment (0: waypoints only, as the thesis)
};

//! Bounding (section 3.3).
struct BoundsParams {
  double resolution = 0.01;  //!< Algorithm 2's Δ [rad] (only hinge joints are bisected)
  //! Collapse guard (section 3.3): a bisected joint whose interval came out narrower than
  //! `resolution` (lower = upper = nominal) gets nominal +- this, clamped to its limits [rad or m]
  double min_half_width = 0.01;
  //! fixed half-width around nominal of every hinge joint that is not bisected (the wrist) [rad]
  double wrist_half_width = 0.2;
  double linear_axis_tolerance = 0.03;  //!< slide joints: half-width as a fraction of the joint's range
  //! The hinge joints Algorithm 3 bisects, by name; bounded in model order (base to tip) whatever the
  //! order here, at most kMaxBisected. Empty: the thesis's rule, the first three hinge joints.
  std::vector<std::string> bisect;
  //! Per-joint fixed half-width around nominal [rad or m], by joint name: replaces wrist_half_width
  //! for a hinge joint and linear_axis_tolerance x range for a slide joint. Bisected joints cannot be
  //! named.
  std::map<std::string, double> half_width;
  //! A probe where two robot geoms touch (Scene::self_pairs()) counts as colliding. Not in the
  //! thesis (false, its probes see the volume only); the leeway preset sets it.
  bool self_collision = false;
};

//! Confidence Factor (section 4.1).
struct CfParams {
  int windows = 30;        //!< the path is split into this many windows
  int samples = 10000;     //!< random configurations per window
  std::uint64_t seed = 1;  //!< RNG seed
  //! A sample counts as colliding when it hits an obstacle (the thesis's CF, false) or also when
  //! the robot hits itself (true). Both counts are reported either way.
  bool self = false;
};

//! How the bounds are made safe against the real obstacles after the volume-guided bisection.
enum class SafetyMode {
  kNone,       //!< the thesis's method as published: no check against the real obstacles
  kSampled,    //!< shrink until an (epsilon, delta) sampling test finds no collision
  kCertified,  //!< shrink until every waypoint box and segment is proven free (the default)
};

//! The repair stage (docs/algorithm.md, "Safe bounds").
struct SafetyParams {
  SafetyMode mode = SafetyMode::kCertified;
  double margin = 0.001;   //!< certified clearance between every link and every obstacle [m]
  int max_leaves = 16384;  //!< certificate's leaf budget per segment test
  double epsilon = 1e-4;   //!< sampled mode: tolerated collision share
  double delta = 0.05;     //!< sampled mode: the test passes a worse region with probability < delta
  std::uint64_t seed = 1;  //!< sampled mode: RNG seed
  //! Certified mode: the joints whose intervals grow beyond the guide once every segment is
  //! certified (docs/algorithm.md, "Growing"): "all", "none", or joint names separated by commas.
  std::string grow = "all";
  //! Certified mode: the largest half-width growth may give a joint, by joint name [rad or m];
  //! joints not named are limited by their free range and joint limits only.
  std::map<std::string, double> max_half_width;
  //! Certified mode: how growth shares the room between joints (docs/algorithm.md, "Growing"):
  //! "greedy" (rounds of a third, two thirds and all of every side's target, tip to base) or
  //! "lever" (one pass, the joint whose kept share costs the tool least motion first, each side
  //! straight to its target).
  std::string shape = "greedy";
  //! Certified mode: growth's leaf budgets (each slab's and each waypoint's or block's in all) as a
  //! multiple of their defaults; more buys room with time (docs/results.md, "Room for time").
  double grow_leaves = 1.0;
  //! Certified mode: before the rounds, a joint that turns last (the robot's last hinge, every geom
  //! it moves held by the pivot cylinder about it) grows straight to its target in one proof per
  //! side (docs/algorithm.md, "Growing beyond the guide", step 3); false: it grows in the rounds
  //! only, as every other joint.
  bool turn = true;
  //! Certified mode, dense paths: a warm segment inside its chain's run box (one proven box for up
  //! to 16 waypoints ahead) needs no proof of its own, and a chain does not retry a widening the
  //! certificate refused (docs/algorithm.md, "Run boxes"); false: every segment is proven on its
  //! own, as before.
  bool runs = true;
};

//! All parameters.
struct Params {
  HeightMapParams height_map;
  VolumeParams volume;
  CategorizeParams categorize;
  BoundsParams bounds;
  CfParams cf;
  SafetyParams safety;

  //! @throws InputError naming the parameter and value when one is out of range (NaN, negative
  //! lengths, LB >= UB, MAX_cells <= 0, ...).
  void validate() const;
};

//! The named parameter sets: "thesis" (section 4.1's height function at 20,000 cells, safety none:
//! the published method) and "leeway" (the parameters leeway-tune found for the nine thesis paths,
//! docs/tuning.md, with certified safety: the default). @throws InputError naming the preset.
Params preset_params(const std::string& name);

//! "none", "sampled" or "certified".
const char* safety_mode_name(SafetyMode mode);

//! The mode safety_mode_name() gives `name`. @throws InputError naming `what` (the flag, key or
//! file that gave it) and the value when it is none of the three.
SafetyMode parse_safety_mode(const std::string& name, const std::string& what);

//! Parameters as JSON (every field, SI units in the key documentation).
nlohmann::json to_json(const Params& p);
//! Parameters from JSON: missing keys keep their defaults, unknown keys are an error.
//! @throws InputError naming `source`, the key and the value.
//! Keys present in `j` override `base` (the defaults unless given).
Params params_from_json(const nlohmann::json& j, const std::string& source, const Params& base = Params{});
//! Reads and validates a parameter file. @throws InputError naming the file.
Params read_params(const std::string& path, const Params& base = Params{});

}  // namespace leeway
