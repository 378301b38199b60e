#pragma once
//! @file urdf_import.hpp
//! A URDF robot (ROS, ROS-Industrial) turned into an MJCF robot fragment in leeway's conventions
//! (docs/mjcf-conventions.md, "Writing your own robot"; docs/robots.md): one body per moving link
//! with its frame at the joint, fixed links merged into their parent, one box per collision element.

#include <string>
#include <utility>
#include <vector>

#include "leeway/error.hpp"

namespace leeway {

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
};

//! An imported robot.
struct UrdfImport {
  std::string robot_name;           //!< the URDF's <robot name>
  std::string mjcf;                 //!< the MJCF fragment (a <mujoco> element to include in <worldbody>)
  std::vector<std::string> joints;  //!< robot joints in model order
  int boxes = 0;                    //!< collision boxes written
  //! What the import changed or approximated beyond the one-box-per-element rule (frozen joints,
  //! thin boxes, a skipped world link), one line each; also written as comments in `mjcf`.
  std::vector<std::string> notes;
  //! The files the import read: the URDF, then each mesh file (as resolved), for refusing an output
  //! that would replace one of them.
  std::vector<std::string> inputs;
};

//! An import that one of UrdfImportOptions' fields would let through (a continuous joint, a
//! missing tool or base link); `field` names it so a program can name its own option.
class UrdfOptionError : public InputError {
 public:
  UrdfOptionError(const std::string& message, std::string field)
      : InputError(message), field_(std::move(field)) {}
  //! "continuous_full_turn", "tool_link" or "base_link".
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

//! Imports a URDF file (parsed by urdfdom; meshes must be STL). The robot is the chain from the
//! base link to the tool link: its revolute, continuous and prismatic joints become hinge and slide
//! joints with the URDF's limits and user[0] = <limit velocity>; every other link below the base is
//! merged into the body it hangs from, with joints off the chain frozen at 0 (clamped to their
//! limits). Deterministic: the same file and options give the same text.
//! @throws InputError naming the file, element and value: unreadable or invalid URDF (urdfdom's
//! message), a link with two parent joints (a loop), a pose, size or limit that is not a finite
//! number or is empty, a mesh that cannot be resolved, found or read as STL, a chain joint that is
//! floating, planar or mimics another, no moving joint or no collision element on the moving links;
//! UrdfOptionError for an unknown base or tool link or a refused continuous joint.
UrdfImport import_urdf(const std::string& urdf_path, const UrdfImportOptions& options = {});

//! The file a URDF resource refers to: `package://NAME/rest` through the package paths of
//! `options`, `file://` paths and plain paths (relative ones from `urdf_dir`).
//! @throws InputError naming `what` and the URI when the scheme is unknown or the package is not
//! found (an existing package path is returned even when the file in it is missing).
std::string resolve_urdf_resource(const std::string& uri, const std::string& urdf_dir,
                                  const UrdfImportOptions& options, const std::string& what);

}  // namespace leeway
