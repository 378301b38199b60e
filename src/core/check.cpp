#include "leeway/core/check.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <utility>

#include "json_io.hpp"
#include "leeway/core/categorize.hpp"
#include "leeway/core/cell_defaults.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/pipeline.hpp"

namespace leeway {
namespace {

// A mesh obstacle whose convex hull exceeds the mesh by more than this share of the hull is reported.
constexpr double kHullExcessWarning = 0.01;

std::string vec3(const Eigen::Vector3d& v) {
  return "(" + format_number(v.x()) + ", " + format_number(v.y()) + ", " + format_number(v.z()) + ")";
}

// Penetration depth [m] between two geoms, negative when they do not touch. Box pairs use our exact
// separating-axis depth: MuJoCo 2.2.2's box-box contact reports half the face penetration as dist
// (measured: two unit cubes overlapping by 0.1 m give dist = -0.05). Other pairs use the deepest
// contact of MuJoCo's narrowphase.
double penetration(const mjModel& m, const mjData& d, int g1, int g2) {
  if (m.geom_type[g1] == mjGEOM_BOX && m.geom_type[g2] == mjGEOM_BOX)
    return box_penetration(geom_box(m, d, g1), geom_box(m, d, g2));
  if (m.geom_type[g1] > m.geom_type[g2]) std::swap(g1, g2);
  mjfCollision f = mjCOLLISIONFUNC[m.geom_type[g1]][m.geom_type[g2]];
  if (!f) return -1;
  const bool has_sphere = m.geom_rbound[g1] > 0 && m.geom_rbound[g2] > 0;
  if (has_sphere) {
    const Eigen::Vector3d p1 = Eigen::Map<const Eigen::Vector3d>(d.geom_xpos + 3 * g1);
    const Eigen::Vector3d p2 = Eigen::Map<const Eigen::Vector3d>(d.geom_xpos + 3 * g2);
    if ((p1 - p2).norm() > m.geom_rbound[g1] + m.geom_rbound[g2]) return -1;
  }
  mjContact con[mjMAXCONPAIR];
  const int n = f(&m, &d, con, g1, g2, 0);
  double depth = -1;
  for (int i = 0; i < n; ++i) depth = std::max(depth, -static_cast<double>(con[i].dist));
  return depth;
}

bool is_box(const mjModel& m, int g) { return m.geom_type[g] == mjGEOM_BOX; }

// The volume [m^3] enclosed by triangles (three vertex indices each into `vertices`, 3 floats per
// vertex) by the divergence theorem: exact for a closed surface.
double enclosed_volume(const float* vertices, const int* faces, int count) {
  double six = 0;
  for (int f = 0; f < count; ++f) {
    Eigen::Vector3d v[3];
    for (int k = 0; k < 3; ++k) {
      const float* p = vertices + 3 * faces[3 * f + k];
      v[k] = Eigen::Vector3d(p[0], p[1], p[2]);
    }
    six += v[0].dot(v[1].cross(v[2]));
  }
  return std::abs(six) / 6;
}

// A mesh obstacle's convex hull (what MuJoCo collides) against the mesh itself: the volume the hull
// fills in beyond the mesh [m^3] and its share of the hull, when MuJoCo computed the hull.
std::optional<std::pair<double, double>> hull_excess(const mjModel& m, int g) {
  const int mesh = m.geom_dataid[g];
  const int graph = m.mesh_graphadr[mesh];
  if (graph < 0) return std::nullopt;
  const int numvert = m.mesh_graph[graph], numface = m.mesh_graph[graph + 1];
  const float* vertices = m.mesh_vert + 3 * m.mesh_vertadr[mesh];
  const double hull =
      enclosed_volume(vertices, m.mesh_graph + graph + 2 + 3 * numvert + 3 * numface, numface);
  const double solid =
      enclosed_volume(vertices, m.mesh_face + 3 * m.mesh_faceadr[mesh], m.mesh_facenum[mesh]);
  if (!(hull > 0)) return std::nullopt;
  const double excess = std::max(0.0, hull - solid);
  return std::make_pair(excess, excess / hull);
}

}  // namespace

std::vector<Box> obstacle_boxes(const Scene& scene) {
  const mjModel& m = scene.model();
  DataPtr d = make_data(m);
  mj_kinematics(&m, d.get());
  std::vector<Box> boxes;
  for (int g : scene.obstacle_geoms()) boxes.push_back(geom_box(m, *d, g));
  return boxes;
}

namespace {

// Obstacles: names, types, overlaps with each other and with the robot's fixed base.
void check_obstacles(const Scene& scene, const mjData& rest, const CheckOptions& options,
                     CheckReport& report) {
  const mjModel& m = scene.model();
  const auto& obstacles = scene.obstacle_geoms();
  if (obstacles.empty()) report.warnings.push_back("the cell has no obstacles");
  for (int g : obstacles) {
    if (object_name(m, mjOBJ_GEOM, g).empty())
      report.problems.push_back("obstacle " + scene.geom_label(g) +
                                " has no name: name every obstacle so results can refer to it");
    if (m.geom_type[g] == mjGEOM_PLANE)
      report.problems.push_back("obstacle " + scene.geom_label(g) +
                                " is a collidable plane: give the floor contype=\"0\" conaffinity=\"0\"");
    else if (m.geom_type[g] == mjGEOM_MESH)
      if (const auto excess = hull_excess(m, g); excess && excess->second > kHullExcessWarning)
        report.warnings.push_back(
            "obstacle " + scene.geom_label(g) +
            " is a mesh: MuJoCo and leeway collide its convex hull, which "
            "fills in " +
            format_number(excess->first) + " m^3 beyond the mesh (" +
            format_number(std::round(excess->second * 1000) / 10) +
            " % of the hull; room in its openings is lost): split it into convex pieces with leeway "
            "import-mesh (docs/mjcf-conventions.md, \"CAD meshes\")");
  }
  auto add_overlap = [&](int a, int b, const char* what) {
    const double depth = penetration(m, rest, a, b);
    if (depth > options.overlap_tolerance) {
      // Counted all, listed up to a limit: n coincident obstacles overlap in n (n - 1) / 2 pairs.
      if (++report.overlap_count > kMaxListedOverlaps) return;
      report.overlaps.push_back({a, b, depth});
      report.problems.push_back(std::string(what) + " '" + scene.geom_label(a) + "' and '" +
                                scene.geom_label(b) + "' overlap by " + format_number(depth) + " m");
    }
  };
  // Pairs in index order, as a double loop would visit them, but only those whose world AABBs meet
  // (a pair that overlaps by more than the tolerance >= 0 must): the midphase's grid keeps this
  // linear in the obstacles instead of quadratic.
  std::vector<Aabb> aabbs;
  for (int g : obstacles) aabbs.push_back(geom_aabb(m, rest, g));
  AabbGrid grid;
  grid.build(aabbs);
  std::vector<int> near;
  for (size_t i = 0; i < obstacles.size(); ++i) {
    near.clear();
    grid.any(aabbs[i], [&](int j) {
      if (static_cast<size_t>(j) > i) near.push_back(j);
      return false;
    });
    std::sort(near.begin(), near.end());
    for (int j : near) add_overlap(obstacles[i], obstacles[static_cast<size_t>(j)], "obstacles");
  }
  for (int o : obstacles)
    for (int b : scene.base_geoms()) add_overlap(o, b, "obstacle and robot base");
  if (report.overlap_count > kMaxListedOverlaps)
    report.problems.push_back("... and " + std::to_string(report.overlap_count - kMaxListedOverlaps) +
                              " more overlapping pairs (" + std::to_string(report.overlap_count) +
                              " in all; the first " + std::to_string(kMaxListedOverlaps) + " are listed)");
}

// Keyframes: collisions, self-collisions and joint limits.
void check_keyframes(const Scene& scene, RobotState& state, CheckReport& report) {
  if (scene.keyframes().empty()) report.warnings.push_back("the cell has no keyframes");
  for (const auto& k : scene.keyframes()) {
    KeyframeFindings f;
    f.name = k.name;
    f.q = k.q;
    f.collisions = state.contacts(k.q);
    f.self_collisions = state.self_contacts(k.q);
    f.tool = state.tool_pose();
    f.clearance = state.clearance(k.q);
    f.limit_violations = scene.joints_outside_limits(k.q);
    for (const auto& c : f.collisions)
      report.problems.push_back("keyframe '" + k.name + "': link '" + scene.geom_label(c.link_geom) +
                                "' collides with obstacle '" + scene.geom_label(c.obstacle_geom) +
                                "' (depth " + format_number(c.depth) + " m)");
    for (const auto& c : f.self_collisions)
      report.problems.push_back("keyframe '" + k.name + "': robot geoms '" + scene.geom_label(c.geom1) +
                                "' and '" + scene.geom_label(c.geom2) + "' collide (self-collision, depth " +
                                format_number(c.depth) +
                                " m); exclude the pair if it is an artefact of the "
                                "collision shapes (docs/mjcf-conventions.md)");
    for (int j : f.limit_violations) {
      const auto& joint = scene.joints()[static_cast<size_t>(j)];
      const char* unit = joint.prismatic ? " m" : " rad";
      report.problems.push_back("keyframe '" + k.name + "': joint '" + joint.name +
                                "' = " + format_number(k.q[j]) + unit + " is outside its range " +
                                format_number(joint.lower) + " .. " + format_number(joint.upper) + unit);
    }
    report.keyframes.push_back(std::move(f));
  }
}

// Goal sites: Algorithm 1 (a goal obstacle below each) and reach.
void check_goals(const Scene& scene, RobotState& state, const mjData& rest, const CheckOptions& options,
                 CheckReport& report) {
  const mjModel& m = scene.model();
  const auto& obstacles = scene.obstacle_geoms();
  // Algorithm 1 over the obstacles with a bounding box, as categorize() searches (the plane rule,
  // box.hpp): a collidable plane is reported above, not made every goal's obstacle.
  std::vector<Box> boxes;
  std::vector<int> box_geoms;
  for (int g : obstacles)
    if (has_bounding_box(m, g)) {
      boxes.push_back(geom_box(m, rest, g));
      box_geoms.push_back(g);
    }
  if (scene.goal_sites().empty()) report.warnings.push_back("the cell has no goal sites");
  const Eigen::VectorXd seed = default_ik_seed(scene);
  for (int s : scene.goal_sites()) {
    GoalFindings g;
    g.site = object_name(m, mjOBJ_SITE, s);
    if (g.site.empty()) g.site = "#" + std::to_string(s);
    g.position = Eigen::Map<const Eigen::Vector3d>(rest.site_xpos + 3 * s);
    const auto found = find_goal_obstacle(g.position, boxes, options.goal_dz);
    if (found) {
      g.goal_obstacle = box_geoms[*found];
    } else {
      report.problems.push_back("goal site '" + g.site + "' at " + vec3(g.position) +
                                " m: no obstacle lies below it (Algorithm 1), so it has no goal obstacle");
    }
    IkOptions ik;
    ik.seed = options.seed;
    ik.position_tolerance = options.reach_tolerance / 10;
    ik.tool_down = false;
    ik.require_collision_free = false;
    const IkResult pos = solve_ik(state, g.position, seed, ik);
    g.reach_error = pos.position_error;
    g.reachable = pos.position_error <= options.reach_tolerance;
    if (!g.reachable) {
      report.problems.push_back("goal site '" + g.site + "' at " + vec3(g.position) +
                                " m is outside the robot's reach: the tool site gets no closer than " +
                                format_number(g.reach_error) + " m within the joint limits");
    } else {
      ik.tool_down = true;
      ik.require_collision_free = true;
      const IkResult down = solve_ik(state, g.position, seed, ik);
      g.reachable_tool_down = down.success;
      if (down.success)
        g.q_tool_down = down.q;
      else
        report.warnings.push_back("goal site '" + g.site +
                                  "' is reachable, but not collision-free with the tool pointing down");
    }
    report.goals.push_back(std::move(g));
  }
}

}  // namespace

CheckReport check_scene(const Scene& scene, const CheckOptions& options) {
  if (!std::isfinite(options.overlap_tolerance) || options.overlap_tolerance < 0)
    throw InputError("overlap tolerance '" + format_number(options.overlap_tolerance) + "' must be >= 0 m");
  if (!std::isfinite(options.reach_tolerance) || options.reach_tolerance <= 0)
    throw InputError("reach tolerance '" + format_number(options.reach_tolerance) + "' must be > 0 m");
  if (!(options.goal_dz >= kMinGoalDz && options.goal_dz <= 10))
    throw InputError("goal descent step '" + format_number(options.goal_dz) + "' must be between " +
                     format_number(kMinGoalDz) + " and 10 m");
  // A cell `bounds` would refuse fails here too: its own parameters (custom numerics) against the
  // default preset's, and the preset's against its joints.
  Params cell_params = preset_params("leeway");
  apply_cell_defaults(scene, cell_params);
  validate_for_scene(cell_params, scene);
  CheckReport report;
  for (const std::string& option : scene.overridden_options())
    report.warnings.push_back("the cell's option " + option);
  RobotState state(scene);
  const mjModel& m = scene.model();
  DataPtr rest = make_data(m);  // the cell at rest: obstacles and sites where the model puts them
  mj_kinematics(&m, rest.get());
  check_obstacles(scene, *rest, options, report);
  check_keyframes(scene, state, report);
  check_goals(scene, state, *rest, options, report);
  return report;
}

nlohmann::json to_json(const Scene& scene, const CheckReport& report) {
  using nlohmann::json;
  const mjModel& m = scene.model();
  auto v3 = [](const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); };
  const auto vec = detail::to_json_array;
  json out;
  out["file"] = scene.source();
  out["units"] = "SI: metres, radians";
  out["ok"] = report.ok();
  out["problems"] = report.problems;
  out["warnings"] = report.warnings;
  json joints = json::array();
  for (const auto& j : scene.joints())
    joints.push_back({{"name", j.name},
                      {"type", j.prismatic ? "slide" : "hinge"},
                      {"lower", j.lower},
                      {"upper", j.upper},
                      {"max_speed", j.max_speed}});
  json links = json::array();
  for (int g : scene.link_geoms()) links.push_back(scene.geom_label(g));
  json base = json::array();
  for (int g : scene.base_geoms()) base.push_back(scene.geom_label(g));
  json excluded = json::array();
  for (const auto& e : scene.excluded_pairs())
    excluded.push_back({{"a", scene.geom_label(e.geom1)},
                        {"b", scene.geom_label(e.geom2)},
                        {"by", e.by_body ? "body exclude" : "leeway_exclude"}});
  out["robot"] = {{"root_body", object_name(m, mjOBJ_BODY, scene.robot_root_body())},
                  {"joints", joints},
                  {"link_geoms", links},
                  {"base_geoms", base},
                  {"self_pairs", scene.self_pairs().size()},
                  {"excluded_pairs", excluded},
                  {"tool_site", object_name(m, mjOBJ_SITE, scene.tool_site())}};
  const std::vector<Box> boxes = obstacle_boxes(scene);
  json obstacles = json::array();
  for (size_t i = 0; i < boxes.size(); ++i) {
    const int g = scene.obstacle_geoms()[i];
    const bool finite = boxes[i].half_size.allFinite();
    obstacles.push_back({{"name", scene.geom_label(g)},
                         {"box", is_box(m, g)},
                         {"center", v3(boxes[i].center)},
                         {"half_size", finite ? v3(boxes[i].half_size) : json(nullptr)}});
  }
  out["obstacles"] = obstacles;
  json keys = json::array();
  for (const auto& k : report.keyframes) {
    json col = json::array();
    for (const auto& c : k.collisions)
      col.push_back({{"link", scene.geom_label(c.link_geom)},
                     {"obstacle", scene.geom_label(c.obstacle_geom)},
                     {"depth", c.depth}});
    json self = json::array();
    for (const auto& c : k.self_collisions)
      self.push_back(
          {{"a", scene.geom_label(c.geom1)}, {"b", scene.geom_label(c.geom2)}, {"depth", c.depth}});
    json lim = json::array();
    for (int j : k.limit_violations) {
      const auto& joint = scene.joints()[static_cast<size_t>(j)];
      lim.push_back(
          {{"joint", joint.name}, {"value", k.q[j]}, {"lower", joint.lower}, {"upper", joint.upper}});
    }
    json clear = nullptr;
    if (k.clearance.link_geom >= 0)
      clear = {{"distance", k.clearance.distance},
               {"link", scene.geom_label(k.clearance.link_geom)},
               {"obstacle", scene.geom_label(k.clearance.obstacle_geom)}};
    keys.push_back({{"name", k.name},
                    {"q", vec(k.q)},
                    {"tool_position", v3(k.tool.position)},
                    {"collisions", col},
                    {"self_collisions", self},
                    {"limit_violations", lim},
                    {"clearance", clear}});
  }
  out["keyframes"] = keys;
  json goals = json::array();
  for (const auto& g : report.goals) {
    json item = {
        {"site", g.site},
        {"position", v3(g.position)},
        {"goal_obstacle", g.goal_obstacle >= 0 ? json(scene.geom_label(g.goal_obstacle)) : json(nullptr)},
        {"reachable", g.reachable},
        {"reach_error", g.reach_error},
        {"reachable_tool_down", g.reachable_tool_down}};
    item["q_tool_down"] = g.reachable_tool_down ? vec(g.q_tool_down) : json(nullptr);
    goals.push_back(item);
  }
  out["goals"] = goals;
  json overlaps = json::array();
  for (const auto& o : report.overlaps)
    overlaps.push_back(
        {{"a", scene.geom_label(o.geom_a)}, {"b", scene.geom_label(o.geom_b)}, {"depth", o.depth}});
  out["overlaps"] = overlaps;
  out["overlap_count"] = report.overlap_count;
  return out;
}

