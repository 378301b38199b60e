#include "leeway/io/urdf_import.hpp"

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "leeway/core/file_io.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/mjcf_source.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/scene.hpp"
#include "leeway/io/stl.hpp"
#include "mjcf_text.hpp"

namespace leeway {
namespace {

namespace fs = std::filesystem;
using Eigen::Isometry3d;
using Eigen::Vector3d;

constexpr double kTwoPi = 6.283185307179586;
constexpr double kMinHalfSize = 5e-4;  // [m] thinner boxes are thickened to this half-size (MuJoCo needs > 0)
// [m] boxes this close at the reference configuration count as touching: boxes meeting face to face
// at a joint touch or not by rounding.
constexpr double kTouch = 1e-6;
constexpr const char* kLinkRgba = "0.93 0.47 0.10 1";
constexpr const char* kBaseRgba = "0.35 0.35 0.38 1";

// urdfdom reports parse errors through console_bridge, a process-wide logger: collect them while
// parsing (one parse at a time) instead of letting them go to standard error.
class ErrorCollector : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) messages.push_back(text);
  }
  std::vector<std::string> messages;
};

std::string urdfdom_message(const std::vector<std::string>& messages) {
  // urdfdom's first error is the specific one (the value), the next names the element; drop its
  // generic follow-ups and the advice after the first sentence.
  std::string out;
  for (std::string m : messages) {
    if (m.find("is not initialized correctly") != std::string::npos) continue;
    const size_t stop = m.find(". ");
    if (stop != std::string::npos) m = m.substr(0, stop);
    while (!m.empty() && (m.back() == '.' || m.back() == ' ')) m.pop_back();
    if (out.find(m) == std::string::npos) out += (out.empty() ? "" : "; ") + m;
  }
  if (out.empty())
    for (const auto& m : messages) out += (out.empty() ? "" : "; ") + m;
  return out.empty() ? "urdfdom could not parse it" : out;
}

urdf::ModelInterfaceSharedPtr parse_urdf(const std::string& file, const std::string& text) {
  require_shallow_xml(text, file);  // urdfdom's TinyXML recurses: 50,000 levels overflow the stack
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  ErrorCollector collector;
  console_bridge::useOutputHandler(&collector);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(text);
  } catch (const std::exception& e) {
    collector.messages.emplace_back(e.what());
  }
  console_bridge::restorePreviousOutputHandler();
  // urdfdom drops a <collision> element it cannot parse, logs an error and returns the model: any
  // error is fatal here, or a link would silently lose collision geometry.
  if (!model || !collector.messages.empty())
    throw InputError(file + ": not a valid URDF: " + urdfdom_message(collector.messages));
  return model;
}

std::string num(double v) { return detail::exact_number(v); }

std::string vec(const Vector3d& v) { return num(v.x()) + " " + num(v.y()) + " " + num(v.z()); }

using detail::comment_text;
using detail::xml_escape;

// pos="..." and quat="..." (MuJoCo's w x y z) of a pose; the quaternion only when it rotates.
std::string pose_attributes(const Isometry3d& t) {
  std::string out = "pos=\"" + vec(t.translation()) + "\"";
  if (!t.linear().isIdentity(0)) {
    Eigen::Quaterniond q(t.linear());
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    q.normalize();
    out += " quat=\"" + num(q.w()) + " " + num(q.x()) + " " + num(q.y()) + " " + num(q.z()) + "\"";
  }
  return out;
}

std::string vector3_text(const urdf::Vector3& v) { return num(v.x) + " " + num(v.y) + " " + num(v.z); }

// A URDF pose as a transform. @throws InputError when a value is not finite.
Isometry3d to_isometry(const urdf::Pose& p, const std::string& what) {
  const Vector3d xyz(p.position.x, p.position.y, p.position.z);
  const Eigen::Quaterniond q(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z);
  if (!xyz.allFinite())
    throw InputError(what + " <origin> xyz '" + vector3_text(p.position) + "' is not finite");
  if (!q.coeffs().allFinite() || std::abs(q.norm() - 1) > 1e-6)
    throw InputError(what + " <origin> rpy gives the quaternion '" + num(q.w()) + " " + num(q.x()) + " " +
                     num(q.y()) + " " + num(q.z()) + "', not a finite rotation");
  Isometry3d t = Isometry3d::Identity();
  t.linear() = q.normalized().toRotationMatrix();
  t.translation() = xyz;
  return t;
}

const char* joint_type_name(int type) {
  switch (type) {
    case urdf::Joint::REVOLUTE:
      return "revolute";
    case urdf::Joint::CONTINUOUS:
      return "continuous";
    case urdf::Joint::PRISMATIC:
      return "prismatic";
    case urdf::Joint::FLOATING:
      return "floating";
    case urdf::Joint::PLANAR:
      return "planar";
    case urdf::Joint::FIXED:
      return "fixed";
    default:
      return "unknown";
  }
}

std::string join_names(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "'" : ", '") + n + "'";
  return out.empty() ? "(none)" : out;
}

// ---- package:// resolution (the ROS convention) ----

std::optional<std::string> package_xml_name(const fs::path& dir) {
  std::ifstream in(dir / "package.xml");
  if (!in) return std::nullopt;
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t a = text.find("<name>");
  const size_t b = a == std::string::npos ? a : text.find("</name>", a);
  if (b == std::string::npos) return std::string();
  std::string name = text.substr(a + 6, b - a - 6);
  const auto first = name.find_first_not_of(" \t\r\n"), last = name.find_last_not_of(" \t\r\n");
  return first == std::string::npos ? std::string() : name.substr(first, last - first + 1);
}

// Most folders one package search looks into: a package path as wide as "/" would otherwise walk
// the whole disk (for every mesh).
constexpr int kMaxPackageSearchFolders = 20000;

