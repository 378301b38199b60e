#include "leeway/io/bounds_file.hpp"

#include <algorithm>
#include <cmath>

#include "core/json_io.hpp"
#include "leeway/core/confidence.hpp"
#include "leeway/core/error.hpp"

namespace leeway {

bool is_bounds_format(const nlohmann::json& format) {
  return format == nlohmann::json(kBoundsFormat) || format == nlohmann::json(kBoundsFormat1);
}

void require_bounds_shape(const nlohmann::json& j, const std::string& path) {
  const std::string expected = std::string("'format' ") + kBoundsFormat + ", 'joints' and 'waypoints'";
  if (!j.is_object())
    throw InputError(path + ": not a leeway bounds file: a JSON " + std::string(j.type_name()) +
                     ", not an object with " + expected);
  if (j.contains("format") && !is_bounds_format(j.at("format")))
    throw InputError(path + ": not a leeway bounds file: format " + j.at("format").dump() +
                     " (leeway reads " + kBoundsFormat + " and " + kBoundsFormat1 + ")");
  if (j.contains("joints") && j.contains("waypoints")) return;  // older files have no 'format'
  std::string missing;
  for (const char* key : {"format", "joints", "waypoints"})
    if (!j.contains(key)) missing += std::string(missing.empty() ? "no '" : ", no '") + key + "'";
  throw InputError(path + ": not a leeway bounds file: " + missing + " (a bounds file has " + expected + ")");
}

namespace {

// What the bounds promise, as data: the region proven free (certified mode) or that nothing is
// proven (sampled or none), and what a proof never covers.
nlohmann::json certified_region_json(const Scene& scene, const SafetyReport& report,
                                     const SafetyParams& params) {
  using nlohmann::json;
  json out = {{"mode", safety_mode_name(report.mode)}};
  if (report.mode != SafetyMode::kCertified) {
    out["proven"] = false;
    out["set"] = report.mode == SafetyMode::kSampled
                     ? "each segment passed a sampled test (safety.epsilon, safety.delta): not a proof"
                     : "nothing checked beyond the volume of boxes (the thesis's method)";
    return out;
  }
  out["proven"] = report.all_passed;
  out["set"] =
      "every q with lower(s) <= q <= upper(s), joint by joint, at every path parameter s in [0, N - 1] "
      "(bounds linear in s between waypoints)";
  out["margin"] = params.margin;
  out["pairs"] = {"link_obstacle", "self"};
  out["excluded_pairs"] = scene.excluded_pairs().size();
  out["not_covered"] = {
      "pairs the cell excludes (safety.pairs.excluded)",
      "pairs on one rigid part or on a parent and its child", "geometry beyond each geom's box",
      "dynamics: what a controller does between its own samples of s", "any q outside the bounds at its s"};
  return out;
}

}  // namespace

nlohmann::json safety_json(const Scene& scene, const SafetyReport& report, const SafetyParams& params) {
  using nlohmann::json;
  json segments = json::array();
  for (const auto& s : report.segments) {
    json j = {{"passed", s.passed}, {"shrink_steps", s.shrink_steps}};
    if (report.mode == SafetyMode::kCertified) {
      j["leaves"] = s.leaves;
      j["max_depth"] = s.max_depth;
      // Only when it happened: the key is new, and older files never ran out this way.
      if (s.budget_exhausted) j["budget_exhausted"] = true;
      if (s.run) j["run"] = true;
    } else {
      j["samples"] = s.samples;
      j["rounds"] = s.rounds;
    }
    segments.push_back(j);
  }
  json out = {{"mode", safety_mode_name(report.mode)}, {"segments", segments}};
  if (report.mode == SafetyMode::kCertified) {
    out["certified"] = report.all_passed;
    out["margin"] = params.margin;
    out["max_leaves"] = params.max_leaves;
    out["leaves"] = report.stats.leaves;
    out["max_depth"] = report.stats.max_depth;
    // What the certificate proved apart: every link against every obstacle, and the robot's own
    // pairs (Scene::self_pairs()); the pairs the cell excludes are listed, never proven.
    json excluded = json::array();
    for (const auto& e : scene.excluded_pairs())
      excluded.push_back({{"a", scene.geom_label(e.geom1)},
                          {"b", scene.geom_label(e.geom2)},
                          {"by", e.by_body ? "body exclude" : "leeway_exclude"}});
    out["pairs"] = {{"link_obstacle", scene.link_geoms().size() * scene.obstacle_geoms().size()},
                    {"self", scene.self_pairs().size()},
                    {"excluded", excluded}};
    // Growth beyond the guide (docs/algorithm.md, "Growing beyond the guide"); its leaves are in
    // `leaves` above too.
    out["grow"] = {{"joints", params.grow},
                   {"max_half_width", params.max_half_width},
                   {"ran", report.grow.ran},
                   {"grown", report.grow.grown},
                   {"leaves", report.grow.stats.leaves}};
    // Dense paths: the segments proven by run boxes (docs/algorithm.md, "Run boxes");
    // their leaves are in `leaves` above too.
    out["runs"] = {
        {"enabled", params.runs}, {"segments", report.run_segments}, {"leaves", report.run_leaves}};
  } else if (report.mode == SafetyMode::kSampled) {
    out["passed"] = report.all_passed;
    out["epsilon"] = params.epsilon;
    out["delta"] = params.delta;
    out["samples_per_segment"] = report.samples_per_segment;
    out["seed"] = params.seed;
  }
  return out;
}

nlohmann::json bounds_json(const Scene& scene, const BoundsRun& run, const Params& params) {
  using nlohmann::json;
  json out;
  out["format"] = kBoundsFormat;
  out["units"] = "SI: metres, radians, seconds (timing_ms in milliseconds, speeds in rad/s or m/s)";
  out["cell"] = scene.source();
  out["joints"] = scene.joint_names();
  json kinds = json::array();
  for (BoundKind k : bound_kinds(scene, params.bounds))
    kinds.push_back(k == BoundKind::kBisected ? "bisected"
                    : k == BoundKind::kFixed  ? "fixed"
                                              : "linear_axis");
  out["joint_bounding"] = kinds;
  const PathTiming timing = time_path(scene, run.bounds);
  json speeds = json::array();
  for (const auto& j : scene.joints()) speeds.push_back(j.max_speed);
  out["timing"] = {
      {"timed", timing.timed},
      {"duration", timing.total},
      {"joint_speeds", speeds},
      {"rule", timing.timed ? "each segment lasts as long as its slowest joint needs at its speed: "
                              "max over joints of |q_j(b) - q_j(a)| / speed_j"
                            : "a joint has no speed (0): each segment lasts 1 and t = s"}};
  out["interpolation"] = {
      {"parameter", "s"},
      {"waypoint_s", "the waypoint's index: s = i at waypoint i, s = i + f a fraction f of the way to i + 1"},
      {"between_waypoints", "linear in s, joint by joint, for q, lower and upper"},
      {"time", "t linear in s within each segment; the guarantee is in s, not in t"}};
  out["certified_region"] = certified_region_json(scene, run.safety, params.safety);
  json wps = json::array();
  for (size_t wi = 0; wi < run.bounds.size(); ++wi) {
    const WaypointBounds& w = run.bounds[wi];
    json collapsed = json::array();
    for (size_t i = 0; i < w.collapsed.size(); ++i)
      if (w.collapsed[i]) collapsed.push_back(scene.joints()[i].name);
    // Per joint: how much the safety stage took off the guide interval, and how much its growth
    // added beyond it [rad or m].
    json shrunk = json::object(), grown = json::object();
    for (Eigen::Index i = 0; i < w.lower.size(); ++i) {
      const auto [below, above] = w.shrunk_by(i);
      const std::string& name = scene.joints()[static_cast<size_t>(i)].name;
      if (below > 0 || above > 0)
        shrunk[name] = {{"lower_by", std::max(0.0, below)}, {"upper_by", std::max(0.0, above)}};
      if (below < 0 || above < 0)
        grown[name] = {{"lower_by", std::max(0.0, -below)}, {"upper_by", std::max(0.0, -above)}};
    }
    json wp = {{"t", timing.segment_start[wi]},
               {"s", static_cast<double>(wi)},
               {"q", detail::to_json_array(w.q)},
               {"lower", detail::to_json_array(w.lower)},
               {"upper", detail::to_json_array(w.upper)},
               {"collapsed", collapsed},
               {"shrunk", shrunk},
               {"guide_lower", detail::to_json_array(w.guide_lower)},
               {"guide_upper", detail::to_json_array(w.guide_upper)},
               {"nominal_in_volume", w.nominal_in_volume},
               {"checks", w.checks}};
    // Only the certified mode grows intervals.
    if (run.safety.mode == SafetyMode::kCertified) wp["grown"] = grown;
    wps.push_back(wp);
  }
  out["waypoints"] = wps;
  out["boxes"] = run.volume.boxes.size();
  out["max_cells"] = params.height_map.max_cells;
  out["grid"] = {{"origin", {run.volume.grid.origin_x, run.volume.grid.origin_y}},
                 {"side", run.volume.grid.side},
                 {"rows", run.volume.grid.rows},
                 {"cols", run.volume.grid.cols},
                 {"cells_under_trail", run.volume.cells_under_trail},
                 {"cells_out_of_reach", run.volume.cells_out_of_reach}};
  out["goal_obstacle"] =
      run.categories.goal_geom >= 0 ? json(scene.geom_label(run.categories.goal_geom)) : json(nullptr);
  out["trail_boxes"] = run.categories.trail.size();
  out["collision_checks"] = run.checks;
  out["safety"] = safety_json(scene, run.safety, params.safety);
  out["timing_ms"] = {{"categorize", run.ms_categorize}, {"volume", run.ms_volume},
                      {"inject", run.ms_inject},         {"bounds", run.ms_bounds},
                      {"safety", run.ms_safety},         {"total", run.ms_total()}};
  out["params"] = to_json(params);
  return out;
}

nlohmann::json room_json(const Scene& scene, const RoomReport& room, const RoomOptions& options) {
  using nlohmann::json;
  auto number = [](double v) { return std::isnan(v) ? json(nullptr) : json(v); };
  json shares = json::object();
  for (int i = 0; i < scene.dof(); ++i)
    shares[scene.joints()[static_cast<size_t>(i)].name] = number(room.joint_share[i]);
  json wps = json::array();
  for (const WaypointRoom& w : room.waypoints) {
    json lower = json::array(), upper = json::array(), share = json::array();
    for (size_t i = 0; i < w.free.size(); ++i) {
      lower.push_back(w.free[i].lower);
      upper.push_back(w.free[i].upper);
      share.push_back(number(w.share[static_cast<Eigen::Index>(i)]));
    }
    wps.push_back({{"waypoint", w.waypoint},
                   {"free_lower", lower},
                   {"free_upper", upper},
                   {"share", share},
                   {"tool_translation", w.tool_translation},
                   {"tool_rotation", w.tool_rotation}});
  }
  return {{"measure",
           "share: per joint and waypoint, (upper - lower) over the width of the one-joint free range "
           "[free_lower, free_upper] (the joint alone moved from its nominal value, the others at theirs, "
           "until the robot touches an obstacle or itself, within the joint's limits); joint_share: its "
           "mean over the waypoints; mean_share: the mean over the joints. tool_translation [m] and "
           "tool_rotation [rad]: the largest found over the box's corners and random configurations "
           "(sampled: a lower bound of the largest). A path of more than max_waypoints waypoints is measured "
           "at max_waypoints of them, evenly spaced (each entry's waypoint is its index)"},
          {"free_range_tolerance", options.tolerance},
          {"tool_samples", options.tool_samples},
          {"max_waypoints", options.max_waypoints},
          {"seed", options.seed},
          {"joint_share", shares},
          {"mean_share", number(room.mean_share)},
          {"waypoints", wps}};
}

namespace {

// The waypoints of a bounds file; with a scene, checked against its robot (joint names and limits).
std::vector<WaypointBounds> bounds_from_json(const nlohmann::json& j, const std::string& path,
                                             const Scene* scene) {
  auto fail = [&](const std::string& what) { throw InputError(path + ": " + what); };
  try {
    require_bounds_shape(j, path);
    const auto names = j.at("joints").get<std::vector<std::string>>();
    if (names.empty()) fail("'joints' is empty");
    if (scene && names != scene->joint_names()) {
      std::string listed;
      for (const auto& n : names) listed += (listed.empty() ? "" : " ") + n;
      fail("its joints '" + listed + "' do not match the robot in " + scene->source());
    }
    const int dof = static_cast<int>(names.size());
    std::vector<WaypointBounds> out;
    const auto& wps = j.at("waypoints");
    if (!wps.is_array() || wps.empty()) fail("'waypoints' must be a non-empty list");
    for (size_t i = 0; i < wps.size(); ++i) {
      WaypointBounds w;
      const std::string where = "waypoint " + std::to_string(i);
      for (const char* key : {"q", "lower", "upper"}) {
        const auto values = wps[i].at(key).get<std::vector<double>>();
        if (static_cast<int>(values.size()) != dof)
          fail(where + " '" + key + "' has " + std::to_string(values.size()) + " values, the robot has " +
               std::to_string(dof) + " joints");
        Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(values.data(), dof);
        if (std::string(key) == "q") w.q = v;
        if (std::string(key) == "lower") w.lower = v;
        if (std::string(key) == "upper") w.upper = v;
      }
      for (int k = 0; scene && k < dof; ++k) {
        const auto& joint = scene->joints()[static_cast<size_t>(k)];
        if (!(w.lower[k] >= joint.lower && w.upper[k] <= joint.upper))
          fail(where + " joint '" + joint.name + "': bounds [" + format_number(w.lower[k]) + ", " +
               format_number(w.upper[k]) + "] leave its limits [" + format_number(joint.lower) + ", " +
               format_number(joint.upper) + "]");
      }
      for (int k = 0; k < dof; ++k)
        if (!(w.lower[k] <= w.q[k] && w.q[k] <= w.upper[k]))
          fail(where + " joint '" + names[static_cast<size_t>(k)] + "': nominal " + format_number(w.q[k]) +
               " is not within [" + format_number(w.lower[k]) + ", " + format_number(w.upper[k]) + "]");
      w.collapsed.assign(static_cast<size_t>(dof), false);
      if (wps[i].contains("collapsed")) {
        // The names of the joints whose interval the collapse guard widened (bounds_json).
        for (const auto& name : wps[i].at("collapsed").get<std::vector<std::string>>()) {
          const auto it = std::find(names.begin(), names.end(), name);
          if (it == names.end()) fail(where + " 'collapsed' names '" + name + "', not a joint of the robot");
          w.collapsed[static_cast<size_t>(it - names.begin())] = true;
        }
      }
      out.push_back(std::move(w));
    }
    return out;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": unexpected content: " + e.what());
  }
}

// Format 2's times: one t per waypoint, from 0, non-decreasing; s equal to the index.
std::vector<double> times_from_json(const nlohmann::json& j, const std::string& path) {
  auto fail = [&](const std::string& what) { throw InputError(path + ": " + what); };
  const auto& wps = j.at("waypoints");
  std::vector<double> times;
  times.reserve(wps.size());
  try {
    for (size_t i = 0; i < wps.size(); ++i) {
      const std::string where = "waypoint " + std::to_string(i);
      if (!wps[i].contains("t")) fail(where + " has no 't' (format " + std::string(kBoundsFormat) + ")");
      const double t = wps[i].at("t").get<double>();
      if (!std::isfinite(t) || (i == 0 && t != 0) || (i > 0 && t < times.back()))
        fail(where + " 't' " + format_number(t) + " s: times start at 0 and never decrease");
      if (wps[i].contains("s") && wps[i].at("s").get<double>() != static_cast<double>(i))
        fail(where + " 's' " + format_number(wps[i].at("s").get<double>()) + " is not its index " +
             std::to_string(i));
      times.push_back(t);
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": unexpected content: " + e.what());
  }
  return times;
}

}  // namespace

