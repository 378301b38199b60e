#pragma once
//! @file export_mjcf.hpp
//! The cell with its generated volume as an MJCF file that MuJoCo's viewer opens
//! (`mujoco-simulate volume.xml`), or as a compiled binary model (MJB) for large volumes.

#include <string>
#include <vector>

#include "leeway/core/box.hpp"

namespace leeway {

//! Name of the static body holding the exported volume's geoms (`leeway_volume_box_<i>`).
inline constexpr const char* kExportBodyName = "leeway_volume_boxes";

//! The MJCF text of the cell at `cell_path` with `boxes` added as named static box geoms in a body
//! kExportBodyName at the end of the worldbody: visual only (contype = conaffinity = 0), coloured by
//! the height of their top as leeway's renders colour them, semi-transparent. The file is meant to be
//! written at `out_path`: the cell's includes are inlined (MuJoCo resolves nested includes against
//! the main file's folder) and the remaining relative paths (compiler meshdir and texturedir, asset
//! files) are rewritten relative to the output's folder.
//! @throws InputError naming the file when the cell or an included file cannot be read, an include
//! nests deeper than 16 levels, or the cell has no </worldbody>.
std::string volume_mjcf(const std::string& cell_path, const std::vector<Box>& boxes,
                        const std::string& out_path);

//! The same model compiled by MuJoCo and saved in its binary format (mj_saveModel), as bytes.
//! @throws InputError when MuJoCo does not compile it (the message names the file and MuJoCo's error).
std::string volume_mjb(const std::string& cell_path, const std::vector<Box>& boxes,
                       const std::string& out_path);

}  // namespace leeway