// A package below `root`: root/NAME, or a folder holding package.xml with <name>NAME</name>
// (searched breadth-first in name order, not below other packages or hidden folders, 8 levels,
// at most kMaxPackageSearchFolders folders).
// @throws InputError when the search stops at that limit without finding the package.
std::optional<fs::path> find_package_in(const fs::path& root, const std::string& name) {
  std::error_code ec;
  if (fs::is_directory(root / name, ec)) return root / name;
  std::deque<std::pair<fs::path, int>> queue = {{root, 0}};
  int visited = 0;
  while (!queue.empty()) {
    const auto [dir, depth] = queue.front();
    queue.pop_front();
    if (++visited > kMaxPackageSearchFolders)
      throw InputError("looking for ROS package '" + name + "' under '" + root.string() + "' stopped after " +
                       std::to_string(kMaxPackageSearchFolders) +
                       " folders; give the package's folder, or the folder holding it, with --package-path");
    if (const auto n = package_xml_name(dir)) {
      if (*n == name) return dir;
      if (depth > 0) continue;  // packages do not nest
    }
    if (depth >= 8) continue;
    std::vector<fs::path> subdirs;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
      if (it->is_directory(ec) && it->path().filename().string().rfind('.', 0) != 0)
        subdirs.push_back(it->path());
    std::sort(subdirs.begin(), subdirs.end());
    for (const auto& s : subdirs) queue.emplace_back(s, depth + 1);
  }
  return std::nullopt;
}

std::vector<std::string> split_paths(const std::string& list) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(list);
  while (std::getline(in, item, ':'))
    if (!item.empty()) out.push_back(item);
  return out;
}

// ---- the robot as leeway's bodies ----

struct Geom {
  std::string name, comment;
  std::string link;          // the URDF link it came from (SRDF entries name links)
  Isometry3d pose;           // in the body's frame
  std::string type = "box";  // the MuJoCo geom type: box, cylinder, sphere or mesh
  Vector3d half;     // [m] a box's half-sizes; a cylinder's radius, radius, half-length; a sphere's radius
  std::string mesh;  // a mesh geom's asset (named as the geom)
};

// A mesh asset of the excludes fragment and the copy it reads.
struct MeshAsset {
  std::string name, what;  // the asset (= the geom's name); the collision element, for messages
  std::string scale;       // the URDF's scale attribute; empty when 1 1 1
  UrdfMeshFile file;
};

// A binary STL of `vertices` (three per triangle) as 32-bit little-endian floats, with the facet
// normals, and `header` (which must not start with "solid") in the 80-byte header.
std::string binary_stl(const std::vector<Vector3d>& vertices, const std::string& header) {
  std::string out(80, '\0');
  out.replace(0, std::min<size_t>(header.size(), 80), header.substr(0, 80));
  auto put_u32 = [&](std::uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xFF));
  };
  auto put = [&](const Vector3d& p) {
    for (int k = 0; k < 3; ++k) {
      const float f = static_cast<float>(p[k]);
      std::uint32_t bits = 0;
      std::memcpy(&bits, &f, sizeof f);
      put_u32(bits);
    }
  };
  put_u32(static_cast<std::uint32_t>(vertices.size() / 3));
  for (size_t t = 0; t + 2 < vertices.size(); t += 3) {
    const Vector3d n = (vertices[t + 1] - vertices[t]).cross(vertices[t + 2] - vertices[t]);
    put(n.norm() > 0 ? Vector3d(n.normalized()) : Vector3d::Zero());
    for (size_t v = t; v < t + 3; ++v) put(vertices[v]);
    out.append(2, '\0');  // attribute byte count
  }
  return out;
}

// Compiles MJCF text as the virtual file `path` with `files` {name, bytes} beside it in MuJoCo's
// virtual file system (MuJoCo 2.2.2 finds a virtual file by its name without folders, so a mesh
// asset whose path ends in that name reads it): the import checks its mesh geoms before it writes
// anything. As load_model_text, with MuJoCo's message on one line.
// @throws InputError "PATH: MJCF does not compile: ...".
ModelPtr load_text_with_files(const std::string& xml, const std::string& path,
                              const std::vector<std::pair<std::string, std::string>>& files) {
  install_mujoco_error_handlers();
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  std::vector<std::pair<std::string, std::string>> all = {{path, xml}};
  all.insert(all.end(), files.begin(), files.end());
  for (const auto& [name, bytes] : all) {
    if (mj_makeEmptyFileVFS(vfs.get(), name.c_str(), static_cast<int>(bytes.size())) != 0) {
      mj_deleteVFS(vfs.get());
      throw std::runtime_error("cannot allocate a MuJoCo virtual file for " + name);
    }
    std::memcpy(vfs->filedata[vfs->nfile - 1], bytes.data(), bytes.size());
  }
  char error[1024] = "";
  mjModel* m = mj_loadXML(path.c_str(), vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  if (!m) {
    std::string msg(error);
    for (size_t p = msg.find('\n'); p != std::string::npos; p = msg.find('\n', p))
      msg.replace(p, 1, p + 1 < msg.size() ? "; " : "");
    throw InputError(path + ": MJCF does not compile: " + msg);
  }
  return ModelPtr(m);
}

// `name` as a file name: characters other than letters, digits, '_', '-' and '.' become '_'.
std::string file_safe(std::string name) {
  for (char& ch : name)
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '_' && ch != '-' && ch != '.') ch = '_';
  return name;
}

struct Body {
  std::string link, comment;
  Isometry3d pose = Isometry3d::Identity();  // in the parent body's frame (the base: identity)
  urdf::JointConstSharedPtr joint;           // null for the base
  std::vector<Geom> geoms;
  std::optional<Isometry3d> tool;  // the tool0 site in this body's frame
};

constexpr size_t kMaxChainJoints = 256;  //!< moving joints from the base to the tool
constexpr size_t kMaxTreeDepth = 1024;   //!< links from the base to the deepest leaf

class Importer {
 public:
  Importer(std::string file, const UrdfImportOptions& options) : file_(std::move(file)), options_(options) {
    urdf_dir_ = fs::path(file_).parent_path().string();
    if (urdf_dir_.empty()) urdf_dir_ = ".";
  }
  // urdfdom's links own their child links and joints (shared_ptr): the joint loops that
  // check_tree and find_tool refuse are cycles of owners that would outlive the model and leak
  // (found by fuzz/fuzz_urdf.cpp). Nothing of the model is used after the import: break them.
  ~Importer() {
    if (!model_) return;
    for (auto& [name, link] : model_->links_) {
      link->child_links.clear();
      link->child_joints.clear();
    }
  }
  Importer(const Importer&) = delete;
  Importer& operator=(const Importer&) = delete;

