#pragma once
//! @file new_cell.hpp
//! A minimal workcell around a robot fragment (an imported or hand-written robot MJCF): a visual
//! floor, the robot, a home keyframe and the robot's reach, ready for obstacles and goals.

#include <string>

namespace leeway {

//! What new_cell wrote.
struct NewCell {
  std::string mjcf;           //!< the cell's text
  int joints = 0;             //!< robot joints
  std::string home;           //!< the home keyframe's values [rad or m], space-separated
  double reach_radius = 0;    //!< the cell's leeway_reach_radius [m]
  std::string robot_include;  //!< the include path written (relative to the cell's folder when possible)
};

//! Writes a cell at `cell_path` that includes the robot fragment `robot_path` and passes leeway's
//! checker (check_scene): a visual-only floor, the robot at the world origin, a keyframe `home`
//! (every joint at the value nearest 0 within its limits) and the custom numeric
//! `leeway_reach_radius`, an upper bound of how far the robot's links and tool site reach from its
//! first hinge joint, rounded up to 0.1 m. The file is written atomically and only once the cell
//! compiles and passes the check.
//! @throws InputError naming the file when the robot file is missing, the cell does not compile or
//! is not a usable leeway cell (the robot recognised by docs/mjcf-conventions.md), or the check fails.
NewCell write_new_cell(const std::string& robot_path, const std::string& cell_path,
                       const std::string& model_name);

}  // namespace leeway
