#pragma once
//! @file new_cell.hpp
//! A minimal workcell around a robot fragment (an imported or hand-written robot MJCF): a visual
//! floor, the robot, its self-collision excludes, a home keyframe and the robot's reach, ready for
//! obstacles and goals.

#include <string>
#include <vector>

namespace leeway {

//! A pair of robot geoms the new cell itself excludes from self-collision.
struct CellExclude {
  std::string geom1;  //!< on the part nearer the robot's root
  std::string geom2;
  double depth = 0;    //!< how far they overlap at the keyframe [m]
  std::string reason;  //!< the sentence written beside the exclude
};

//! What new_cell wrote.
struct NewCell {
  std::string mjcf;           //!< the cell's text
  int joints = 0;             //!< robot joints
  std::string home;           //!< the home keyframe's values [rad or m], space-separated
  double reach_radius = 0;    //!< the cell's leeway_reach_radius [m]
  std::string robot_include;  //!< the include path written (relative to the cell's folder when possible)
  //! The robot's excludes fragment included at the cell's top level (written as robot_include), or
  //! empty when there is none.
  std::string excludes_include;
  int included_excludes = 0;  //!< pairs that fragment excludes
  //! The <compiler meshdir> written: the robot's folder relative to the cell's when the excludes
  //! fragment names mesh files (import-urdf's mesh geoms) and the cell is in another folder; else
  //! empty (none written).
  std::string meshdir;
  //! Pairs that still touched at the home keyframe, excluded in the cell itself (with a comment each).
  std::vector<CellExclude> cell_excludes;
  int self_pairs = 0;  //!< robot geom pairs the cell checks for self-collision
};

//! Writes a cell at `cell_path` that includes the robot fragment `robot_path` and passes leeway's
//! checker (check_scene): a visual-only floor, the robot at the world origin, a keyframe `home`
//! (every joint at the value nearest 0 within its limits) and the custom numeric
//! `leeway_reach_radius`, an upper bound of how far the robot's links and tool site reach from its
//! first hinge joint, rounded up to 0.1 m. Self-collision: the excludes fragment `excludes_path`
//! (empty: excludes_path(robot_path) from urdf_import.hpp when that file exists) is included at the
//! top level, and every robot geom pair still touching at `home` is excluded in the cell itself as a
//! leeway_exclude custom text with a comment giving the overlap. When the excludes fragment names
//! mesh files (import-urdf's mesh geoms, named relative to the robot's folder) and the cell is in
//! another folder, the cell's <compiler meshdir> names the robot's folder relative to the cell. The file is
//! written atomically and only once the cell compiles and passes the check.
//! @throws InputError naming the file when the robot or the given excludes file is missing, the
//! cell does not compile or is not a usable leeway cell (the robot recognised by
//! docs/mjcf-conventions.md), or the check fails.
NewCell write_new_cell(const std::string& robot_path, const std::string& cell_path,
                       const std::string& model_name, const std::string& excludes_path = "");

}  // namespace leeway
