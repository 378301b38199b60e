#include "leeway/new_cell.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "leeway/check.hpp"
#include "leeway/error.hpp"
#include "leeway/file_io.hpp"
#include "leeway/mjcf_source.hpp"
#include "leeway/scene.hpp"
#include "mjcf_text.hpp"

namespace leeway {
namespace {

namespace fs = std::filesystem;

std::string cell_text(const std::string& model_name, const std::string& include, const std::string& robot,
                      double reach, const std::string& home) {
  const double floor = std::max(5.0, std::ceil(reach) + 1.0);
  std::ostringstream x;
  x.imbue(std::locale::classic());
  x << "<!--\n"
    << "  A minimal cell around the robot " << detail::comment_text(robot)
    << " (written by leeway new-cell):\n"
    << "  a visual-only floor, the robot with its base at the world origin, a home keyframe. Add\n"
    << "  obstacles (named boxes, contype=\"0\" conaffinity=\"1\"), goal sites and keyframes\n"
    << "  (docs/mjcf-conventions.md), then run leeway check. Units: metres, radians.\n"
    << "-->\n"
    << "<mujoco model=\"" << detail::xml_escape(model_name) << "\">\n"
    << "  <compiler angle=\"radian\" autolimits=\"true\"/>\n\n"
    << "  <custom>\n"
    << "    <!-- [m] an upper bound of the robot's reach from its first hinge (link boxes and tool site) "
       "-->\n"
    << "    <numeric name=\"leeway_reach_radius\" data=\"" << format_number(reach) << "\"/>\n"
    << "  </custom>\n\n"
    << "  <worldbody>\n"
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
                       const std::string& model_name) {
  std::error_code ec;
  if (!fs::is_regular_file(robot_path, ec))
    throw InputError(robot_path + ": cannot open the robot file (missing or not a file)");
  NewCell out;
  // MuJoCo 2.2.2 resolves includes from the main file's folder: write the robot's path relative to it.
  // Lexically, as MuJoCo joins the folder and the include (symbolic links are kept).
  const fs::path cell_dir = fs::absolute(fs::path(cell_path)).lexically_normal().parent_path();
  const fs::path robot_abs = fs::absolute(robot_path).lexically_normal();
  const fs::path rel = robot_abs.lexically_relative(cell_dir);
  out.robot_include = rel.empty() ? robot_abs.string() : rel.string();
  const std::string robot_name = fs::path(robot_path).filename().string();

  // First the cell without keyframes, to learn the robot's joints and reach.
  std::string text = cell_text(model_name, out.robot_include, robot_name, 2.8, "");
  text.erase(text.find("  <keyframe>"), text.find("</mujoco>") - text.find("  <keyframe>"));
  const Scene probe = load_beside(cell_path, text);
  const Eigen::VectorXd home =
      Eigen::VectorXd::Zero(probe.dof()).cwiseMax(probe.lower_limits()).cwiseMin(probe.upper_limits());
  for (int i = 0; i < home.size(); ++i) out.home += (i ? " " : "") + detail::exact_number(home[i]);
  out.joints = probe.dof();
  out.reach_radius = reach_bound(probe);
  out.mjcf = cell_text(model_name, out.robot_include, robot_name, out.reach_radius, out.home);

  // Then the cell itself, checked before it is moved into place.
  std::vector<std::string> inputs;
  const Scene scene = load_beside(cell_path, out.mjcf, &inputs);
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