  UrdfImport run() {
    std::ifstream in(file_);
    if (!in) throw InputError(file_ + ": cannot open the URDF file");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    model_ = parse_urdf(file_, text);
    check_tree();
    const urdf::LinkConstSharedPtr base = find_base();
    const urdf::LinkConstSharedPtr tool = find_tool(base);
    for (auto l = tool; l != base; l = l->getParent()) chain_.insert(l->parent_joint->name);
    check_depth(base, tool);

    Body root;
    root.link = base->name;
    root.comment = "base link '" + base->name + "' (fixed: the robot base)";
    bodies_.push_back(root);
    visit(base, 0, Isometry3d::Identity(), "");
    for (const Body& b : bodies_)
      if (b.link == "world")
        throw InputError(link_label(b.link) +
                         (b.joint ? " (the child of joint '" + b.joint->name + "')" : "") +
                         " would be a body named 'world', a name MJCF keeps for its world body; rename "
                         "the link in the URDF");
    if (bodies_.size() < 2)
      throw InputError(file_ + ": no revolute, continuous or prismatic joint between the base link '" +
                       base->name + "' and the tool link '" + tool->name +
                       "'; leeway needs a robot that moves");
    bool moving_geoms = false;
    for (size_t i = 1; i < bodies_.size(); ++i) moving_geoms = moving_geoms || !bodies_[i].geoms.empty();
    if (!moving_geoms)
      throw InputError(file_ + ": no <collision> element on the links that move (below joint '" +
                       bodies_[1].joint->name + "'); leeway checks collisions of those links");
    UrdfImport out = write(base->name, tool->name);
    find_excludes(out);
    return out;
  }

 private:
  std::string link_label(const std::string& link) const { return file_ + ": link '" + link + "'"; }

  void check_tree() {
    // urdfdom accepts a link that is the child of two joints (it keeps the last parent), which
    // makes a loop of the tree: refuse it here.
    std::map<std::string, std::vector<std::string>> parents;
    for (const auto& [name, joint] : model_->joints_) parents[joint->child_link_name].push_back(name);
    for (const auto& [link, joints] : parents)
      if (joints.size() > 1)
        throw InputError(file_ + ": link '" + link + "' is the child of joints " + join_names(joints) +
                         ": a joint loop (a URDF must be a tree, each link with one parent joint)");
  }

  // Each moving joint on the chain nests one <body> in the next, and MuJoCo's XML reader stops at
  // 500 levels; visit() recurses once per link. Both are refused here, before any work, by count.
  void check_depth(const urdf::LinkConstSharedPtr& base, const urdf::LinkConstSharedPtr& tool) const {
    size_t moving = 0;
    for (const auto& name : chain_)
      if (model_->getJoint(name)->type != urdf::Joint::FIXED) ++moving;
    if (moving > kMaxChainJoints)
      throw InputError(file_ + ": the chain from the base link '" + base->name + "' to the tool link '" +
                       tool->name + "' has " + std::to_string(moving) +
                       " moving joints; leeway imports at most " + std::to_string(kMaxChainJoints) +
                       " (each nests a body in the MJCF, which MuJoCo reads to 500 levels)");
    std::vector<std::pair<urdf::LinkConstSharedPtr, size_t>> open{{base, 0}};
    while (!open.empty()) {
      const auto [link, depth] = open.back();
      open.pop_back();
      if (depth > kMaxTreeDepth)
        throw InputError(link_label(link->name) + " is more than " + std::to_string(kMaxTreeDepth) +
                         " links below the base link '" + base->name +
                         "'; leeway imports trees up to that depth");
      for (const auto& child : link->child_links) open.emplace_back(child, depth + 1);
    }
  }

  urdf::LinkConstSharedPtr find_base() {
    if (!options_.base_link.empty()) {
      auto l = model_->getLink(options_.base_link);
      if (!l)
        throw UrdfOptionError(
            file_ + ": no link '" + options_.base_link + "' for the base; links: " + link_names(),
            "base_link");
      return l;
    }
    urdf::LinkConstSharedPtr root = model_->getRoot();
    // Gazebo's convention: a link 'world' fixed to the real base. MJCF reserves the name 'world'.
    if (root->name == "world" && root->child_joints.size() == 1 &&
        root->child_joints.front()->type == urdf::Joint::FIXED) {
      const auto& j = root->child_joints.front();
      notes_.push_back("the root link 'world' and its fixed joint '" + j->name +
                       "' are left out: the base is '" + j->child_link_name + "'");
      return model_->getLink(j->child_link_name);
    }
    return root;
  }

  urdf::LinkConstSharedPtr find_tool(const urdf::LinkConstSharedPtr& base) {
    auto tool = model_->getLink(options_.tool_link);
    if (!tool)
      throw UrdfOptionError(file_ + ": no tool link: the URDF has no link '" + options_.tool_link +
                                "' (the flange frame, 'tool0' in ROS-Industrial); links: " + link_names(),
                            "tool_link");
    size_t steps = 0;
    for (auto l = tool; l; l = l->getParent()) {
      if (l == base) return tool;
      // A cycle of links each with one parent joint, apart from the root's tree, has no end.
      if (++steps > model_->links_.size())
        throw InputError(file_ + ": link '" + l->name + "' lies on a joint loop above the tool link '" +
                         tool->name + "' (a URDF must be a tree)");
    }
    throw UrdfOptionError(
        file_ + ": tool link '" + tool->name + "' is not below the base link '" + base->name + "'",
        "tool_link");
  }

  std::string link_names() const {
    std::vector<std::string> names;
    for (const auto& [name, link] : model_->links_) names.push_back(name);
    return join_names(names);
  }

  // Adds `link` (at `t` in body `b`'s frame) and everything below it. `via` says how it got there.
  void visit(const urdf::LinkConstSharedPtr& link, size_t b, const Isometry3d& t, const std::string& via) {
    add_collisions(*link, b, t, via);
    if (link->name == options_.tool_link) bodies_[b].tool = t;
    for (const auto& joint : link->child_joints) {
      const std::string what = file_ + ": joint '" + joint->name + "'";
      const Isometry3d origin = to_isometry(joint->parent_to_joint_origin_transform, what);
      const auto child = model_->getLink(joint->child_link_name);
      if (chain_.count(joint->name) && joint->type != urdf::Joint::FIXED) {
        bodies_.push_back(chain_body(*joint, t * origin));
        visit(child, bodies_.size() - 1, Isometry3d::Identity(), "");
      } else {
        std::string how = "fixed joint '" + joint->name + "'";
        Isometry3d motion = Isometry3d::Identity();
        if (joint->type != urdf::Joint::FIXED) {
          const double v = frozen_value(*joint);
          how = std::string(joint_type_name(joint->type)) + " joint '" + joint->name + "' frozen at " +
                num(v) + (joint->type == urdf::Joint::PRISMATIC ? " m" : " rad");
          notes_.push_back("joint '" + joint->name +
                           "' is off the chain from the base to the tool link: frozen at " + num(v) +
                           (joint->type == urdf::Joint::PRISMATIC ? " m" : " rad") +
                           ", its links merged into '" + bodies_[b].link + "'");
          motion = joint_motion(*joint, v, what);
        }
        visit(child, b, t * origin * motion, "link '" + child->name + "' (merged through " + how + ")");
      }
    }
  }

