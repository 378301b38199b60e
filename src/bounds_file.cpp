#include "leeway/bounds_file.hpp"

#include <algorithm>

#include "json_io.hpp"
#include "leeway/error.hpp"

namespace leeway {

nlohmann::json safety_json(const Scene& scene, const SafetyReport& report, const SafetyParams& params) {
  using nlohmann::json;
  json segments = json::array();
  for (const auto& s : report.segments) {
    json j = {{"passed", s.passed}, {"shrink_steps", s.shrink_steps}};
    if (report.mode == SafetyMode::kCertified) {
      j["leaves"] = s.leaves;
      j["max_depth"] = s.max_depth;
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
  out["units"] = "SI: metres, radians, milliseconds";
  out["cell"] = scene.source();
  out["joints"] = scene.joint_names();
  json kinds = json::array();
  for (BoundKind k : bound_kinds(scene))
    kinds.push_back(k == BoundKind::kBisected ? "bisected"
                    : k == BoundKind::kFixed  ? "fixed"
                                              : "linear_axis");
  out["joint_bounding"] = kinds;
  json wps = json::array();
  for (const auto& w : run.bounds) {
    json collapsed = json::array();
    for (size_t i = 0; i < w.collapsed.size(); ++i)
      if (w.collapsed[i]) collapsed.push_back(scene.joints()[i].name);
    // Per joint: how much the safety stage took off the guide interval [rad or m].
    json shrunk = json::object();
    for (Eigen::Index i = 0; i < w.lower.size(); ++i) {
      const auto [below, above] = w.shrunk_by(i);
      if (below > 0 || above > 0)
        shrunk[scene.joints()[static_cast<size_t>(i)].name] = {{"lower_by", below}, {"upper_by", above}};
    }
    wps.push_back({{"q", detail::to_json_array(w.q)},
                   {"lower", detail::to_json_array(w.lower)},
                   {"upper", detail::to_json_array(w.upper)},
                   {"collapsed", collapsed},
                   {"shrunk", shrunk},
                   {"guide_lower", detail::to_json_array(w.guide_lower)},
                   {"guide_upper", detail::to_json_array(w.guide_upper)},
                   {"nominal_in_volume", w.nominal_in_volume},
                   {"checks", w.checks}});
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

std::vector<WaypointBounds> read_bounds(const std::string& path, const Scene& scene) {
  const nlohmann::json j = detail::read_json_file(path, "bounds file");
  auto fail = [&](const std::string& what) { throw InputError(path + ": " + what); };
  try {
    if (!j.is_object() || !j.contains("joints") || !j.contains("waypoints"))
      fail("not a leeway bounds file (needs 'joints' and 'waypoints')");
    // Older files have no 'format'; one that names another format is not ours to guess at.
    if (j.contains("format") && j.at("format") != nlohmann::json(kBoundsFormat))
      fail("format " + j.at("format").dump() + " is not a leeway bounds file (" + kBoundsFormat + ")");
    const auto names = j.at("joints").get<std::vector<std::string>>();
    if (names != scene.joint_names()) {
      std::string listed;
      for (const auto& n : names) listed += (listed.empty() ? "" : " ") + n;
      fail("its joints '" + listed + "' do not match the robot in " + scene.source());
    }
    std::vector<WaypointBounds> out;
    const auto& wps = j.at("waypoints");
    if (!wps.is_array() || wps.empty()) fail("'waypoints' must be a non-empty list");
    for (size_t i = 0; i < wps.size(); ++i) {
      WaypointBounds w;
      const std::string where = "waypoint " + std::to_string(i);
      for (const char* key : {"q", "lower", "upper"}) {
        const auto values = wps[i].at(key).get<std::vector<double>>();
        if (static_cast<int>(values.size()) != scene.dof())
          fail(where + " '" + key + "' has " + std::to_string(values.size()) + " values, the robot has " +
               std::to_string(scene.dof()) + " joints");
        Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(values.data(), scene.dof());
        if (std::string(key) == "q") w.q = v;
        if (std::string(key) == "lower") w.lower = v;
        if (std::string(key) == "upper") w.upper = v;
      }
      for (int k = 0; k < scene.dof(); ++k) {
        const auto& joint = scene.joints()[static_cast<size_t>(k)];
        if (!(w.lower[k] >= joint.lower && w.upper[k] <= joint.upper))
          fail(where + " joint '" + joint.name + "': bounds [" + format_number(w.lower[k]) + ", " +
               format_number(w.upper[k]) + "] leave its limits [" + format_number(joint.lower) + ", " +
               format_number(joint.upper) + "]");
      }
      for (int k = 0; k < scene.dof(); ++k)
        if (!(w.lower[k] <= w.q[k] && w.q[k] <= w.upper[k]))
          fail(where + " joint '" + names[static_cast<size_t>(k)] + "': nominal " + format_number(w.q[k]) +
               " is not within [" + format_number(w.lower[k]) + ", " + format_number(w.upper[k]) + "]");
      w.collapsed.assign(static_cast<size_t>(scene.dof()), false);
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

}  // namespace leeway
