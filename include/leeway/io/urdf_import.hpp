#pragma once
//! @file urdf_import.hpp
//! A URDF robot (ROS, ROS-Industrial) turned into an MJCF robot fragment in leeway's conventions
//! (docs/mjcf-conventions.md, "Writing your own robot"; docs/robots.md): one body per moving link
//! with its frame at the joint, fixed links merged into their parent, one geom per collision element
//! (the URDF's shape, a collision mesh as a MuJoCo mesh geom; or one box each), and the self-collision
//! excludes those geoms need (a second fragment, for the cell's top level, which also holds the mesh
//! assets).

#include <string>
#include <utility>
#include <vector>

#include "leeway/core/error.hpp"

namespace leeway {

//! What each URDF <collision> element becomes.
enum class LinkGeometry {
  //! Its own shape: a box, cylinder or sphere as the same MuJoCo primitive, an STL mesh as a mesh
  //! geom (which MuJoCo collides as its convex hull) on a binary STL copy of the mesh.
  kMesh,
  //! One box that contains it (a mesh: the axis-aligned bounding box of its vertices in its frame).
  kBox,
};

//! "mesh" or "box".
const char* link_geometry_name(LinkGeometry g);

//! The LinkGeometry named "mesh" or "box".
//! @throws InputError naming the value when it is neither.
LinkGeometry parse_link_geometry(const std::string& name);

//! How a URDF is imported.
struct UrdfImportOptions {
  //! Folders searched first for `package://NAME/...` (a package NAME is a folder NAME directly in
  //! one of them, or any folder below one holding a package.xml with <name>NAME</name>).
  std::vector<std::string> package_paths;
  //! Then these, as the environment variable ROS_PACKAGE_PATH gives them (folders separated by ':').
  std::string ros_package_path;
  std::string base_link;            //!< the robot's fixed base; empty: the URDF's root link
  std::string tool_link = "tool0";  //!< the link whose frame becomes the site tool0
  //! Continuous joints get the range -2 pi .. 2 pi rad instead of being refused.
  bool continuous_full_turn = false;
  //! An SRDF file (MoveIt's semantic description) whose <disable_collisions link1 link2 reason>
  //! pairs are excluded too; empty: none.
  std::string srdf;
  LinkGeometry link_geometry = LinkGeometry::kMesh;  //!< shapes as they are, or one box each
  //! With LinkGeometry::kMesh: the folder of the mesh copies, as the fragments name it (relative to
  //! the robot fragment's folder; see mesh_folder_path).
  std::string mesh_folder = "meshes";
};

//! A binary STL copy of a collision mesh, for the mesh asset that names it.
struct UrdfMeshFile {
  std::string file;    //!< as the <mesh file> attribute names it: MESH_FOLDER/GEOM.stl
  std::string source;  //!< the STL file it copies (as resolved)
  std::string bytes;   //!< the binary STL (the source's vertices as 32-bit floats, unscaled)
};

//! A pair of robot boxes the import excludes from self-collision, and why.
struct UrdfExclude {
  std::string geom1;  //!< the box on the part nearer the base
  std::string geom2;
  double depth = 0;    //!< how far the boxes overlap at the reference configuration [m]; 0 when they do not
  std::string reason;  //!< one sentence: the overlap at the reference configuration, the SRDF entry, or both
};

//! An imported robot.
struct UrdfImport {
  std::string robot_name;           //!< the URDF's <robot name>
  std::string mjcf;                 //!< the MJCF fragment (a <mujoco> element to include in <worldbody>)
  std::vector<std::string> joints;  //!< robot joints in model order
  int boxes = 0;                    //!< collision geoms written (all of them boxes with LinkGeometry::kBox)
  //! The excludes fragment: a <mujoco> element whose <custom> holds one leeway_exclude text per
  //! entry of `excludes`, each with a comment saying why, and with mesh geoms the <asset> of their
  //! meshes; include it at the top level of a cell (beside <worldbody>: an include inside it can
  //! carry neither <custom> nor <asset>). Written even when empty.
  std::string excludes_mjcf;
  //! The mesh copies the excludes fragment's assets name (LinkGeometry::kMesh), to be written
  //! beside the robot fragment.
  std::vector<UrdfMeshFile> meshes;
  //! The pairs excluded: every pair of boxes leeway would check for self-collision (Scene::self_pairs())
  //! that overlaps at the reference configuration, and the SRDF's disabled pairs; in the order of
  //! Scene::self_pairs().
  std::vector<UrdfExclude> excludes;
  int self_pairs = 0;     //!< box pairs leeway still checks for self-collision
  std::string reference;  //!< the reference configuration [rad or m], space-separated
  //! What the import changed or approximated beyond the one-box-per-element rule (frozen joints,
  //! thin boxes, a skipped world link), one line each; also written as comments in `mjcf`.
  std::vector<std::string> notes;
  //! The files the import read: the URDF, then each mesh file (as resolved), for refusing an output
  //! that would replace one of them.
  std::vector<std::string> inputs;
};

//! An import that one of UrdfImportOptions' fields would let through (a continuous joint, a
//! missing tool or base link, a mesh MuJoCo cannot compile); `field` names it so a program can name
//! its own option.
class UrdfOptionError : public InputError {
 public:
  UrdfOptionError(const std::string& message, std::string field)
      : InputError(message), field_(std::move(field)) {}
  //! "continuous_full_turn", "tool_link", "base_link" or "link_geometry" (a mesh MuJoCo cannot
  //! compile as a mesh geom, which LinkGeometry::kBox imports as its box).
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

//! Imports a URDF file (parsed by urdfdom; meshes must be STL). The robot is the chain from the
//! base link to the tool link: its revolute, continuous and prismatic joints become hinge and slide
//! joints with the URDF's limits and user[0] = <limit velocity>; every other link below the base is
//! merged into the body it hangs from, with joints off the chain frozen at 0 (clamped to their
//! limits). Collision elements become geoms as options.link_geometry says. The result is loaded as a
//! cell with leeway's Scene (mesh geoms as MuJoCo compiles them, on their convex hulls): every pair
//! of geoms that it checks for self-collision and that touches at the reference configuration (every
//! joint at 0, or at the limit nearest 0: what new-cell's home keyframe is; boxes within 1e-6 m, other
//! geoms by MuJoCo's collision function) is excluded, with the overlap in a comment; the URDF's zero
//! pose is collision-free for the real arm, so such an overlap is the approximation's.
//! Deterministic: the same file and options give the same text.
//! @throws InputError naming the file, element and value: unreadable or invalid URDF (urdfdom's
//! message), a link with two parent joints (a loop), a pose, size or limit that is not a finite
//! number or is empty, a mesh that cannot be resolved, found or read as STL, or (as a mesh geom)
//! that MuJoCo cannot compile, a chain joint that is floating, planar or mimics another, no moving
//! joint or no collision element on the moving links, an SRDF that cannot be read or names a link
//! the URDF does not have;
//! UrdfOptionError for an unknown base or tool link or a refused continuous joint.
UrdfImport import_urdf(const std::string& urdf_path, const UrdfImportOptions& options = {});

//! Where the excludes fragment of the robot fragment `robot_path` lives: beside it, named
//! STEM_excludes.EXT (mjcf/robots/NAME.xml: mjcf/robots/NAME_excludes.xml). import-urdf writes it
//! there and new-cell includes it from there.
std::string excludes_path(const std::string& robot_path);

//! Where the mesh copies of the robot fragment `robot_path` live: the folder STEM_meshes beside it
//! (mjcf/robots/NAME.xml: mjcf/robots/NAME_meshes). import-urdf writes them there.
std::string mesh_folder_path(const std::string& robot_path);

//! The file a URDF resource refers to: `package://NAME/rest` through the package paths of
//! `options`, `file://` paths and plain paths (relative ones from `urdf_dir`).
//! @throws InputError naming `what` and the URI when the scheme is unknown or the package is not
//! found (an existing package path is returned even when the file in it is missing).
std::string resolve_urdf_resource(const std::string& uri, const std::string& urdf_dir,
                                  const UrdfImportOptions& options, const std::string& what);

}  // namespace leeway