  double frozen_value(const urdf::Joint& j) const {
    if ((j.type == urdf::Joint::REVOLUTE || j.type == urdf::Joint::PRISMATIC) && j.limits)
      return std::clamp(0.0, j.limits->lower, std::max(j.limits->lower, j.limits->upper));
    return 0.0;
  }

  Vector3d axis(const urdf::Joint& j, const std::string& what) const {
    const Vector3d a(j.axis.x, j.axis.y, j.axis.z);
    if (!a.allFinite() || a.norm() < 1e-9)
      throw InputError(what + " <axis> xyz '" + vector3_text(j.axis) + "' is not a finite non-zero vector");
    return a.normalized();
  }

  Isometry3d joint_motion(const urdf::Joint& j, double v, const std::string& what) const {
    Isometry3d m = Isometry3d::Identity();
    if (j.type == urdf::Joint::REVOLUTE || j.type == urdf::Joint::CONTINUOUS)
      m.linear() = Eigen::AngleAxisd(v, axis(j, what)).toRotationMatrix();
    else if (j.type == urdf::Joint::PRISMATIC)
      m.translation() = v * axis(j, what);
    return m;
  }

  Body chain_body(const urdf::Joint& j, const Isometry3d& pose) {
    const std::string what = file_ + ": joint '" + j.name + "'";
    if (j.type == urdf::Joint::FLOATING || j.type == urdf::Joint::PLANAR || j.type == urdf::Joint::UNKNOWN)
      throw InputError(what + " is " + joint_type_name(j.type) +
                       " on the chain from the base to the tool link; leeway's robot joints are 1-dof "
                       "(revolute, continuous, prismatic)");
    if (j.mimic)
      throw InputError(what + " mimics joint '" + j.mimic->joint_name +
                       "'; leeway's robot joints move independently");
    if (j.type == urdf::Joint::CONTINUOUS && !options_.continuous_full_turn)
      throw UrdfOptionError(what +
                                " is continuous (no limits); leeway needs limited joints: import it with the "
                                "range -2 pi .. 2 pi rad on request",
                            "continuous_full_turn");
    axis(j, what);
    if (j.type != urdf::Joint::CONTINUOUS) {
      if (!j.limits) throw InputError(what + " has no <limit>");
      const double lo = j.limits->lower, hi = j.limits->upper;
      if (!std::isfinite(lo) || !std::isfinite(hi) || lo >= hi)
        throw InputError(what + " <limit> lower '" + num(lo) + "' upper '" + num(hi) +
                         "' is not a finite, non-empty range");
    }
    if (j.limits && (!std::isfinite(j.limits->velocity) || j.limits->velocity < 0))
      throw InputError(what + " <limit> velocity '" + num(j.limits->velocity) +
                       "' must be a finite value >= 0");
    Body body;
    body.link = j.child_link_name;
    body.comment = "link '" + j.child_link_name + "', " + joint_type_name(j.type) + " joint '" + j.name +
                   "' from '" + j.parent_link_name + "'";
    body.pose = pose;
    body.joint = model_->getJoint(j.name);
    return body;
  }

  void add_collisions(const urdf::Link& link, size_t b, const Isometry3d& t, const std::string& via) {
    std::vector<urdf::CollisionSharedPtr> collisions = link.collision_array;
    if (collisions.empty() && link.collision) collisions.push_back(link.collision);
    const bool boxes = options_.link_geometry == LinkGeometry::kBox;
    int index = 0;
    for (const auto& c : collisions) {
      ++index;
      if (!c || !c->geometry) continue;
      const std::string what = link_label(link.name) + " <collision> " + std::to_string(index) +
                               (c->name.empty() ? "" : " '" + c->name + "'");
      Geom g;
      g.pose = t * to_isometry(c->origin, what);
      std::string shape;
      switch (c->geometry->type) {
        case urdf::Geometry::BOX: {
          const auto& d = static_cast<const urdf::Box&>(*c->geometry).dim;
          g.half = Vector3d(d.x, d.y, d.z) / 2;
          require_positive(g.half, what + " <box> size '" + vector3_text(d) + "'");
          shape = "box " + vector3_text(d) + " m (exact)";
          break;
        }
        case urdf::Geometry::CYLINDER: {
          const auto& cy = static_cast<const urdf::Cylinder&>(*c->geometry);
          g.half = Vector3d(cy.radius, cy.radius, cy.length / 2);
          require_positive(
              g.half, what + " <cylinder> radius '" + num(cy.radius) + "' length '" + num(cy.length) + "'");
          shape = "cylinder radius " + num(cy.radius) + " m, length " + num(cy.length) +
                  (boxes ? " m as its tight box (axis = box z)" : " m (exact)");
          if (!boxes) g.type = "cylinder";
          break;
        }
        case urdf::Geometry::SPHERE: {
          const double r = static_cast<const urdf::Sphere&>(*c->geometry).radius;
          g.half = Vector3d::Constant(r);
          require_positive(g.half, what + " <sphere> radius '" + num(r) + "'");
          shape = "sphere radius " + num(r) + (boxes ? " m as its bounding cube" : " m (exact)");
          if (!boxes) g.type = "sphere";
          break;
        }
        case urdf::Geometry::MESH: {
          const auto& mesh = static_cast<const urdf::Mesh&>(*c->geometry);
          shape = mesh_shape(mesh, what, link.name, c->name, collisions.size() > 1 ? index : 0, g);
          break;
        }
        default:
          throw InputError(what + " has a geometry leeway does not know");
      }
      for (int k = 0; k < 3 && g.type == "box"; ++k)
        if (g.half[k] < kMinHalfSize) {
          notes_.push_back(what + ": half-size " + num(g.half[k]) + " m along box axis " + "xyz"[k] +
                           " thickened to " + num(kMinHalfSize) + " m");
          g.half[k] = kMinHalfSize;
        }
      if (g.name.empty()) g.name = geom_name(link.name, c->name, collisions.size() > 1 ? index : 0, g.type);
      g.link = link.name;
      g.comment = (via.empty() ? "" : via + ", ") + "collision " + std::to_string(index) +
                  (c->name.empty() ? "" : " '" + c->name + "'") + ": " + shape;
      bodies_[b].geoms.push_back(g);
    }
  }