std::vector<WaypointBounds> read_bounds(const std::string& path, const Scene& scene) {
  return bounds_from_json(detail::read_json_file(path, "bounds file"), path, &scene);
}

namespace {

// The trajectory of a parsed bounds file: format 2's own times, else (with a scene) the scene's.
BoundsTrajectory trajectory_from_json(const nlohmann::json& j, const std::string& path, const Scene* scene) {
  std::vector<WaypointBounds> bounds = bounds_from_json(j, path, scene);
  if (j.value("format", std::string()) != kBoundsFormat) {
    if (!scene)
      throw InputError(path + ": a bounds file without times (format " + kBoundsFormat1 +
                       " or older); give the cell to time it by its joint speeds, or write it again with "
                       "leeway bounds");
    return BoundsTrajectory(*scene, std::move(bounds));
  }
  std::vector<double> times = times_from_json(j, path);
  bool timed = true;
  try {
    timed = !j.contains("timing") || j.at("timing").value("timed", true);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": unexpected content: " + e.what());
  }
  try {
    return BoundsTrajectory(std::move(bounds), std::move(times), timed);
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  }
}

}  // namespace

BoundsTrajectory read_bounds_trajectory(const std::string& path, const Scene& scene) {
  return trajectory_from_json(detail::read_json_file(path, "bounds file"), path, &scene);
}

BoundsFile read_bounds_file(const std::string& path) {
  const nlohmann::json j = detail::read_json_file(path, "bounds file");
  BoundsTrajectory trajectory = trajectory_from_json(j, path, nullptr);
  std::string cell;
  try {
    cell = j.value("cell", std::string());
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": 'cell' is not a file name: " + e.what());
  }
  return {j.at("joints").get<std::vector<std::string>>(), cell, std::move(trajectory)};
}

}  // namespace leeway
