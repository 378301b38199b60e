#include "leeway/nominal_path.hpp"

#include <cmath>

#include <ompl/config.h>

#include "json_io.hpp"
#include "leeway/error.hpp"

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

}  // namespace leeway