  static void require_positive(const Vector3d& half, const std::string& what) {
    if (!half.allFinite() || (half.array() <= 0).any())
      throw InputError(what + " must be finite and positive [m]");
  }

  // An STL <mesh> as its bounding box (LinkGeometry::kBox) or as a mesh geom on a binary copy of it
  // (kMesh, which also names the geom); returns how the shape was taken.
  std::string mesh_shape(const urdf::Mesh& mesh, const std::string& what, const std::string& link,
                         const std::string& collision, int index, Geom& g) {
    const std::string m = what + " <mesh> filename '" + mesh.filename + "'";
    const std::string path = resolve_urdf_resource(mesh.filename, urdf_dir_, options_, m);
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
    if (ext != ".stl")
      throw InputError(m + " is not an STL file ('" + ext +
                       "'); leeway reads STL meshes only: export the collision "
                       "mesh as STL or give the link primitive shapes");
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw InputError(m + ": the mesh file '" + path + "' does not exist");
    const Vector3d scale(mesh.scale.x, mesh.scale.y, mesh.scale.z);
    if (!scale.allFinite() || (scale.array() == 0).any())
      throw InputError(m + " scale '" + vector3_text(mesh.scale) + "' must be finite and non-zero");
    meshes_read_.push_back(path);
    StlMesh stl;
    try {
      stl = read_stl(path);
    } catch (const InputError& e) {
      throw InputError(m + ": " + e.what());
    }
    const std::string source =
        "mesh '" + mesh.filename + "' (" + std::to_string(stl.triangles()) + " triangles, " +
        (stl.binary ? "binary" : "ASCII") + " STL" +
        (scale == Vector3d::Ones() ? std::string() : ", scale " + vector3_text(mesh.scale)) + ")";
    if (options_.link_geometry == LinkGeometry::kMesh) {
      g.type = "mesh";
      g.name = geom_name(link, collision, index, "mesh");
      g.mesh = g.name;
      MeshAsset a;
      a.name = g.name;
      a.what = m;
      if (scale != Vector3d::Ones()) a.scale = vector3_text(mesh.scale);
      std::string file = file_safe(g.name);
      for (int k = 2; !mesh_files_.insert(file).second; ++k)
        file = file_safe(g.name) + "_" + std::to_string(k);
      a.file.file = options_.mesh_folder + "/" + file + ".stl";
      a.file.source = path;
      a.file.bytes = binary_stl(
          stl.vertices, "leeway import-urdf: binary STL copy of " + fs::path(path).filename().string());
      mesh_assets_.push_back(std::move(a));
      return source + " as a mesh geom on its binary STL copy '" + mesh_assets_.back().file.file +
             "' (MuJoCo collides it as its convex hull)";
    }
    std::vector<Vector3d> points;
    points.reserve(stl.vertices.size());
    for (const auto& v : stl.vertices) points.push_back(v.cwiseProduct(scale));
    const auto [lo, hi] = bounding_box(points);
    g.half = (hi - lo) / 2;
    Isometry3d offset = Isometry3d::Identity();
    offset.translation() = (hi + lo) / 2;
    g.pose = g.pose * offset;
    return source + " as its axis-aligned bounding box in the mesh's frame";
  }

  // LINK_box for a link's only collision element (whatever its name: ROS-Industrial names them all
  // "collision"), else LINK_NAME_box for a named one and LINK_box_K for the K-th unnamed one; with
  // LinkGeometry::kMesh the geom's type instead of "box" (LINK_mesh, LINK_cylinder, ...).
  std::string geom_name(const std::string& link, const std::string& collision, int index,
                        const std::string& type) {
    std::string base = link + "_" + type;
    if (index > 0)
      base = collision.empty() ? base + "_" + std::to_string(index) : link + "_" + collision + "_" + type;
    std::string name = base;
    for (int k = 2; !geom_names_.insert(name).second; ++k) name = base + "_" + std::to_string(k);
    return name;
  }

  // The robot fragment's header comment: where it came from, how to include it, its geoms.
  std::string header(const std::string& robot, const std::string& base, const std::string& tool) const {
    std::ostringstream x;
    x << "<!--\n"
      << "  Robot '" << comment_text(robot) << "' imported from the URDF '"
      << comment_text(fs::path(file_).filename().string()) << "' by leeway import-urdf (docs/robots.md).\n"
      << "  Base link '" << comment_text(base) << "', tool link '" << comment_text(tool)
      << "' (the site tool0).\n"
      << "  Include it inside <worldbody>; the including model must use\n"
      << "  <compiler angle=\"radian\" autolimits=\"true\"/>. Units: metres, radians; joint user[0] is the\n"
      << "  URDF's <limit velocity> [rad/s or m/s].\n"
      << "  Every body frame is its URDF link frame (= its joint frame); links fixed to a moving link are\n"
      << "  merged into it. ";
    if (options_.link_geometry == LinkGeometry::kBox)
      x << "Collision: one box per URDF <collision> element (a box exactly, a cylinder as\n"
        << "  its tight box, a sphere as its cube, an STL mesh as its axis-aligned bounding box in the\n"
        << "  mesh's frame): the boxes contain the URDF's shapes, so leeway's checks err on the safe side.\n";
    else
      x << "Collision: one geom per URDF <collision> element, its own shape (a box,\n"
        << "  cylinder or sphere exactly; an STL mesh as a mesh geom on its binary STL copy in the folder\n"
        << "  '" << comment_text(options_.mesh_folder)
        << "' beside this file). MuJoCo collides a mesh geom as the\n"
        << "  convex hull of its vertices, which contains the mesh, so leeway's checks err on the safe "
           "side.\n"
        << "  The mesh assets are in the excludes fragment; MuJoCo 2.2.2 reads mesh files from the folder\n"
        << "  of the cell (the main file) and its <compiler meshdir>, so a cell in another folder sets\n"
        << "  meshdir to this file's folder (leeway new-cell does).\n";
    x << "  Robot geoms: contype=\"1\" conaffinity=\"0\" (they touch obstacles); leeway checks them\n"
      << "  against each other by its own rule (docs/mjcf-conventions.md, \"Self-collision\"). The pairs\n"
      << "  excluded from that check are in the second fragment written beside this one\n"
      << "  (NAME_excludes.xml for NAME.xml), which the cell includes at its top level.\n";
    for (const auto& n : notes_) x << "  Note: " << comment_text(n) << "\n";
    x << "-->\n";
    return x.str();
  }

