#pragma once
//! @file cell_defaults.hpp
//! Cell-specific defaults of the method's parameters, read from the cell's MJCF custom numerics.

#include "leeway/params.hpp"
#include "leeway/scene.hpp"

namespace leeway {

//! Cell-specific defaults read from MJCF custom numerics (docs/mjcf-conventions.md):
//! `leeway_reach_radius` [m] and `leeway_add_obstacle_boxes` (0 or 1). Applied to `params`.
//! @throws InputError on a non-finite or out-of-range value.
void apply_cell_defaults(const Scene& scene, Params& params);

}  // namespace leeway
