#include "leeway/path/nominal_path.hpp"

#include <cmath>
#include <optional>

#include <ompl/config.h>

#include "core/json_io.hpp"
#include "leeway/core/error.hpp"

namespace leeway {
namespace {

using nlohmann::json;

json endpoint_json(const Endpoint& e) {
  json out = {{"spec", e.spec}, {"q", detail::to_json_array(e.q)}};
  out["keyframe"] = e.keyframe.empty() ? json(nullptr) : json(e.keyframe);
  out["site"] = e.site.empty() ? json(nullptr) : json(e.site);
  out["position"] =
      e.keyframe.empty() ? json({e.position.x(), e.position.y(), e.position.z()}) : json(nullptr);
  return out;
}

}  // namespace

std::vector<Eigen::VectorXd> keyframe_path(const Scene& scene, const std::string& from, const std::string& to,
                                           int waypoints) {
  if (waypoints < 2)
    throw InputError("path from keyframe '" + from + "' to '" + to + "': waypoint count " +
                     std::to_string(waypoints) + " must be >= 2");
  const Eigen::VectorXd a = scene.keyframe(from).q, b = scene.keyframe(to).q;
  std::vector<Eigen::VectorXd> path;
  for (int i = 0; i < waypoints; ++i)
    path.push_back(a + (b - a) * (static_cast<double>(i) / (waypoints - 1)));
  return path;
}

json path_json(const Scene& scene, const PlanResult& result, const PlanOptions& options, const Endpoint& from,
               const Endpoint& to) {
  json out;
  out["format"] = "leeway-path-1";
  out["units"] = "SI: metres, radians, seconds";
  out["cell"] = scene.source();
  out["joints"] = scene.joint_names();
  json wps = json::array();
  for (const auto& q : result.waypoints) wps.push_back({{"q", detail::to_json_array(q)}});
  out["waypoints"] = wps;
  out["from"] = endpoint_json(from);
  out["to"] = endpoint_json(to);
  out["planner"] = {
      {"name", "RRTConnect"},
      {"library", "OMPL " + std::to_string(OMPL_MAJOR_VERSION) + "." + std::to_string(OMPL_MINOR_VERSION) +
                      "." + std::to_string(OMPL_PATCH_VERSION)},
      {"method", result.method},
      {"seed", options.seed},
      {"time_limit", options.time_limit},
      {"resolution", options.resolution},
      {"slide_resolution", options.slide_resolution},
      {"range", options.range},
      {"clearance", options.clearance},
      {"simplify", options.simplify},
      {"try_direct", options.try_direct}};
  out["simplified"] = result.simplified;
  out["raw_waypoints"] = result.raw_waypoints;
  out["length"] = result.length;
  out["collision_checks"] = result.checks;
  out["time"] = {{"plan", result.plan_seconds},
                 {"simplify", result.simplify_seconds},
                 {"total", result.plan_seconds + result.simplify_seconds}};
  return out;
}

std::vector<Eigen::VectorXd> read_path(const std::string& path, const Scene& scene) {
  const json j = detail::read_json_file(path, "path file");
  auto fail = [&](const std::string& what) { throw InputError(path + ": " + what); };
  try {
    if (!j.is_object() || !j.contains("joints") || !j.contains("waypoints"))
      fail("not a leeway path file (needs 'joints' and 'waypoints')");
    if (j.contains("format")) {
      const auto format = j.at("format").get<std::string>();
      if (format != "leeway-path-1" && format != "leeway-bounds-1" && format != "leeway-bounds-2")
        fail("format '" + format +
             "' is not a leeway path (leeway-path-1) or bounds file (leeway-bounds-1 or leeway-bounds-2)");
    }
    const auto names = j.at("joints").get<std::vector<std::string>>();
    if (names != scene.joint_names()) {
      auto list = [](const std::vector<std::string>& v) {
        std::string s;
        for (const auto& n : v) s += (s.empty() ? "" : " ") + n;
        return s;
      };
      fail("its joints '" + list(names) + "' do not match the robot in " + scene.source() + " ('" +
           list(scene.joint_names()) + "')");
    }
    const auto& wps = j.at("waypoints");
    if (!wps.is_array() || wps.size() < 2)
      fail("'waypoints' must be a list of at least two waypoints, got " +
           (wps.is_array() ? std::to_string(wps.size()) : std::string("a ") + wps.type_name()));
    std::vector<Eigen::VectorXd> out;
    for (size_t i = 0; i < wps.size(); ++i) {
      const std::string where = "waypoint " + std::to_string(i);
      if (!wps[i].is_object() || !wps[i].contains("q")) fail(where + " has no 'q'");
      const auto& values = wps[i].at("q");
      if (!values.is_array() || static_cast<int>(values.size()) != scene.dof())
        fail(where + " 'q' has " + (values.is_array() ? std::to_string(values.size()) : std::string("no")) +
             " values, the robot has " + std::to_string(scene.dof()) + " joints");
      Eigen::VectorXd q(scene.dof());
      for (int k = 0; k < scene.dof(); ++k) {
        const auto& v = values[static_cast<size_t>(k)];
        const RobotJoint& joint = scene.joints()[static_cast<size_t>(k)];
        if (!v.is_number() || !std::isfinite(v.get<double>()))
          fail(where + " joint '" + joint.name + "': " + v.dump() + " is not a finite number");
        q[k] = v.get<double>();
        if (q[k] < joint.lower || q[k] > joint.upper)
          fail(where + " joint '" + joint.name + "' = " + format_number(q[k]) +
               (joint.prismatic ? " m" : " rad") + " is outside its limits [" + format_number(joint.lower) +
               ", " + format_number(joint.upper) + "]");
      }
      out.push_back(std::move(q));
    }
    return out;
  } catch (const json::exception& e) {
    throw InputError(path + ": unexpected content: " + e.what());
  }
}

const char* refusal_name(PathRefusal refusal) {
  switch (refusal) {
    case PathRefusal::kNone:
      return "";
    case PathRefusal::kCollision:
      return "collision";
    case PathRefusal::kUnreachable:
      return "unreachable";
    case PathRefusal::kNoPath:
      return "no path";
  }
  return "";
}

namespace {

NominalPath refused(NominalPath out, PathRefusal refusal, std::string message) {
  out.refusal = refusal;
  out.message = std::move(message);
  out.waypoints.clear();
  return out;
}

// A straight path between two keyframes that collides: planned around unless the request says not
// to or a keyframe is not free itself. Fills `out` with the planned path and the record of what it
// replaced, or returns the refusal.
std::optional<NominalPath> plan_around(const Scene& scene, const PathRequest& r,
                                       const PathCheckResult& checked, std::vector<Eigen::VectorXd>& path,
                                       NominalPath& out) {
  const PathCollision hit = *checked.collision;
  const std::string what =
      "the straight path from " + r.from + " to " + r.to +
      (path.size() > 2 ? " (" + std::to_string(path.size()) + " waypoints)" : std::string()) + " " +
      describe_collision(scene, hit, true);
  // A keyframe that is not free itself cannot be planned around.
  std::string stuck;
  for (const auto& [key, q] : {std::pair{r.from, path.front()}, std::pair{r.to, path.back()}})
    if (stuck.empty() && !check_path(scene, {q}, r.check).free()) stuck = key;
  if (!r.plan_around || !stuck.empty())
    return refused(
        out, PathRefusal::kCollision,
        scene.source() + ": " + what +
            (stuck.empty() ? "" : "; keyframe '" + stuck + "' itself is not free, so no path avoids it"));
  PlanOptions around = r.plan;
  around.try_direct = false;  // the straight edge may pass the planner's coarser check
  const PlanResult planned =
      plan_path(scene, path.front(), path.back(), around, "start '" + r.from + "'", "goal '" + r.to + "'");
  if (!planned.success)
    return refused(out, PathRefusal::kNoPath, scene.source() + ": " + what + "; " + planned.message);
  out.replaced =
      what + "; planned a path with " + std::to_string(planned.waypoints.size()) +
      " waypoints (RRT-Connect, seed " + std::to_string(around.seed) + ")" +
      (path.size() > 2 ? ", which replaces the " + std::to_string(path.size()) + " straight waypoints"
                       : std::string());
  out.record["planned"] = true;
  out.record["replaced_straight_path"] = {
      {"from", r.from},
      {"to", r.to},
      {"waypoints", path.size()},
      {"obstacle", hit.obstacle_geom >= 0 && !hit.self ? json(hit.obstacle) : json(nullptr)},
      {"link", hit.link_geom >= 0 ? json(hit.link) : json(nullptr)},
      {"self", hit.self},
      {"self_with", hit.self ? json(hit.obstacle) : json(nullptr)},
      {"s", hit.path_fraction},
      {"depth", hit.depth},
      {"q", detail::to_json_array(hit.q)},
      {"checks", checked.checks},
      {"planner",
       {{"name", "RRTConnect"},
        {"seed", around.seed},
        {"time_limit", around.time_limit},
        {"resolution", around.resolution},
        {"slide_resolution", around.slide_resolution},
        {"waypoints", planned.waypoints.size()}}}};
  out.label += hit.self
                   ? " (planned around a self-collision of '" + hit.obstacle + "' and '" + hit.link + "')"
                   : " (planned around '" + hit.obstacle + "')";
  out.planned = true;
  path = planned.waypoints;
  return std::nullopt;
}

}  // namespace

NominalPath resolve_nominal_path(const Scene& scene, const PathRequest& r) {
  NominalPath out;
  out.linear = r.file.empty() && !is_gripper_goal(r.from) && !is_gripper_goal(r.to);
  std::vector<Eigen::VectorXd> path;
  if (!r.file.empty()) {
    path = read_path(r.file, scene);
    out.label = r.file;
  } else if (r.from.empty() || r.to.empty()) {
    throw InputError(scene.source() +
                     ": a nominal path needs a path file or two ends (keyframes, site:NAME or xyz:X,Y,Z)");
  } else if (out.linear) {
    path = keyframe_path(scene, r.from, r.to, r.waypoints);
    out.label = r.from + " -> " + r.to;
  } else {
    out.label = r.from + " -> " + r.to;
    EndpointOptions eo;
    eo.ik_seed_key = r.ik_seed;
    const auto [a, b] = resolve_endpoints(scene, r.from, r.to, eo);
    for (const Endpoint* e : {&a, &b})
      if (!e->reachable)
        return refused(out, PathRefusal::kUnreachable,
                       scene.source() + ": " + describe_unreachable(*e, e == &a));
    const PlanResult planned =
        plan_path(scene, a.q, b.q, r.plan, "start '" + r.from + "'", "goal '" + r.to + "'");
    if (!planned.success) return refused(out, PathRefusal::kNoPath, scene.source() + ": " + planned.message);
    path = planned.waypoints;
    out.planned = true;
  }
  // Checked densely whatever its source: the thesis's method (chapter 3) assumes the nominal path
  // collision-free (our reading).
  out.record = {{"checked", true},
                {"resolution", r.check.resolution},
                {"slide_resolution", r.check.slide_resolution},
                {"planned", out.planned}};
  PathCheckResult checked = check_path(scene, path, r.check);
  if (out.linear && !checked.free()) {
    if (auto refusal = plan_around(scene, r, checked, path, out)) return *refusal;
    checked = check_path(scene, path, r.check);
  }
  if (!checked.free()) {
    // A path file, or a planned path that passed the planner's coarser edge check.
    return refused(
        out, PathRefusal::kCollision,
        (r.file.empty() ? scene.source() : r.file) + ": " +
            (r.file.empty() ? "the path planned from " + r.from + " to " + r.to : std::string("the path")) +
            " " + describe_collision(scene, *checked.collision) +
            (out.planned ? " when checked at " + format_number(r.check.resolution) +
                               " rad (the planner checks at " + format_number(r.plan.resolution) + " rad)"
                         : std::string()));
  }
  out.record["checks"] = checked.checks;
  out.waypoints = std::move(path);
  return out;
}

}  // namespace leeway