  // A <geom> element (after its comment line), in body `body` (0: the base).
  static std::string geom_element(const Geom& g, const std::string& indent, size_t body) {
    std::string shape = "type=\"" + g.type + "\"";
    if (g.type == "mesh")
      shape += " mesh=\"" + xml_escape(g.mesh) + "\" " + pose_attributes(g.pose);
    else if (g.type == "cylinder")
      shape += " " + pose_attributes(g.pose) + " size=\"" + num(g.half.x()) + " " + num(g.half.z()) + "\"";
    else if (g.type == "sphere")
      shape += " " + pose_attributes(g.pose) + " size=\"" + num(g.half.x()) + "\"";
    else
      shape += " " + pose_attributes(g.pose) + " size=\"" + vec(g.half) + "\"";
    return indent + "<geom name=\"" + xml_escape(g.name) + "\" " + shape + "\n" + indent +
           "      contype=\"1\" conaffinity=\"0\" rgba=\"" + (body == 0 ? kBaseRgba : kLinkRgba) + "\"/>\n";
  }

  UrdfImport write(const std::string& base, const std::string& tool) {
    UrdfImport out;
    out.robot_name = model_->getName();
    std::ostringstream x;
    x << header(out.robot_name, base, tool) << "<mujoco>\n";
    std::string indent = "  ";
    for (size_t i = 0; i < bodies_.size(); ++i) {
      const Body& b = bodies_[i];
      x << indent << "<!-- " << comment_text(b.comment) << " -->\n";
      x << indent << "<body name=\"" << xml_escape(b.link) << "\" " << pose_attributes(b.pose) << ">\n";
      indent += "  ";
      if (b.joint) {
        const urdf::Joint& j = *b.joint;
        const bool slide = j.type == urdf::Joint::PRISMATIC;
        const double lo = j.type == urdf::Joint::CONTINUOUS ? -kTwoPi : j.limits->lower;
        const double hi = j.type == urdf::Joint::CONTINUOUS ? kTwoPi : j.limits->upper;
        if (j.type == urdf::Joint::CONTINUOUS)
          x << indent << "<!-- continuous: range -2 pi .. 2 pi rad -->\n";
        x << indent << "<joint name=\"" << xml_escape(j.name) << "\" type=\"" << (slide ? "slide" : "hinge")
          << "\" axis=\"" << vec(axis(j, file_)) << "\" range=\"" << num(lo) << " " << num(hi) << "\" user=\""
          << num(j.limits ? j.limits->velocity : 0.0) << "\"/>\n";
        out.joints.push_back(j.name);
      }
      if (b.geoms.empty() && b.joint) {
        // MuJoCo needs mass on a body with a joint; leeway only uses kinematics.
        x << indent << "<!-- no collision element: a placeholder inertia (kinematics only) -->\n"
          << indent << "<inertial pos=\"0 0 0\" mass=\"0.001\" diaginertia=\"1e-06 1e-06 1e-06\"/>\n";
      }
      for (const Geom& g : b.geoms) {
        x << indent << "<!-- " << comment_text(g.comment) << " -->\n" << geom_element(g, indent, i);
        ++out.boxes;
      }
      if (b.tool) {
        if (i == 0)
          throw InputError(file_ + ": tool link '" + tool +
                           "' does not move: it is fixed to the base link '" + base + "'");
        x << indent << "<site name=\"tool0\" " << pose_attributes(*b.tool)
          << " size=\"0.02\" rgba=\"1 0 0 1\"/>\n";
      }
    }
    for (size_t i = bodies_.size(); i-- > 0;) {
      indent.resize(indent.size() - 2);
      x << indent << "</body>\n";
    }
    x << "</mujoco>\n";
    out.mjcf = x.str();
    out.notes = notes_;
    out.inputs = {file_};
    out.inputs.insert(out.inputs.end(), meshes_read_.begin(), meshes_read_.end());
    return out;
  }

  // The fragment's bodies inside a world body, with the mesh assets: a cell leeway's Scene can load.
  std::string as_cell(const std::string& fragment, const std::string& custom) const {
    const size_t a = fragment.find("<mujoco>\n"), b = fragment.rfind("</mujoco>");
    LEEWAY_DEMAND(a != std::string::npos && b != std::string::npos && a < b);
    return "<mujoco>\n<compiler angle=\"radian\" autolimits=\"true\"/>\n" + asset_text() + custom +
           "<worldbody>\n" + fragment.substr(a + 9, b - a - 9) + "</worldbody>\n</mujoco>\n";
  }

  // The <asset> of the mesh geoms (indented for the excludes fragment); empty without meshes.
  std::string asset_text() const {
    if (mesh_assets_.empty()) return "";
    std::string x = "  <asset>\n";
    for (const MeshAsset& a : mesh_assets_)
      x += "    <mesh name=\"" + xml_escape(a.name) + "\" file=\"" + xml_escape(a.file.file) + "\"" +
           (a.scale.empty() ? "" : " scale=\"" + a.scale + "\"") + "/>\n";
    return x + "  </asset>\n";
  }

  // Loads the cell text with the mesh copies as virtual files (nothing is written yet). MuJoCo's
  // refusal of a mesh is reported for its collision element.
  Scene load_cell(const std::string& text) const {
    std::vector<std::pair<std::string, std::string>> files;
    for (const MeshAsset& a : mesh_assets_)
      files.emplace_back(fs::path(a.file.file).filename().string(), a.file.bytes);
    try {
      return Scene::from_model(load_text_with_files(text, file_ + ".leeway.xml", files), file_);
    } catch (const InputError& e) {
      const std::string what = e.what();
      for (const MeshAsset& a : mesh_assets_)
        if (what.find("Object name = " + a.name + ",") != std::string::npos)
          throw UrdfOptionError(a.what + ": MuJoCo cannot compile it as a mesh geom (" +
                                    what.substr(what.find(": MJCF does not compile: ") == std::string::npos
                                                    ? 0
                                                    : what.find(": MJCF does not compile: ") + 25) +
                                    "); import it as its bounding box instead",
                                "link_geometry");
      throw InputError(file_ + ": the imported robot does not load as a leeway robot: " + what);
    }
  }

