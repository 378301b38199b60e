#pragma once
//! @file cell_defaults.hpp
//! Cell-specific defaults of the method's parameters, read from the cell's MJCF custom numerics,
//! and compose_params(), the one order in which a run's parameters are layered.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "leeway/core/params.hpp"
#include "leeway/core/scene.hpp"

namespace leeway {

//! Cell-specific defaults read from MJCF custom numerics (docs/mjcf-conventions.md):
//! `leeway_reach_radius` [m] and `leeway_add_obstacle_boxes` (0 or 1). Applied to `params`.
//! @throws InputError on a non-finite or out-of-range value.
void apply_cell_defaults(const Scene& scene, Params& params);

//! The layers of a run's parameters, each over the one before.
struct ParamLayers {
  std::string preset = "leeway";  //!< preset_params(): "leeway" or "thesis"
  std::string file;               //!< a parameter file (read_params()), or ""
  nlohmann::json object;          //!< parameters as a JSON object (params_from_json()), or null
  std::string object_source = "the parameters";  //!< names `object` in messages
  std::optional<SafetyMode> safety;              //!< the safety mode, over the preset's and the file's
};

//! A run's parameters, as every command, leeway batch, leeway-tune and the Python module build
//! them: the preset, then the cell's own defaults (apply_cell_defaults()), then the keys present in
//! the file, then those in the object, then the safety mode. Not validated: the caller applies its
//! own flags (MAX_cells, CF settings) and then validates.
//! @throws InputError on an unknown preset, a bad cell default, a bad file or object.
Params compose_params(const Scene& scene, const ParamLayers& layers);

}  // namespace leeway
