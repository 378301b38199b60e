#include "leeway/viz/viewer.hpp"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "leeway/core/error.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/shape.hpp"
#include "leeway/viz/render.hpp"

#ifndef LEEWAY_THREE_DIR
#define LEEWAY_THREE_DIR "/usr/share/javascript/three"
#endif

namespace leeway {
namespace detail {
extern const char* const kViewerPage;
}  // namespace detail

namespace {

using nlohmann::json;

// --frame robot's margin: obstacles within this of the robot's reach along the path [m] are framed.
constexpr double kNearObstacles = 0.3;
// At most this many configurations are posed to find the robot's extent along the path.
constexpr long kFramedConfigurations = 240;

// Base64 (RFC 4648, with padding) of raw bytes.
std::string base64(const unsigned char* bytes, size_t n) {
  static const char* const kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((n + 2) / 3 * 4);
  for (size_t i = 0; i < n; i += 3) {
    const unsigned v = static_cast<unsigned>(bytes[i]) << 16 | (i + 1 < n ? bytes[i + 1] << 8 : 0) |
                       (i + 2 < n ? bytes[i + 2] : 0);
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out.push_back(i + 1 < n ? kAlphabet[(v >> 6) & 63] : '=');
    out.push_back(i + 2 < n ? kAlphabet[v & 63] : '=');
  }
  return out;
}

// Little-endian bytes of numbers (x86 and ARM are little-endian, as the browsers' typed arrays).
template <typename T>
std::string base64_of(const std::vector<T>& values) {
  return base64(reinterpret_cast<const unsigned char*>(values.data()), values.size() * sizeof(T));
}

json vec3(const double* v) { return json::array({v[0], v[1], v[2]}); }
json quat(const double* v) { return json::array({v[0], v[1], v[2], v[3]}); }

const char* geom_type_name(int type) {
  switch (type) {
    case mjGEOM_PLANE:
      return "plane";
    case mjGEOM_SPHERE:
      return "sphere";
    case mjGEOM_CAPSULE:
      return "capsule";
    case mjGEOM_ELLIPSOID:
      return "ellipsoid";
    case mjGEOM_CYLINDER:
      return "cylinder";
    case mjGEOM_BOX:
      return "box";
    case mjGEOM_MESH:
      return "mesh";
    default:
      return nullptr;  // height fields and others: not drawn
  }
}

// The colour MuJoCo's visualiser gives a geom: its material's when it has one and its own rgba is
// MuJoCo's default, else its own.
json geom_rgba(const mjModel& m, int g) {
  const float* own = m.geom_rgba + 4 * g;
  const bool default_rgba = own[0] == 0.5f && own[1] == 0.5f && own[2] == 0.5f && own[3] == 1.0f;
  const float* c = m.geom_matid[g] >= 0 && default_rgba ? m.mat_rgba + 4 * m.geom_matid[g] : own;
  return json::array({c[0], c[1], c[2], c[3]});
}

// Bodies with their joints: the tree the page poses with three.js groups as mj_kinematics does.
json bodies_json(const Scene& scene) {
  const mjModel& m = scene.model();
  std::vector<int> joint_index(static_cast<size_t>(m.njnt), -1);
  for (size_t k = 0; k < scene.joints().size(); ++k)
    joint_index[static_cast<size_t>(scene.joints()[k].id)] = static_cast<int>(k);
  json bodies = json::array();
  for (int b = 0; b < m.nbody; ++b) {
    json joints = json::array();
    for (int j = m.body_jntadr[b]; j >= 0 && j < m.body_jntadr[b] + m.body_jntnum[b]; ++j) {
      if (m.jnt_type[j] != mjJNT_HINGE && m.jnt_type[j] != mjJNT_SLIDE) continue;  // not a robot joint
      joints.push_back({{"type", m.jnt_type[j] == mjJNT_HINGE ? "hinge" : "slide"},
                        {"axis", vec3(m.jnt_axis + 3 * j)},
                        {"pos", vec3(m.jnt_pos + 3 * j)},
                        {"index", joint_index[static_cast<size_t>(j)]},
                        {"ref", m.qpos0[m.jnt_qposadr[j]]}});
    }
    bodies.push_back({{"parent", b == 0 ? -1 : m.body_parentid[b]},
                      {"pos", vec3(m.body_pos + 3 * b)},
                      {"quat", quat(m.body_quat + 4 * b)},
                      {"joints", joints}});
  }
  return bodies;
}

// Geoms MuJoCo's viewer shows by default (groups 0-2, not fully transparent), with their role in
// leeway: a robot link (coloured by clearance), the robot's base, an obstacle, or only visual.
json geoms_json(const Scene& scene, json& meshes, long& drawn) {
  const mjModel& m = scene.model();
  auto in = [](const std::vector<int>& list, int g) {
    return std::find(list.begin(), list.end(), g) != list.end();
  };
  std::vector<int> mesh_index(static_cast<size_t>(m.nmesh), -1);
  json geoms = json::array();
  for (int g = 0; g < m.ngeom; ++g) {
    const char* type = geom_type_name(m.geom_type[g]);
    if (!type || m.geom_group[g] > 2 || geom_rgba(m, g)[3].get<double>() <= 0) continue;
    const auto link = std::find(scene.link_geoms().begin(), scene.link_geoms().end(), g);
    const bool moving = in(scene.moving_bodies(), m.geom_bodyid[g]);
    json geom = {{"body", m.geom_bodyid[g]},
                 {"type", type},
                 {"size", vec3(m.geom_size + 3 * g)},
                 {"pos", vec3(m.geom_pos + 3 * g)},
                 {"quat", quat(m.geom_quat + 4 * g)},
                 {"rgba", geom_rgba(m, g)},
                 {"moving", moving},
                 {"role", link != scene.link_geoms().end() ? "link"
                          : in(scene.base_geoms(), g)      ? "base"
                          : in(scene.obstacle_geoms(), g)  ? "obstacle"
                                                           : "visual"},
                 {"link", link != scene.link_geoms().end() ? link - scene.link_geoms().begin() : -1}};
    if (m.geom_type[g] == mjGEOM_MESH) {
      const int id = m.geom_dataid[g];
      if (mesh_index[static_cast<size_t>(id)] < 0) {
        mesh_index[static_cast<size_t>(id)] = static_cast<int>(meshes.size());
        const std::vector<float> vert(m.mesh_vert + 3 * m.mesh_vertadr[id],
                                      m.mesh_vert + 3 * (m.mesh_vertadr[id] + m.mesh_vertnum[id]));
        const std::vector<std::int32_t> face(m.mesh_face + 3 * m.mesh_faceadr[id],
                                             m.mesh_face + 3 * (m.mesh_faceadr[id] + m.mesh_facenum[id]));
        meshes.push_back({{"vert", base64_of(vert)}, {"face", base64_of(face)}});
      }
      geom["mesh"] = mesh_index[static_cast<size_t>(id)];
    }
    geoms.push_back(std::move(geom));
    ++drawn;
  }
  return geoms;
}

// Each link's clearance [m] to the obstacles at q, as RobotState::clearance measures the closest
// pair (the shapes as MuJoCo collides them, shape.hpp; planes skipped).
void link_clearances(const Scene& scene, const mjData& d, const std::vector<Shape>& obstacles,
                     std::vector<float>& out) {
  const mjModel& m = scene.model();
  for (int l : scene.link_geoms()) {
    const Shape link = geom_shape(m, d, l);
    const Eigen::AlignedBox3d around = aligned(link.box);
    double best = INFINITY;
    for (const Shape& o : obstacles) {
      // The distance between the aligned boxes is a lower bound: skip pairs that cannot be closer.
      const Eigen::AlignedBox3d ob = aligned(o.box);
      const Eigen::Vector3d gap =
          (ob.min() - around.max()).cwiseMax(around.min() - ob.max()).cwiseMax(Eigen::Vector3d::Zero());
      if (gap.norm() >= best) continue;
      best = std::min(best, shape_distance(link, o));
    }
    out.push_back(static_cast<float>(std::isfinite(best) ? best : -1.0));  // -1: no obstacle
  }
}

// The path sampled at the slider's stops: times, nominal values, bounds, the tool's position and
// each link's clearance at the nominal configuration.
json path_json(const Scene& scene, const BoundsTrajectory& path, const ViewerOptions& options,
               Eigen::AlignedBox3d& robot) {
  const double dt = std::max(options.dt, path.duration() / (kMaxViewerSamples - 1));
  const std::vector<BoundsStage> stages =
      path.duration() > 0 ? path.sample(dt) : std::vector<BoundsStage>{path.at_s(0)};
  const mjModel& m = scene.model();
  DataPtr d = make_data(m);
  mj_kinematics(&m, d.get());
  std::vector<Shape> obstacles;
  for (int o : scene.obstacle_geoms())
    if (has_bounding_box(m, o)) obstacles.push_back(geom_shape(m, *d, o));
  std::vector<double> t, s, nominal, lower, upper;
  std::vector<float> tool, clearance;
  std::vector<Eigen::VectorXd> framed;
  const long every = std::max<long>(1, static_cast<long>(stages.size()) / (kFramedConfigurations / 3));
  for (size_t i = 0; i < stages.size(); ++i) {
    const BoundsStage& st = stages[i];
    t.push_back(st.t);
    s.push_back(st.s);
    for (int k = 0; k < path.dof(); ++k) {
      nominal.push_back(st.nominal[k]);
      lower.push_back(st.lower[k]);
      upper.push_back(st.upper[k]);
    }
    scene.set_qpos(*d, st.nominal);
    mj_kinematics(&m, d.get());
    for (int c = 0; c < 3; ++c) tool.push_back(static_cast<float>(d->site_xpos[3 * scene.tool_site() + c]));
    link_clearances(scene, *d, obstacles, clearance);
    if (static_cast<long>(i) % every == 0 || i + 1 == stages.size())
      framed.insert(framed.end(), {st.nominal, st.lower, st.upper});
  }
  robot = robot_extent(scene, framed);
  return {{"timed", path.timed()},
          {"duration", path.duration()},
          {"waypoints", path.waypoint_count()},
          {"dt", dt},
          {"count", stages.size()},
          {"t", base64_of(t)},
          {"s", base64_of(s)},
          {"nominal", base64_of(nominal)},
          {"lower", base64_of(lower)},
          {"upper", base64_of(upper)},
          {"tool", base64_of(tool)},
          {"links", scene.link_geoms().size()},
          {"clearance", base64_of(clearance)}};
}

// The volume: centre and half size of every box (float32), its colour by the height of its top
// (as leeway render colours it), and its orientation when any box is not axis-aligned.
json volume_json(const std::vector<Box>& boxes) {
  const double max_top = highest_top(boxes);
  std::vector<float> geometry;
  std::vector<unsigned char> colour;
  std::vector<float> rotation;
  bool rotated = false;
  geometry.reserve(6 * boxes.size());
  colour.reserve(3 * boxes.size());
  for (const Box& b : boxes) {
    for (int k = 0; k < 3; ++k) geometry.push_back(static_cast<float>(b.center[k]));
    for (int k = 0; k < 3; ++k) geometry.push_back(static_cast<float>(b.half_size[k]));
    const auto c = height_colour(b.center.z() + b.half_size.z(), max_top);
    for (float v : c)
      colour.push_back(static_cast<unsigned char>(std::lround(255 * std::clamp(v, 0.0f, 1.0f))));
    rotated = rotated || !b.rotation.isIdentity(0);
  }
  // The colour scale, for the page's legend: 9 stops from 0 to the highest top.
  json scale = json::array();
  for (int i = 0; i <= 8; ++i) scale.push_back(height_colour(max_top * i / 8, max_top));
  json out = {{"count", boxes.size()},
              {"max_top", max_top},
              {"scale", scale},
              {"boxes", base64_of(geometry)},
              {"colour", base64(colour.data(), colour.size())}};
  if (rotated) {
    for (const Box& b : boxes) {
      const Eigen::Quaterniond q(b.rotation);
      for (double v : {q.w(), q.x(), q.y(), q.z()}) rotation.push_back(static_cast<float>(v));
    }
    out["rotation"] = base64_of(rotation);
  }
  return out;
}

// The files of libjs-three the page inlines.
constexpr const char* kThreeJs = "three.min.js";
constexpr const char* kOrbitControls = "examples/js/controls/OrbitControls.js";

InputError three_js_missing(const std::string& path) {
  return InputError(path +
                    ": three.js is not there (Debian: apt-get install libjs-three; or set "
                    "LEEWAY_THREE_DIR to the folder holding three.min.js)");
}

std::string read_asset(const std::string& dir, const std::string& name) {
  const std::string path = dir + "/" + name;
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  if (!in || !(text << in.rdbuf())) throw three_js_missing(path);
  return text.str();
}

// Text placed inside a <script> element: "</" would end it early.
std::string script_safe(std::string text) {
  for (size_t at = text.find("</"); at != std::string::npos; at = text.find("</", at + 3))
    text.replace(at, 2, "<\\/");
  return text;
}

void replace_once(std::string& page, const std::string& marker, const std::string& text) {
  const size_t at = page.find(marker);
  if (at == std::string::npos) throw std::logic_error("viewer page template lacks " + marker);
  page.replace(at, marker.size(), text);
}

// three.js's licence (MIT), as its LICENSE file in the release Debian packages (r111).
constexpr const char* kThreeLicence =
    "three.js r111, from Debian's libjs-three. The MIT License. Copyright (c) 2010-2019 three.js authors.\n"
    "Permission is hereby granted, free of charge, to any person obtaining a copy of this software and\n"
    "associated documentation files (the \"Software\"), to deal in the Software without restriction,\n"
    "including without limitation the rights to use, copy, modify, merge, publish, distribute,\n"
    "sublicense, and/or sell copies of the Software, and to permit persons to whom the Software is\n"
    "furnished to do so, subject to the following conditions: The above copyright notice and this\n"
    "permission notice shall be included in all copies or substantial portions of the Software.\n"
    "THE SOFTWARE IS PROVIDED \"AS IS\", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR IMPLIED, INCLUDING BUT\n"
    "NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY, FITNESS FOR A PARTICULAR PURPOSE AND\n"
    "NONINFRINGEMENT. IN NO EVENT SHALL THE AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM,\n"
    "DAMAGES OR OTHER LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM, OUT\n"
    "OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE SOFTWARE.";

}  // namespace

std::string default_three_dir() {
  const char* env = std::getenv("LEEWAY_THREE_DIR");
  return env && *env ? env : LEEWAY_THREE_DIR;
}

void require_three_js(const std::string& dir) {
  for (const char* name : {kThreeJs, kOrbitControls})
    if (!std::ifstream(dir + "/" + name)) throw three_js_missing(dir + "/" + name);
}

std::string viewer_data_json(const Scene& scene, const ViewerContent& content, const ViewerOptions& options) {
  long drawn = static_cast<long>(content.volume.size());
  if (drawn > options.max_boxes)
    throw InputError("the volume has " + std::to_string(drawn) + " boxes, more than the viewer's limit of " +
                     std::to_string(options.max_boxes) +
                     " (--max-boxes; a thinned volume would show room that is not there: lower --max-cells)");
  json meshes = json::array();
  json geoms = geoms_json(scene, meshes, drawn);
  if (drawn > options.max_boxes)
    throw InputError("the cell and its volume have " + std::to_string(drawn) +
                     " geoms and boxes, more than the viewer's limit of " +
                     std::to_string(options.max_boxes) + " (--max-boxes)");
  json joints = json::array();
  for (const auto& j : scene.joints())
    joints.push_back({{"name", j.name}, {"unit", j.prismatic ? "m" : "rad"}});
  Eigen::AlignedBox3d robot;
  json out = {
      {"version", 1},
      {"title", content.title},
      {"units", {{"length", "m"}, {"angle", "rad"}, {"time", "s"}}},
      {"fovy", scene.model().vis.global.fovy},
      {"bodies", bodies_json(scene)},
      {"geoms", geoms},
      {"meshes", meshes},
      {"joints", joints},
      {"volume", volume_json(content.volume)},
      {"initial_volume", content.initial_volume},
      {"tints", {{"lower", kLowerGhostTint}, {"upper", kUpperGhostTint}}},
      {"clearance_scale", kViewerClearanceScale},
      {"safety", {{"mode", content.safety_mode}, {"proven", content.proven}, {"margin", content.margin}}}};
  if (content.path) {
    if (content.path->dof() != scene.dof())
      throw InputError("the bounds have " + std::to_string(content.path->dof()) +
                       " joints, the cell's robot " + std::to_string(scene.dof()));
    out["path"] = path_json(scene, *content.path, options, robot);
  } else {
    scene.validate_configuration(content.q, "shown configuration");
    out["q"] = std::vector<double>(content.q.data(), content.q.data() + content.q.size());
    // Without bounds the joint sliders span the joints' limits: the cell can be explored.
    const Eigen::VectorXd lower = scene.lower_limits(), upper = scene.upper_limits();
    out["limits"] = {{"lower", std::vector<double>(lower.data(), lower.data() + lower.size())},
                     {"upper", std::vector<double>(upper.data(), upper.data() + upper.size())}};
    robot = robot_extent(scene, {content.q});
  }
  const Eigen::AlignedBox3d framed = robot_neighbourhood(scene, robot, kNearObstacles);
  const RenderCamera direction;
  out["frame"] = {{"min", {framed.min().x(), framed.min().y(), framed.min().z()}},
                  {"max", {framed.max().x(), framed.max().y(), framed.max().z()}},
                  {"azimuth", direction.azimuth},
                  {"elevation", direction.elevation}};
  return out.dump();
}

std::string viewer_html(const Scene& scene, const ViewerContent& content, const ViewerOptions& options) {
  const std::string three_dir = options.three_dir.empty() ? default_three_dir() : options.three_dir;
  const std::string three = read_asset(three_dir, kThreeJs);
  const std::string controls = read_asset(three_dir, kOrbitControls);
  std::string page = detail::kViewerPage;
  replace_once(page, "/*LEEWAY_THREE_LICENCE*/", "/*\n" + std::string(kThreeLicence) + "\n*/");
  replace_once(page, "/*LEEWAY_THREE*/", script_safe(three));
  replace_once(page, "/*LEEWAY_CONTROLS*/", script_safe(controls));
  replace_once(page, "LEEWAY_DATA", script_safe(viewer_data_json(scene, content, options)));
  return page;
}

}  // namespace leeway