  // The self-collision pairs to exclude (UrdfImport::excludes) and their fragment.
  void find_excludes(UrdfImport& out) {
    const Scene scene = load_cell(as_cell(out.mjcf, ""));
    const mjModel& m = scene.model();
    const Eigen::VectorXd q =
        Eigen::VectorXd::Zero(scene.dof()).cwiseMax(scene.lower_limits()).cwiseMin(scene.upper_limits());
    for (int i = 0; i < q.size(); ++i) out.reference += (i ? " " : "") + num(q[i]);
    auto key = [](int a, int b) { return std::make_pair(std::min(a, b), std::max(a, b)); };
    std::map<std::pair<int, int>, std::vector<std::string>> why;
    std::map<std::pair<int, int>, double> depth;
    RobotState state(scene);
    const bool boxes = options_.link_geometry == LinkGeometry::kBox;
    for (const SelfContact& c : self_contacts_within(state, q, kTouch)) {
      depth[key(c.geom1, c.geom2)] = c.depth;
      const bool two_boxes = m.geom_type[c.geom1] == mjGEOM_BOX && m.geom_type[c.geom2] == mjGEOM_BOX;
      const std::string touch = boxes       ? "the boxes touch (within " + num(kTouch) + " m)"
                                : two_boxes ? "the geoms touch (within " + num(kTouch) + " m)"
                                            : "the geoms touch";
      why[key(c.geom1, c.geom2)].push_back(
          (c.depth > kTouch ? (boxes ? "the boxes" : "the geoms") + std::string(" overlap by ") +
                                  format_number(c.depth) + " m"
                            : touch) +
          " at the reference configuration (every joint at 0 or the limit nearest 0), where the arm is "
          "taken to stand clear of itself: an artefact of the " +
          (boxes ? "box approximation" : "collision shapes (a mesh geom is its convex hull)") + "; check it");
    }
    std::string srdf_note;
    if (!options_.srdf.empty()) {
      srdf_note = srdf_excludes(scene, why);
      out.notes.push_back(srdf_note);
    }

    std::string texts;
    std::set<std::string> text_names;
    for (const RobotPair& p : scene.self_pairs()) {
      const auto w = why.find(key(p.geom1, p.geom2));
      if (w == why.end()) continue;
      UrdfExclude e;
      e.geom1 = object_name(m, mjOBJ_GEOM, p.geom1);
      e.geom2 = object_name(m, mjOBJ_GEOM, p.geom2);
      e.depth = depth.count(w->first) ? depth[w->first] : 0.0;
      for (const auto& r : w->second) e.reason += (e.reason.empty() ? "" : "; and ") + r;
      for (const std::string* g : {&e.geom1, &e.geom2})
        if (g->find_first_of(" \t\r\n") != std::string::npos)
          throw InputError(file_ + (boxes ? ": box '" : ": geom '") + *g +
                           "' must be excluded from self-collision (" + e.reason +
                           "), but a name with white space cannot be: rename its link");
      std::string name = "leeway_exclude_" + e.geom1 + "_" + e.geom2;
      for (int k = 2; !text_names.insert(name).second; ++k)
        name = "leeway_exclude_" + e.geom1 + "_" + e.geom2 + "_" + std::to_string(k);
      texts += detail::wrapped_comment(e.geom1 + " and " + e.geom2 + ": " + e.reason + ".", 4) +
               "    <text name=\"" + xml_escape(name) + "\" data=\"" + xml_escape(e.geom1 + " " + e.geom2) +
               "\"/>\n";
      out.excludes.push_back(std::move(e));
    }
    std::ostringstream x;
    x << "<!--\n"
      << "  Self-collision excludes of robot '" << comment_text(out.robot_name)
      << "' imported from the URDF '" << comment_text(fs::path(file_).filename().string())
      << "' by leeway import-urdf (docs/robots.md).\n"
      << "  Include this file at the top level of the cell, beside <worldbody> (an include inside the\n"
      << "  world body cannot carry <custom>); leeway new-cell does. leeway checks every other pair of\n"
      << "  robot " << (boxes ? "boxes" : "geoms")
      << " on parts that are neither the same nor parent and child\n"
      << "  (docs/mjcf-conventions.md, \"Self-collision\").\n";
    if (!mesh_assets_.empty())
      x << "  The <asset> holds the meshes of the robot's mesh geoms: binary STL copies in the folder\n"
        << "  '" << comment_text(options_.mesh_folder)
        << "' beside the robot fragment, named relative to it (MuJoCo 2.2.2 reads them from the\n"
        << "  cell's folder and its <compiler meshdir>: a cell in another folder sets meshdir to the robot\n"
        << "  fragment's folder).\n";
    if (!srdf_note.empty()) x << "  Note: " << comment_text(srdf_note) << "\n";
    x << "-->\n<mujoco>\n" << asset_text();
    if (texts.empty())
      // MuJoCo refuses an include without elements: an empty <custom> stands in.
      x << "  <!-- Nothing excluded: no two " << (boxes ? "boxes" : "geoms")
        << " checked against each other touch at the reference\n"
        << "       configuration (every joint at 0 or the limit nearest 0)"
        << (options_.srdf.empty() ? "" : ", and the SRDF disables no such pair") << ". -->\n"
        << "  <custom/>\n";
    else
      x << "  <custom>\n" << texts << "  </custom>\n";
    x << "</mujoco>\n";
    out.excludes_mjcf = x.str();

    // The excludes read back as leeway reads them: exactly these pairs leave the check.
    const Scene with =
        load_cell(as_cell(out.mjcf, texts.empty() ? "" : "<custom>\n" + texts + "</custom>\n"));
    LEEWAY_DEMAND(with.excluded_pairs().size() == out.excludes.size());
    out.self_pairs = static_cast<int>(with.self_pairs().size());
    for (const MeshAsset& a : mesh_assets_) out.meshes.push_back(a.file);
  }

