#pragma once
//! @file volume.hpp
//! Volume generation (thesis section 3.2): a height-map over the floor and a box per cell whose
//! height is the height function (eq. 3.1 with eq. 4.1), zero beyond reach and under the trail.

#include <Eigen/Core>
#include <vector>

#include "leeway/core/box.hpp"
#include "leeway/core/categorize.hpp"
#include "leeway/core/params.hpp"

namespace leeway {

//! The resolved grid: cell (i, j) has centre (origin_x + (i + 0.5) * side, origin_y + (j + 0.5) * side).
struct Grid {
  double origin_x = 0, origin_y = 0;
  double side = 0;  //!< cell side [m] = sqrt(x_dim * y_dim / MAX_cells)
  int rows = 0;     //!< cells along x = round(x_dim / side)
  int cols = 0;     //!< cells along y = round(y_dim / side)
};

//! Resolves the grid of section 3.2.1 from explicit or automatic extents.
//! @throws InputError on non-positive dimensions or MAX_cells, auto extent without arm-base
//! positions, or a map so elongated that rounding would give more than 4 MAX_cells cells.
Grid make_grid(const HeightMapParams& p, const Categories& c, const VolumeParams& v);

//! Height function h(c) [m] at a point of the floor (eq. 3.1, goal term per eq. 4.1 when enabled),
//! without the activation: each normalised distance fraction is clamped to [0, 1] before its
//! exponent, so each term stays within [0, h_max] (see docs/algorithm.md).
//! Distances are from `cell_center` to the nearest trail box, the goal obstacle and the nearest
//! non-goal obstacle, measured as `v.distance` says. A missing goal contributes its saturated value.
//! @throws InputError on invalid parameters (Params::validate's messages) or non-finite boxes.
double height(const Eigen::Vector2d& cell_center, const Categories& c, const VolumeParams& v);

//! The volume: one box per cell with h > 0 and A_t != 0 (A_t = 0 beyond reach_radius from every
//! arm-base position, and where a box of the maximum possible height on that cell would touch a
//! trail box), plus the obstacle boxes when v.add_obstacle_boxes.
struct Volume {
  Grid grid;
  std::vector<Box> boxes;
  int cells_evaluated = 0;     //!< rows * cols
  int cells_under_trail = 0;   //!< cells within reach whose max-height box touches a trail box
  int cells_out_of_reach = 0;  //!< cells beyond reach (counted here even when also under the trail)
};

//! Generates the volume. Deterministic.
//! @throws InputError on invalid parameters, non-finite boxes or no arm-base position.
Volume generate_volume(const Categories& c, const HeightMapParams& hm, const VolumeParams& v);

}  // namespace leeway
