#include "leeway/core/volume.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>

#include "leeway/core/error.hpp"

namespace leeway {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

Box box(const Vector3d& center, const Vector3d& half_size,
        const Eigen::Matrix3d& rotation = Eigen::Matrix3d::Identity()) {
  Box b;
  b.center = center;
  b.half_size = half_size;
  b.rotation = rotation;
  return b;
}

Eigen::Matrix3d about(const Vector3d& axis, double angle) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

HeightMapParams explicit_map(double x0, double y0, double x_dim, double y_dim, int max_cells) {
  HeightMapParams p;
  p.auto_extent = false;
  p.origin_x = x0;
  p.origin_y = y0;
  p.x_dim = x_dim;
  p.y_dim = y_dim;
  p.max_cells = max_cells;
  return p;
}

// ---------------------------------------------------------------------------------------------
// Grid (section 3.2.1)

TEST(GridTest, ExplicitExtent) {
  // side = sqrt(10 * 5 / 200) = sqrt(0.25) = 0.5; rows = 10 / 0.5 = 20; cols = 5 / 0.5 = 10.
  const Grid g = make_grid(explicit_map(-2, 1, 10, 5, 200), {}, {});
  EXPECT_DOUBLE_EQ(g.side, 0.5);
  EXPECT_EQ(g.rows, 20);
  EXPECT_EQ(g.cols, 10);
  EXPECT_EQ(g.origin_x, -2.0);
  EXPECT_EQ(g.origin_y, 1.0);
}

TEST(GridTest, RowsAndColsAreRounded) {
  // side = sqrt(3 * 1 / 10) = sqrt(0.3) = 0.547723; rows = round(3 / 0.547723 = 5.477) = 5;
  // cols = round(1 / 0.547723 = 1.826) = 2: 10 cells asked, 10 given, but not 3 m x 1 m exactly.
  const Grid g = make_grid(explicit_map(0, 0, 3, 1, 10), {}, {});
  EXPECT_NEAR(g.side, 0.5477225575, 1e-9);
  EXPECT_EQ(g.rows, 5);
  EXPECT_EQ(g.cols, 2);
  // side = sqrt(1 * 1 / 2) = 0.7071; rows = cols = round(1.414) = 1: one cell where 2 were asked.
  const Grid h = make_grid(explicit_map(0, 0, 1, 1, 2), {}, {});
  EXPECT_EQ(h.rows, 1);
  EXPECT_EQ(h.cols, 1);
}

TEST(GridTest, AutoExtentCoversReachOfEveryBase) {
  // Bases (0, 0) and (2, 1), reach 1: x in [-1, 3], y in [-1, 2], a 4 x 3 m map; 12 cells of 1 m.
  Categories c;
  c.arm_base = {{0, 0}, {2, 1}, {0, 0}};
  HeightMapParams hm;
  hm.max_cells = 12;
  hm.origin_x = 100;  // ignored with auto_extent
  VolumeParams v;
  v.reach_radius = 1.0;
  const Grid g = make_grid(hm, c, v);
  EXPECT_DOUBLE_EQ(g.origin_x, -1.0);
  EXPECT_DOUBLE_EQ(g.origin_y, -1.0);
  EXPECT_DOUBLE_EQ(g.side, 1.0);
  EXPECT_EQ(g.rows, 4);
  EXPECT_EQ(g.cols, 3);
}

TEST(GridTest, BadInputsThrow) {
  HeightMapParams hm;  // auto_extent without arm bases
  EXPECT_THROW(make_grid(hm, {}, {}), InputError);
  EXPECT_THROW(make_grid(explicit_map(0, 0, 0, 1, 10), {}, {}), InputError);
  EXPECT_THROW(make_grid(explicit_map(0, 0, 1, -1, 10), {}, {}), InputError);
  EXPECT_THROW(make_grid(explicit_map(0, 0, std::nan(""), 1, 10), {}, {}), InputError);
  EXPECT_THROW(make_grid(explicit_map(0, 0, 1, 1, 0), {}, {}), InputError);
  // 1000 m x 1 mm with 10 cells: side 0.316 m, 3162 x 1 cells after rounding; refused.
  try {
    make_grid(explicit_map(0, 0, 1000, 0.001, 10), {}, {});
    ADD_FAILURE() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("max_cells"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// Height function (eq. 3.1, eq. 4.1); the cell is at the origin unless said otherwise.

//! Trail box footprint x in [0.925, 1.925], y in [-0.1, 0.1]: 0.925 m from the origin.
//! Goal footprint x in [-0.3, 0.3], y in [-2.05, -1.05]: 1.05 m. Non-goal x in [-1.25, -0.25]: 0.25 m.
//! All stand on the floor, so 3D distances from (0, 0, 0) equal the plane ones.
Categories hand_scene() {
  Categories c;
  c.trail = {box({1.425, 0, 0.5}, {0.5, 0.1, 0.5})};
  c.goal = box({0, -1.55, 0.25}, {0.3, 0.5, 0.25});
  c.non_goal = {box({-0.75, 0, 0.5}, {0.5, 0.5, 0.5})};
  return c;
}

TEST(HeightTest, ThesisDefaultsByHand) {
  // trail: (0.925 - 0.35) / (1.5 - 0.35) = 0.5 -> 1.5 * 0.5 = 0.75
  // goal (eq. 4.1): (1.05 - 0.1) / (2.0 - 0.1) = 0.5 -> 1.5 / 3 + 2/3 * 1.5 * 0.5 = 0.5 + 0.5 = 1.0
  // non-goal: (0.5 - 0.25) / 0.5 = 0.5 -> 0.75;  total 2.5 m
  EXPECT_NEAR(height({0, 0}, hand_scene(), VolumeParams{}), 2.5, 1e-12);
  VolumeParams v3;
  v3.distance = DistanceMode::k3d;
  EXPECT_NEAR(height({0, 0}, hand_scene(), v3), 2.5, 1e-12);
}

TEST(HeightTest, ExponentsTwo) {
  // 0.5^2 = 0.25: trail 1.5 * 0.25 = 0.375; goal 0.5 + 1.0 * 0.25 = 0.75; non-goal 0.375; total 1.5.
  VolumeParams v;
  v.alpha_t = v.alpha_g = v.alpha_ng = 2.0;
  EXPECT_NEAR(height({0, 0}, hand_scene(), v), 1.5, 1e-12);
}

TEST(HeightTest, GoalTermOfEq31WithoutConstant) {
  // goal: 1.5 * 0.5 = 0.75; total 0.75 + 0.75 + 0.75 = 2.25.
  VolumeParams v;
  v.goal_constant_term = false;
  EXPECT_NEAR(height({0, 0}, hand_scene(), v), 2.25, 1e-12);
}

TEST(HeightTest, EmptyCategories) {
  // No trail and no goal: both saturated (1.5 + 1.5); no non-goal obstacle: 0. Total 2 h_max = 3.0.
  EXPECT_NEAR(height({0, 0}, Categories{}, VolumeParams{}), 3.0, 1e-12);
  VolumeParams v;
  v.goal_constant_term = false;  // 1.5 * 1 as well
  EXPECT_NEAR(height({7, -3}, Categories{}, v), 3.0, 1e-12);
}

TEST(HeightTest, TrailTermClamped) {
  Categories c;
  c.trail = {box({0, 0, 1}, {0.2, 0.2, 0.2})};  // floating above the cell: plane distance 0
  // Inside the footprint: d_t = 0 < d_t,LB -> 0, not h_max * (-0.35 / 1.15); goal saturated 1.5.
  EXPECT_NEAR(height({0, 0}, c, VolumeParams{}), 1.5, 1e-12);
  // 0.2 + 0.35 = 0.55 m from the centre is exactly d_t,LB from the footprint: still 0.
  EXPECT_NEAR(height({0.55, 0}, c, VolumeParams{}), 1.5, 1e-12);
  // 3 m away: beyond d_t,UB -> h_max, not 1.5 * (2.8 / 1.15); total 3.0.
  EXPECT_NEAR(height({3.2, 0}, c, VolumeParams{}), 3.0, 1e-12);
}

TEST(HeightTest, GoalTermClamped) {
  Categories c;
  c.goal = box({0, 0, 0.25}, {0.5, 0.5, 0.25});
  // 0.05 m from the goal (< d_g,LB = 0.1): eq. 4.1 leaves the constant 0.5; + trail 1.5 = 2.0.
  EXPECT_NEAR(height({0.55, 0}, c, VolumeParams{}), 2.0, 1e-12);
  VolumeParams v;
  v.goal_constant_term = false;  // eq. 3.1: 0 + 1.5
  EXPECT_NEAR(height({0.55, 0}, c, v), 1.5, 1e-12);
  // 5 m away (> d_g,UB = 2): 0.5 + 1.0 = 1.5 (not 0.5 + 1.0 * 4.9 / 1.9); total 3.0.
  EXPECT_NEAR(height({5.5, 0}, c, VolumeParams{}), 3.0, 1e-12);
}

TEST(HeightTest, NonGoalTermClamped) {
  Categories c;
  c.non_goal = {box({0, 0, 0.25}, {0.5, 0.5, 0.25})};
  // Inside: d_ng = 0 -> 1.5; + 1.5 + 1.5 = 4.5. 0.6 m away (> 0.5): 0, not negative; total 3.0.
  EXPECT_NEAR(height({0.2, 0.1}, c, VolumeParams{}), 4.5, 1e-12);
  EXPECT_NEAR(height({1.1, 0}, c, VolumeParams{}), 3.0, 1e-12);
}

TEST(HeightTest, NearestNonGoalObstacleIsUsed) {
  Categories c = hand_scene();
  const Box far = box({0, 0.9, 0.5}, {0.5, 0.5, 0.5});  // y in [0.4, 1.4]: 0.4 m
  c.non_goal.insert(c.non_goal.begin(), far);
  // Nearest is still the 0.25 m one: 2.5 as before (not a sum, not the first in the list).
  EXPECT_NEAR(height({0, 0}, c, VolumeParams{}), 2.5, 1e-12);
  c.non_goal = {far};
  // Only the 0.4 m one: (0.5 - 0.4) / 0.5 = 0.2 -> 0.3; total 0.75 + 1.0 + 0.3 = 2.05.
  EXPECT_NEAR(height({0, 0}, c, VolumeParams{}), 2.05, 1e-12);
}

//! A trail-only scene whose height reads the distance: d_t,LB = 0, d_t,UB = `ub`, h_max = 1, so
//! h = d / ub + 1 (the missing goal gives 1/3 + 2/3 = 1) while d < ub.
VolumeParams distance_probe(double ub, DistanceMode mode) {
  VolumeParams v;
  v.d_t_lb = 0.0;
  v.d_t_ub = ub;
  v.h_max = 1.0;
  v.distance = mode;
  return v;
}

TEST(HeightTest, PlaneVersusThreeDForAFloatingBox) {
  // Box x in [0.75, 1.75], z in [1, 2]: plane distance 0.75, 3D sqrt(0.75^2 + 1^2) = 1.25.
  Categories c;
  c.trail = {box({1.25, 0, 1.5}, {0.5, 0.5, 0.5})};
  EXPECT_NEAR(height({0, 0}, c, distance_probe(2.5, DistanceMode::kPlane)), 0.75 / 2.5 + 1, 1e-12);  // 1.3
  EXPECT_NEAR(height({0, 0}, c, distance_probe(2.5, DistanceMode::k3d)), 1.25 / 2.5 + 1, 1e-12);     // 1.5
}

TEST(HeightTest, RotatedBoxFootprint) {
  // A 1 m cube turned 45 degrees about z at (2, 0): a corner at x = 2 - sqrt(2)/2 = 1.292893.
  Categories c;
  c.trail = {box({2, 0, 0.5}, {0.5, 0.5, 0.5}, about(Vector3d::UnitZ(), M_PI / 4))};
  const double corner = 2 - std::sqrt(2.0) / 2;
  EXPECT_NEAR(height({0, 0}, c, distance_probe(10, DistanceMode::kPlane)), 1 + corner / 10, 1e-12);
  EXPECT_NEAR(height({0, 0}, c, distance_probe(10, DistanceMode::k3d)), 1 + corner / 10, 1e-12);
  // From (3, 1) the nearest feature is the edge x + y = 2 + sqrt(2)/2 between the corners
  // (2.7071, 0) and (2, 0.7071): distance (3 + 1 - 2.7071) / sqrt(2) = 0.914214.
  const double edge = (4 - corner - std::sqrt(2.0)) / std::sqrt(2.0);
  EXPECT_NEAR(edge, 0.914214, 1e-6);
  EXPECT_NEAR(height({3, 1}, c, distance_probe(10, DistanceMode::kPlane)), 1 + edge / 10, 1e-12);
  // Inside the turned square but outside its axis-aligned 1 m square: (2.6, 0) -> 0.
  EXPECT_NEAR(height({2.6, 0}, c, distance_probe(10, DistanceMode::kPlane)), 1.0, 1e-12);
}

TEST(HeightTest, TiltedBoxFootprintIsTheHullOfItsCorners) {
  // The cube turned 45 degrees about y at (2, 0, 1): its corners project to x in
  // [2 - 0.7071, 2 + 0.7071], so the plane distance is again 1.292893; in 3D the nearest point is
  // the lower edge at (1.292893, y, 1): sqrt(1.292893^2 + 1) = 1.634495.
  Categories c;
  c.trail = {box({2, 0, 1}, {0.5, 0.5, 0.5}, about(Vector3d::UnitY(), M_PI / 4))};
  const double gap = 2 - std::sqrt(2.0) / 2;
  EXPECT_NEAR(height({0, 0}, c, distance_probe(10, DistanceMode::kPlane)), 1 + gap / 10, 1e-12);
  EXPECT_NEAR(height({0, 0}, c, distance_probe(10, DistanceMode::k3d)), 1 + 1.6344946850 / 10, 1e-10);
}

TEST(HeightTest, BadInputsThrow) {
  VolumeParams v;
  v.d_t_lb = 2.0;
  EXPECT_THROW(height({0, 0}, hand_scene(), v), InputError);
  Categories c = hand_scene();
  c.non_goal[0].half_size.x() = std::numeric_limits<double>::infinity();  // a collidable plane
  try {
    height({0, 0}, c, VolumeParams{});
    ADD_FAILURE() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("non-goal obstacle #0"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// Volume (activation, boxes)

//! A 4 x 4 m map of 1 m cells (centres 0.5 .. 3.5) with the arm base at (0.5, 0.5), reach 2.5 m:
//! cell (i, j) is sqrt(i^2 + j^2) m from it, so (0,3) (1,3) (2,2) (2,3) (3,0) (3,1) (3,2) (3,3)
//! (i^2 + j^2 = 9, 10, 8, 13, 9, 10, 13, 18 > 6.25) are beyond reach: 8 cells.
//! Trail box A: x in [1, 2], y in [0, 1], z in [0.75, 1.25]; it touches the prisms of cells i in
//! {0, 1, 2} (the faces x = 1 and x = 2 count) and j in {0, 1}: 6 cells, all in reach.
//! Trail box B: x in [3.25, 3.75], y in [0.25, 0.75], under cell (3, 0), which is out of reach.
//! Goal: x in [0, 1], y in [3.5, 4]. Non-goal: x in [1.75, 2.5], y in [2, 3].
//! Left: cells (0, 2) at (0.5, 2.5) and (1, 2) at (1.5, 2.5).
Categories grid_scene() {
  Categories c;
  c.arm_base = {{0.5, 0.5}};
  c.trail = {box({1.5, 0.5, 1.0}, {0.5, 0.5, 0.25}), box({3.5, 0.5, 0.75}, {0.25, 0.25, 0.25})};
  c.goal = box({0.5, 3.75, 0.25}, {0.5, 0.25, 0.25});
  c.non_goal = {box({2.125, 2.5, 0.5}, {0.375, 0.5, 0.5})};
  return c;
}

VolumeParams grid_scene_params() {
  VolumeParams v;
  v.reach_radius = 2.5;
  v.d_t_ub = 2.0;  // so that the trail term is not saturated at the two cells left
  return v;
}

TEST(VolumeTest, TinySceneByHand) {
  const Volume vol = generate_volume(grid_scene(), explicit_map(0, 0, 4, 4, 16), grid_scene_params());
  EXPECT_EQ(vol.grid.rows, 4);
  EXPECT_EQ(vol.grid.cols, 4);
  EXPECT_EQ(vol.cells_evaluated, 16);
  EXPECT_EQ(vol.cells_out_of_reach, 8);
  EXPECT_EQ(vol.cells_under_trail, 6);
  ASSERT_EQ(vol.boxes.size(), 2u);
  // Cell (0, 2) at (0.5, 2.5):
  //   trail: to A's footprint dx = 0.5, dy = 1.5, d = sqrt(2.5) = 1.581139;
  //          (1.581139 - 0.35) / (2.0 - 0.35) = 0.746144 -> 1.5 * 0.746144 = 1.119217
  //   goal: dy = 1.0; (1.0 - 0.1) / 1.9 = 0.473684 -> 0.5 + 1.0 * 0.473684 = 0.973684
  //   non-goal: dx = 1.25 > 0.5 -> 0;  h = 2.092901
  // Cell (1, 2) at (1.5, 2.5):
  //   trail: dy = 1.5 -> (1.5 - 0.35) / 1.65 = 0.696970 -> 1.045455
  //   goal: dx = 0.5, dy = 1.0, d = sqrt(1.25) = 1.118034 -> (1.118034 - 0.1) / 1.9 = 0.535807
  //         -> 0.5 + 0.535807 = 1.035807
  //   non-goal: dx = 0.25 -> (0.5 - 0.25) / 0.5 = 0.5 -> 0.75;  h = 2.831262
  const double h0 = 2.092901, h1 = 2.831262;
  const Box& b0 = vol.boxes[0];
  const Box& b1 = vol.boxes[1];
  EXPECT_NEAR(b0.center.x(), 0.5, 1e-12);
  EXPECT_NEAR(b0.center.y(), 2.5, 1e-12);
  EXPECT_NEAR(b0.center.z(), h0 / 2, 1e-6);
  EXPECT_NEAR(b0.half_size.z(), h0 / 2, 1e-6);
  EXPECT_NEAR(b1.center.x(), 1.5, 1e-12);
  EXPECT_NEAR(b1.center.y(), 2.5, 1e-12);
  EXPECT_NEAR(b1.center.z(), h1 / 2, 1e-6);
  for (const Box& b : vol.boxes) {
    EXPECT_EQ(b.half_size.x(), 0.5);
    EXPECT_EQ(b.half_size.y(), 0.5);
    EXPECT_TRUE(b.rotation.isIdentity());
  }
}

TEST(VolumeTest, ObstacleBoxesAppended) {
  VolumeParams v = grid_scene_params();
  v.add_obstacle_boxes = true;
  const Categories c = grid_scene();
  const Volume vol = generate_volume(c, explicit_map(0, 0, 4, 4, 16), v);
  ASSERT_EQ(vol.boxes.size(), 4u);  // 2 cells + goal + 1 non-goal
  EXPECT_EQ(vol.boxes[2].center, c.goal->center);
  EXPECT_EQ(vol.boxes[3].center, c.non_goal[0].center);
}

TEST(VolumeTest, TrailTestUsesThreeTimesHmax) {
  // h_max = 1: the tallest possible box is 3 m. Trail box over x in [1, 2], y in [0, 1] (6 cells
  // touched, as in grid_scene) with its bottom at z = 3 touches those prisms' tops; at 3.01 it
  // does not. No other boxes; reach 10 m covers every cell.
  Categories c;
  c.arm_base = {{0.5, 0.5}};
  VolumeParams v;
  v.h_max = 1.0;
  v.reach_radius = 10.0;
  c.trail = {box({1.5, 0.5, 3.25}, {0.5, 0.5, 0.25})};
  Volume vol = generate_volume(c, explicit_map(0, 0, 4, 4, 16), v);
  EXPECT_EQ(vol.cells_under_trail, 6);
  EXPECT_EQ(vol.cells_out_of_reach, 0);
  EXPECT_EQ(vol.boxes.size(), 10u);
  c.trail[0].center.z() = 3.26;
  vol = generate_volume(c, explicit_map(0, 0, 4, 4, 16), v);
  EXPECT_EQ(vol.cells_under_trail, 0);
  EXPECT_EQ(vol.boxes.size(), 16u);
}

TEST(VolumeTest, TrailMarginWidensTheClearedCells) {
  // The trail box of TrailTestUsesThreeTimesHmax, lowered to z in [0.75, 1.25]: x in [1, 2],
  // y in [0, 1] touches cells i in {0, 1, 2}, j in {0, 1} (6 cells). Grown by 0.3 m it spans
  // x in [0.7, 2.3], y in [-0.3, 1.3]: still inside the squares of those 6 cells. Grown by 1 m it
  // spans x in [0, 3], y in [-1, 2]: it touches i = 3 (face x = 3) and j = 2 (face y = 2) too,
  // 4 x 3 = 12 cells. A margin of 0 is the thesis's test.
  Categories c;
  c.arm_base = {{0.5, 0.5}};
  VolumeParams v;
  v.reach_radius = 10.0;
  c.trail = {box({1.5, 0.5, 1.0}, {0.5, 0.5, 0.25})};
  EXPECT_EQ(generate_volume(c, explicit_map(0, 0, 4, 4, 16), v).cells_under_trail, 6);
  v.trail_margin = 0.3;
  EXPECT_EQ(generate_volume(c, explicit_map(0, 0, 4, 4, 16), v).cells_under_trail, 6);
  v.trail_margin = 1.0;
  EXPECT_EQ(generate_volume(c, explicit_map(0, 0, 4, 4, 16), v).cells_under_trail, 12);
}

TEST(VolumeTest, ReachFromEveryBasePosition) {
  // A base moving from (0.5, 0.5) to (3.5, 0.5), reach 1 m: within 1 m of either position are the
  // cells (0,0) (0,1) (1,0) [distances 0, 1, 1] and (3,0) (3,1) (2,0); (1,1) is sqrt(2) away.
  // No obstacles: each box is h_max (trail) + h_max (goal) = 3.0 m.
  Categories c;
  c.arm_base = {{0.5, 0.5}, {0.5, 0.5}, {3.5, 0.5}};
  VolumeParams v;
  v.reach_radius = 1.0;
  const Volume vol = generate_volume(c, explicit_map(0, 0, 4, 4, 16), v);
  EXPECT_EQ(vol.cells_out_of_reach, 10);
  ASSERT_EQ(vol.boxes.size(), 6u);
  const double expected[][2] = {{0.5, 0.5}, {0.5, 1.5}, {1.5, 0.5}, {2.5, 0.5}, {3.5, 0.5}, {3.5, 1.5}};
  for (size_t k = 0; k < 6; ++k) {
    EXPECT_NEAR(vol.boxes[k].center.x(), expected[k][0], 1e-12);
    EXPECT_NEAR(vol.boxes[k].center.y(), expected[k][1], 1e-12);
    EXPECT_NEAR(vol.boxes[k].half_size.z(), 1.5, 1e-12);
    EXPECT_NEAR(vol.boxes[k].center.z(), 1.5, 1e-12);
  }
}

TEST(VolumeTest, AutoExtentGrid) {
  // One base at (1, 2), reach 1: map [0, 2] x [1, 3], 4 cells of 1 m; all within sqrt(0.5) of the base.
  Categories c;
  c.arm_base = {{1, 2}};
  HeightMapParams hm;
  hm.max_cells = 4;
  VolumeParams v;
  v.reach_radius = 1.0;
  const Volume vol = generate_volume(c, hm, v);
  EXPECT_EQ(vol.cells_evaluated, 4);
  ASSERT_EQ(vol.boxes.size(), 4u);
  EXPECT_NEAR(vol.boxes[0].center.x(), 0.5, 1e-12);
  EXPECT_NEAR(vol.boxes[0].center.y(), 1.5, 1e-12);
  EXPECT_NEAR(vol.boxes[3].center.x(), 1.5, 1e-12);
  EXPECT_NEAR(vol.boxes[3].center.y(), 2.5, 1e-12);
}

TEST(VolumeTest, BadInputsThrow) {
  Categories c = grid_scene();
  c.arm_base.clear();
  EXPECT_THROW(generate_volume(c, explicit_map(0, 0, 4, 4, 16), grid_scene_params()), InputError);
  c = grid_scene();
  c.trail[1].center.x() = std::nan("");
  try {
    generate_volume(c, explicit_map(0, 0, 4, 4, 16), grid_scene_params());
    ADD_FAILURE() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("trail box #1"), std::string::npos) << e.what();
  }
  VolumeParams v = grid_scene_params();
  v.h_max = -1;
  try {
    generate_volume(grid_scene(), explicit_map(0, 0, 4, 4, 16), v);
    ADD_FAILURE() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'volume.h_max'"), std::string::npos) << e.what();
  }
}

//! Random scenes against the definition evaluated cell by cell without any acceleration: reach by
//! the minimum over all bases, the trail test by box_penetration of the max-height prism against
//! every trail box, the height by height(). Seed and count from LEEWAY_FUZZ_SEED / _COUNT.
TEST(VolumeTest, MatchesBruteForceOnRandomScenes) {
  const char* seed_env = std::getenv("LEEWAY_FUZZ_SEED");
  const char* count_env = std::getenv("LEEWAY_FUZZ_COUNT");
  std::mt19937 rng(seed_env ? static_cast<unsigned>(std::stoul(seed_env)) : 7u);
  const int scenes = count_env ? std::stoi(count_env) : 12;
  std::uniform_real_distribution<double> pos(-1.0, 4.0), size(0.02, 0.6), height_d(0.0, 2.0),
      angle(-M_PI, M_PI), unit(-1, 1);
  auto random_box = [&] {
    return box({pos(rng), pos(rng), height_d(rng)}, {size(rng), size(rng), size(rng)},
               about(Vector3d(unit(rng), unit(rng), unit(rng)) + Vector3d(0, 0, 1e-3), angle(rng)));
  };
  int total_out_of_reach = 0, total_under_trail = 0;
  for (int s = 0; s < scenes; ++s) {
    Categories c;
    for (int k = 0; k < 25; ++k) c.trail.push_back(random_box());
    for (int k = 0; k < 4; ++k) c.non_goal.push_back(random_box());
    if (s % 3 != 0) c.goal = random_box();
    c.arm_base = {{pos(rng), pos(rng)}, {pos(rng), pos(rng)}};
    VolumeParams v;
    v.reach_radius = 2.5;
    v.distance = s % 2 ? DistanceMode::k3d : DistanceMode::kPlane;
    v.h_max = 0.3 + 0.3 * (s % 4);  // trail boxes reach 2.6 m: H = 0.9 .. 3.6 m cuts some of them
    const HeightMapParams hm = explicit_map(-1.1, -0.9, 5.3, 4.9, 1500);
    const Volume vol = generate_volume(c, hm, v);

    const Grid g = vol.grid;
    const double big = 3 * v.h_max;
    int out_of_reach = 0, under_trail = 0;
    size_t next = 0;
    for (int i = 0; i < g.rows; ++i)
      for (int j = 0; j < g.cols; ++j) {
        const Vector2d p(g.origin_x + (i + 0.5) * g.side, g.origin_y + (j + 0.5) * g.side);
        double reach = std::numeric_limits<double>::infinity();
        for (const Vector2d& b : c.arm_base) reach = std::min(reach, (p - b).norm());
        if (reach > v.reach_radius) {
          ++out_of_reach;
          continue;
        }
        const Box prism = box({p.x(), p.y(), big / 2}, {g.side / 2, g.side / 2, big / 2});
        bool touched = false;
        for (const Box& t : c.trail) touched = touched || box_penetration(prism, t) >= 0;
        if (touched) {
          ++under_trail;
          continue;
        }
        const double h = height(p, c, v);
        if (h <= 0) continue;
        ASSERT_LT(next, vol.boxes.size());
        const Box& b = vol.boxes[next++];
        EXPECT_NEAR(b.center.x(), p.x(), 1e-12);
        EXPECT_NEAR(b.center.y(), p.y(), 1e-12);
        EXPECT_NEAR(b.half_size.z(), h / 2, 1e-12);
        EXPECT_GT(b.half_size.z(), 0);
        EXPECT_EQ(b.center.z(), b.half_size.z());  // on the floor
      }
    EXPECT_EQ(next, vol.boxes.size());
    EXPECT_EQ(vol.cells_out_of_reach, out_of_reach) << "scene " << s;
    EXPECT_EQ(vol.cells_under_trail, under_trail) << "scene " << s;
    total_out_of_reach += out_of_reach;
    total_under_trail += under_trail;
  }
  // The scenes exercise both parts of the activation.
  EXPECT_GT(total_out_of_reach, 0);
  EXPECT_GT(total_under_trail, 0);
}

}  // namespace
}  // namespace leeway