  // The SRDF's <disable_collisions> entries, as reasons for the box pairs of the two links that
  // leeway checks; pairs it never checks (one rigid part, or parent and child) need no exclude.
  // Returns a one-line summary.
  std::string srdf_excludes(const Scene& scene,
                            std::map<std::pair<int, int>, std::vector<std::string>>& why) {
    const std::string& srdf = options_.srdf;
    require_regular_input(srdf, "SRDF file");
    {
      std::ifstream in(srdf, std::ios::binary);
      try {
        require_shallow_xml(std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()),
                            srdf);
      } catch (const MjcfSyntaxError& e) {
        // "SRDF: line N: reason" -> "SRDF: not a valid SRDF: reason (line N)", as TinyXML's are.
        const std::string what = std::string(e.what()).substr(srdf.size() + 2);
        const size_t colon = what.find(": ");
        throw InputError(srdf + ": not a valid SRDF: " +
                         (colon == std::string::npos
                              ? what
                              : what.substr(colon + 2) + " (" + what.substr(0, colon) + ")"));
      }
    }
    TiXmlDocument doc;
    if (!doc.LoadFile(srdf))
      throw InputError(srdf + ": not a valid SRDF: " + doc.ErrorDesc() + " (line " +
                       std::to_string(doc.ErrorRow()) + ")");
    const TiXmlElement* root = doc.RootElement();
    if (!root || root->ValueStr() != "robot")
      throw InputError(srdf + ": not a valid SRDF: the root element is not <robot>");
    const std::string name = fs::path(srdf).filename().string();
    const mjModel& m = scene.model();
    std::set<std::pair<int, int>> checked;
    for (const RobotPair& p : scene.self_pairs())
      checked.insert({std::min(p.geom1, p.geom2), std::max(p.geom1, p.geom2)});
    int entries = 0, unchecked = 0;
    for (const TiXmlElement* e = root->FirstChildElement("disable_collisions"); e;
         e = e->NextSiblingElement("disable_collisions")) {
      const char* l1 = e->Attribute("link1");
      const char* l2 = e->Attribute("link2");
      const char* reason = e->Attribute("reason");
      const std::string where = srdf + ": <disable_collisions> on line " + std::to_string(e->Row());
      if (!l1 || !l2) throw InputError(where + " needs both link1 and link2");
      for (const char* l : {l1, l2})
        if (!model_->getLink(l))
          throw InputError(where + " names link '" + l + "', which the URDF '" + file_ + "' does not have");
      ++entries;
      bool any = false;
      for (const Body& b1 : bodies_)
        for (const Geom& g1 : b1.geoms)
          for (const Body& b2 : bodies_)
            for (const Geom& g2 : b2.geoms) {
              if (g1.link != l1 || g2.link != l2) continue;
              const int a = mj_name2id(&m, mjOBJ_GEOM, g1.name.c_str()),
                        b = mj_name2id(&m, mjOBJ_GEOM, g2.name.c_str());
              const auto k = std::make_pair(std::min(a, b), std::max(a, b));
              if (!checked.count(k)) continue;
              any = true;
              const std::string r = "the SRDF '" + name + "' disables collisions between links '" + l1 +
                                    "' and '" + l2 + "'" +
                                    (reason ? " (reason '" + std::string(reason) + "')" : std::string());
              if (std::find(why[k].begin(), why[k].end(), r) == why[k].end()) why[k].push_back(r);
            }
      if (!any) ++unchecked;
    }
    return "the SRDF '" + name + "' disables " + std::to_string(entries) + " link pair(s); " +
           std::to_string(unchecked) +
           (options_.link_geometry == LinkGeometry::kBox
                ? " of them have no box pair leeway checks (one rigid part, parent and child, or no boxes)"
                : " of them have no geom pair leeway checks (one rigid part, parent and child, or no geoms)");
  }

  std::string file_, urdf_dir_;
  const UrdfImportOptions& options_;
  urdf::ModelInterfaceSharedPtr model_;
  std::set<std::string> chain_;  // joint names from the base to the tool
  std::vector<Body> bodies_;
  std::vector<std::string> notes_;
  std::vector<std::string> meshes_read_;
  std::set<std::string> geom_names_;
  std::vector<MeshAsset> mesh_assets_;  // LinkGeometry::kMesh: in the order of their geoms
  std::set<std::string> mesh_files_;    // the copies' file names (without .stl)
};

}  // namespace

std::string resolve_urdf_resource(const std::string& uri, const std::string& urdf_dir,
                                  const UrdfImportOptions& options, const std::string& what) {
  const std::string package = "package://", file = "file://";
  if (uri.rfind(package, 0) == 0) {
    const std::string rest = uri.substr(package.size());
    const size_t slash = rest.find('/');
    const std::string name = rest.substr(0, slash);
    if (name.empty() || slash == std::string::npos)
      throw InputError(what + ": '" + uri + "' is not package://NAME/PATH");
    // The file must stay inside its package: no "..", as a name or climbing above the package.
    const fs::path inside = fs::path(rest.substr(slash + 1)).lexically_normal();
    if (name == "." || name == ".." || inside.empty() || inside.is_absolute() || *inside.begin() == "..")
      throw InputError(what + ": '" + uri +
                       "' leaves its package; package://NAME/PATH names a file inside it");
    std::vector<std::string> roots = options.package_paths;
    for (const auto& p : split_paths(options.ros_package_path)) roots.push_back(p);
    try {
      for (const auto& root : roots)
        if (const auto dir = find_package_in(root, name)) return (*dir / inside).string();
    } catch (const InputError& e) {
      throw InputError(what + ": " + e.what());
    }
    throw InputError(what + ": no ROS package '" + name + "' under the package paths " +
                     join_names(options.package_paths) + " or ROS_PACKAGE_PATH '" + options.ros_package_path +
                     "' (a package is a folder of that name, or one holding a package.xml naming it)");
  }
  std::string path = uri;
  if (uri.rfind(file, 0) == 0)
    path = uri.substr(file.size());
  else if (uri.find("://") != std::string::npos)
    throw InputError(what + ": '" + uri +
                     "' has a scheme leeway does not read (package://, file:// or a path)");
  if (path.empty()) throw InputError(what + ": empty file name");
  return fs::path(path).is_absolute() ? path : (fs::path(urdf_dir) / path).string();
}

const char* link_geometry_name(LinkGeometry g) { return g == LinkGeometry::kBox ? "box" : "mesh"; }

LinkGeometry parse_link_geometry(const std::string& name) {
  if (name == "mesh") return LinkGeometry::kMesh;
  if (name == "box") return LinkGeometry::kBox;
  throw InputError("link geometry '" + name + "' is not one of: mesh, box");
}

std::string mesh_folder_path(const std::string& robot_path) {
  const fs::path p(robot_path);
  return (p.parent_path() / (p.stem().string() + "_meshes")).string();
}

UrdfImport import_urdf(const std::string& urdf_path, const UrdfImportOptions& options) {
  return Importer(urdf_path, options).run();
}

std::string excludes_path(const std::string& robot_path) {
  const fs::path p(robot_path);
  return (p.parent_path() / (p.stem().string() + "_excludes" + p.extension().string())).string();
}

}  // namespace leeway