std::string to_text(const Scene& scene, const CheckReport& report) {
  const mjModel& m = scene.model();
  std::ostringstream os;
  os << scene.source() << " (units: metres, radians)\n";
  os << "robot: " << scene.dof() << " joints (";
  for (size_t i = 0; i < scene.joints().size(); ++i) os << (i ? " " : "") << scene.joints()[i].name;
  os << "), " << scene.link_geoms().size() << " link geoms, " << scene.base_geoms().size()
     << " base geoms, tool site '" << object_name(m, mjOBJ_SITE, scene.tool_site()) << "'\n";
  os << "self-collision: " << scene.self_pairs().size() << " robot geom pairs checked, "
     << scene.excluded_pairs().size() << " excluded by the cell\n";
  // A crowded cell (thousands of obstacles) would print one line of thousands of names: the text
  // names the first ones, --json lists every one.
  constexpr size_t kListedObstacles = 20;
  const auto& obstacles = scene.obstacle_geoms();
  os << "obstacles: " << obstacles.size() << " (";
  for (size_t i = 0; i < std::min(obstacles.size(), kListedObstacles); ++i)
    os << (i ? ", " : "") << scene.geom_label(obstacles[i]);
  if (obstacles.size() > kListedObstacles)
    os << ", ... and " << obstacles.size() - kListedObstacles << " more: --json lists them all";
  os << ")\n";
  for (const auto& k : report.keyframes) {
    os << "keyframe " << k.name << ": tool at " << vec3(k.tool.position) << " m, ";
    if (k.collisions.empty() && k.self_collisions.empty() && k.limit_violations.empty()) {
      os << "within limits, ";
      if (k.clearance.link_geom >= 0)
        os << "clearance " << format_number(k.clearance.distance) << " m ("
           << scene.geom_label(k.clearance.link_geom) << " to " << scene.geom_label(k.clearance.obstacle_geom)
           << ")\n";
      else
        os << "no obstacles\n";
    } else
      os << k.collisions.size() << " collision(s), " << k.self_collisions.size() << " self-collision(s), "
         << k.limit_violations.size() << " joint(s) outside limits\n";
  }
  for (const auto& g : report.goals) {
    os << "goal site " << g.site << " at " << vec3(g.position) << " m: goal obstacle "
       << (g.goal_obstacle >= 0 ? scene.geom_label(g.goal_obstacle) : std::string("none")) << ", "
       << (g.reachable ? (g.reachable_tool_down ? "reachable with the tool down" : "reachable")
                       : "out of reach by " + format_number(g.reach_error) + " m")
       << "\n";
  }
  for (const auto& w : report.warnings) os << "warning: " << w << "\n";
  for (const auto& p : report.problems) os << "problem: " << p << "\n";
  os << (report.ok() ? "check passed: no problems\n"
                     : "check FAILED: " + std::to_string(report.problems.size()) + " problem(s)\n");
  return os.str();
}

}  // namespace leeway
