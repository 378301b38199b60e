#include "leeway/io/new_cell.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "leeway/core/check.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/mjcf_source.hpp"
#include "leeway/core/scene.hpp"
#include "leeway/io/urdf_import.hpp"
#include "mjcf_text.hpp"

namespace leeway {
namespace {

namespace fs = std::filesystem;

// `excludes_include`: the robot's excludes fragment ("" none); `excludes`: leeway_exclude texts with
// their comments, written in the cell's own <custom>; `meshdir`: the <compiler meshdir> ("" none).
std::string cell_text(const std::string& model_name, const std::string& include, const std::string& robot,
                      double reach, const std::string& home, const std::string& excludes_include,
                      const std::string& excludes, const std::string& meshdir) {
  const double floor = std::max(5.0, std::ceil(reach) + 1.0);
  std::ostringstream x;
  x.imbue(std::locale::classic());
  x << "<!--\n"
    << "  A minimal cell around the robot " << detail::comment_text(robot)
    << " (written by leeway new-cell):\n"
    << "  a visual-only floor, the robot with its base at the world origin, its self-collision\n"
    << "  excludes, a home keyframe. Add obstacles (named boxes, contype=\"0\" conaffinity=\"1\"), goal\n"
    << "  sites and keyframes (docs/mjcf-conventions.md), then run leeway check. Units: metres,\n"
    << "  radians.\n"
    << "-->\n"
    << "<mujoco model=\"" << detail::xml_escape(model_name) << "\">\n"
    << "  <compiler angle=\"radian\" autolimits=\"true\""
    << (meshdir.empty() ? "" : " meshdir=\"" + detail::xml_escape(meshdir) + "\"") << "/>\n\n"
    << "  <custom>\n"
    << "    <!-- [m] an upper bound of the robot's reach from its first hinge (link boxes and tool site) "
       "-->\n"
    << "    <numeric name=\"leeway_reach_radius\" data=\"" << format_number(reach) << "\"/>\n"
    << excludes << "  </custom>\n\n";
  if (!excludes_include.empty())
    x << "  <!-- The robot's self-collision excludes: top level, not in the world body. -->\n"
      << "  <include file=\"" << detail::xml_escape(excludes_include) << "\"/>\n";
  x << "  <worldbody>\n"
    << "    <light name=\"sun\" pos=\"0 0 8\" dir=\"0 0 -1\" directional=\"true\" diffuse=\"0.7 0.7 0.7\"/>\n"
    << "    <!-- Visual only: the floor is no obstacle (contype = conaffinity = 0). -->\n"
    << "    <geom name=\"floor\" type=\"plane\" size=\"" << format_number(floor) << " "
    << format_number(floor) << " 0.1\" contype=\"0\" conaffinity=\"0\" rgba=\"0.82 0.82 0.80 1\"/>\n"
    << "    <include file=\"" << detail::xml_escape(include) << "\"/>\n\n"
    << "    <!-- Obstacles and goals, for example:\n"
    << "    <geom name=\"table\" type=\"box\" pos=\"1.5 0 0.4\" size=\"0.5 0.5 0.4\" contype=\"0\" "
       "conaffinity=\"1\"/>\n"
    << "    <site name=\"pick\" pos=\"1.5 0 1.0\" size=\"0.03\"/>\n"
    << "    -->\n"
    << "  </worldbody>\n\n"
    << "  <keyframe>\n"
    << "    <!-- One value per robot joint, in model order [rad or m]. -->\n"
    << "    <key name=\"home\" qpos=\"" << home << "\"/>\n"
    << "  </keyframe>\n"
    << "</mujoco>\n";
  return x.str();
}

// Writes `text` to a temporary file beside `cell_path` (so that the include and the meshes resolve
// as they will from the cell), loads it as a Scene and removes it again; MuJoCo's and leeway's
// messages name the cell. `inputs`, when given, receives the files the cell reads (the robot, its
// includes and meshes).
Scene load_beside(const std::string& cell_path, const std::string& text,
                  std::vector<std::string>* inputs = nullptr) {
  TempFile tmp(cell_path);
  try {
    tmp.write(text);
    tmp.close();
    Scene s = Scene::load(tmp.path());
    if (inputs) {
      *inputs = model_input_files(tmp.path());
      inputs->erase(inputs->begin());  // the temporary file itself
    }
    return s;
  } catch (const InputError& e) {
    std::string msg = e.what();
    for (size_t p = msg.find(tmp.path()); p != std::string::npos; p = msg.find(tmp.path()))
      msg.replace(p, tmp.path().size(), cell_path);
    throw InputError(msg);
  }
}

// `path` as MuJoCo 2.2.2 resolves an include of the cell at `cell_path`: relative to the cell's
// folder, lexically (symbolic links kept), or absolute when there is no relative path.
std::string include_path(const std::string& path, const std::string& cell_path) {
  const fs::path cell_dir = fs::absolute(fs::path(cell_path)).lexically_normal().parent_path();
  const fs::path abs = fs::absolute(path).lexically_normal();
  const fs::path rel = abs.lexically_relative(cell_dir);
  return rel.empty() ? abs.string() : rel.string();
}

// Upper bound of the distance from the first hinge's anchor to any point of a link geom or the
// tool site: the anchor's offset in its body, the lengths of the body offsets below it (rotations
// keep lengths), slide travel, and the geom's offset plus its bounding-sphere radius.
double reach_bound(const Scene& scene) {
  const mjModel& m = scene.model();
  int hinge = -1;
  for (const auto& j : scene.joints())
    if (!j.prismatic) {
      hinge = j.id;
      break;
    }
  if (hinge < 0) return 0;
  const int top = m.jnt_bodyid[hinge];
  auto chain = [&](int body, double& d) {
    d = Eigen::Map<const Eigen::Vector3d>(m.jnt_pos + 3 * hinge).norm();
    for (int b = body; b != top; b = m.body_parentid[b]) {
      if (b <= 0) return false;  // not below the first hinge (a rail carriage, the base)
      d += Eigen::Map<const Eigen::Vector3d>(m.body_pos + 3 * b).norm();
      for (int j = m.body_jntadr[b]; j >= 0 && j < m.body_jntadr[b] + m.body_jntnum[b]; ++j)
        if (m.jnt_type[j] == mjJNT_SLIDE)
          d += std::max(std::abs(m.jnt_range[2 * j]), std::abs(m.jnt_range[2 * j + 1]));
    }
    return true;
  };
  double reach = 0, d = 0;
  for (int g : scene.link_geoms())
    if (chain(m.geom_bodyid[g], d))
      reach = std::max(reach,
                       d + Eigen::Map<const Eigen::Vector3d>(m.geom_pos + 3 * g).norm() + m.geom_rbound[g]);
  const int site = scene.tool_site();
  if (chain(m.site_bodyid[site], d))
    reach = std::max(reach, d + Eigen::Map<const Eigen::Vector3d>(m.site_pos + 3 * site).norm());
  return std::ceil(reach * 10 - 1e-9) / 10;
}

}  // namespace

NewCell write_new_cell(const std::string& robot_path, const std::string& cell_path,
                       const std::string& model_name, const std::string& excludes_path) {
  std::error_code ec;
  if (!fs::is_regular_file(robot_path, ec))
    throw InputError(robot_path + ": cannot open the robot file (missing or not a file)");
  if (const std::string section = first_model_section(robot_path); !section.empty())
    throw InputError(robot_path + ": has " + section +
                     ": a whole MJCF model, not a robot fragment (the new cell includes the robot inside "
                     "<worldbody>, so the file holds its bodies only, e.g. mjcf/robots/irb6700_body.xml)");
  if (!excludes_path.empty() && !fs::is_regular_file(excludes_path, ec))
    throw InputError(excludes_path + ": cannot open the excludes file (missing or not a file)");
  NewCell out;
  // MuJoCo 2.2.2 resolves includes from the main file's folder: write the paths relative to it.
  out.robot_include = include_path(robot_path, cell_path);
  // The robot's excludes fragment: given, or the one import-urdf writes beside the robot.
  const std::string excludes = excludes_path.empty() ? leeway::excludes_path(robot_path) : excludes_path;
  if (fs::is_regular_file(excludes, ec)) out.excludes_include = include_path(excludes, cell_path);
  // Its mesh assets (import-urdf's mesh geoms) name their files relative to the robot's folder, and
  // MuJoCo 2.2.2 reads them relative to the cell's folder and meshdir.
  if (!out.excludes_include.empty() && read_mjcf_source(excludes).files.size() > 1) {
    const std::string robot_dir = fs::absolute(robot_path).lexically_normal().parent_path().string();
    const fs::path rel = include_path(robot_dir, cell_path);
    if (rel != "." && !rel.empty()) out.meshdir = rel.string();
  }
  const std::string robot_name = fs::path(robot_path).filename().string();

  // First the cell without keyframes, to learn the robot's joints and reach, and the pairs that
  // touch at home.
  std::string text =
      cell_text(model_name, out.robot_include, robot_name, 2.8, "", out.excludes_include, "", out.meshdir);
  text.erase(text.find("  <keyframe>"), text.find("</mujoco>") - text.find("  <keyframe>"));
  const Scene probe = load_beside(cell_path, text);
  const Eigen::VectorXd home =
      Eigen::VectorXd::Zero(probe.dof()).cwiseMax(probe.lower_limits()).cwiseMin(probe.upper_limits());
  for (int i = 0; i < home.size(); ++i) out.home += (i ? " " : "") + detail::exact_number(home[i]);
  out.joints = probe.dof();
  out.reach_radius = reach_bound(probe);
  out.included_excludes = static_cast<int>(probe.excluded_pairs().size());

  // A pair touching at home would fail the check: the cell excludes it, saying so. A fragment written
  // by import-urdf has excluded these already (its reference configuration is this home).
  std::string texts;
  RobotState state(probe);
  constexpr double kTouch = 1e-6;  // [m] as import-urdf: geoms meeting face to face touch or not by rounding
  for (const SelfContact& c : self_contacts_within(state, home, kTouch)) {
    CellExclude e;
    e.geom1 = probe.geom_label(c.geom1);
    e.geom2 = probe.geom_label(c.geom2);
    e.depth = c.depth;
    e.reason = (c.depth > kTouch ? "the geoms overlap by " + format_number(c.depth) + " m"
                                 : std::string("the geoms touch (within 1e-06 m)")) +
               " at keyframe home, where the arm is taken to stand clear of itself: an artefact of the "
               "collision shapes; check it";
    const std::string name = "leeway_exclude_home_" + std::to_string(out.cell_excludes.size() + 1);
    if (object_name(probe.model(), mjOBJ_GEOM, c.geom1).empty() ||
        object_name(probe.model(), mjOBJ_GEOM, c.geom2).empty() ||
        (e.geom1 + e.geom2).find_first_of(" \t\r\n") != std::string::npos)
      throw InputError(cell_path + ": robot geoms " + e.geom1 + " and " + e.geom2 +
                       " touch at keyframe home (" + e.reason +
                       "), but only named geoms without white space can be excluded: name them");
    texts += detail::wrapped_comment(e.geom1 + " and " + e.geom2 + ": " + e.reason + ".", 4) +
             "    <text name=\"" + name + "\" data=\"" + detail::xml_escape(e.geom1 + " " + e.geom2) +
             "\"/>\n";
    out.cell_excludes.push_back(std::move(e));
  }
  out.mjcf = cell_text(model_name, out.robot_include, robot_name, out.reach_radius, out.home,
                       out.excludes_include, texts, out.meshdir);

  // Then the cell itself, checked before it is moved into place.
  std::vector<std::string> inputs;
  const Scene scene = load_beside(cell_path, out.mjcf, &inputs);
  out.self_pairs = static_cast<int>(scene.self_pairs().size());
  const CheckReport report = check_scene(scene);
  if (!report.ok()) {
    std::string problems;
    for (const auto& p : report.problems) problems += (problems.empty() ? "" : "; ") + p;
    throw InputError(cell_path + ": the new cell fails leeway's check: " + problems);
  }
  // The cell may not replace the robot, a file it includes or a mesh it names.
  require_outputs({{cell_path, "", {}}}, inputs);
  write_file_atomic(cell_path, out.mjcf);
  return out;
}

}  // namespace leeway
