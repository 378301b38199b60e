#include "leeway/box.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

namespace leeway {
namespace {

TEST(BoxTest, ContainsAxisAligned) {
  Box b;
  b.center = {1, 2, 3};
  b.half_size = {0.5, 0.25, 1.0};
  EXPECT_TRUE(contains(b, {1, 2, 3}));
  EXPECT_TRUE(contains(b, {1.5, 2.25, 4.0}));  // a corner: on the surface counts as inside
  EXPECT_FALSE(contains(b, {1.51, 2, 3}));
  EXPECT_FALSE(contains(b, {1, 2.26, 3}));
  EXPECT_FALSE(contains(b, {1, 2, 1.99}));
}

TEST(BoxTest, ContainsRotated) {
  // A 1 m cube turned 45 degrees about z: its corners reach sqrt(2)/2 = 0.7071 m along x.
  Box b;
  b.half_size = {0.5, 0.5, 0.5};
  b.rotation = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_TRUE(contains(b, {0.70, 0, 0}));
  EXPECT_FALSE(contains(b, {0.72, 0, 0}));
  // Along the diagonal the face is at 0.5 m: (0.36, 0.36) is 0.509 m from the centre along it.
  EXPECT_TRUE(contains(b, {0.35, 0.35, 0}));
  EXPECT_FALSE(contains(b, {0.36, 0.36, 0}));
}

Box cube(const Eigen::Vector3d& center, double yaw = 0) {
  Box b;
  b.center = center;
  b.half_size = {0.5, 0.5, 0.5};
  b.rotation = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return b;
}

TEST(BoxPenetrationTest, FaceOverlapIsExact) {
  // Unit cubes 0.9 m apart along x overlap by 0.1 m (MuJoCo 2.2.2's box-box reports 0.05).
  EXPECT_NEAR(box_penetration(cube({0, 0, 0}), cube({0.9, 0, 0})), 0.1, 1e-12);
  EXPECT_NEAR(box_penetration(cube({0, 0, 0}), cube({1.0, 0, 0})), 0.0, 1e-12);     // touching
  EXPECT_NEAR(box_penetration(cube({0, 0, 0}), cube({1.25, 0, 0})), -0.25, 1e-12);  // 0.25 m gap
}

TEST(BoxPenetrationTest, RotatedCornerIntoFace) {
  // A cube turned 45 degrees about z, centred at x = 1.2: its corner reaches 1.2 - sqrt(2)/2 =
  // 0.49289 m, 0.00711 m into the other cube's face at x = 0.5.
  EXPECT_NEAR(box_penetration(cube({0, 0, 0}), cube({1.2, 0, 0}, M_PI / 4)), 0.5 + std::sqrt(0.5) - 1.2,
              1e-12);
  EXPECT_NEAR(box_penetration(cube({0, 0, 0}), cube({1.3, 0, 0}, M_PI / 4)), 0.5 + std::sqrt(0.5) - 1.3,
              1e-12);
}

TEST(BoxPenetrationTest, EdgeEdgeSeparation) {
  // Two cubes turned 45 degrees about x and about z respectively, stacked along z: the lower one's
  // top is an edge along x at z = sqrt(2)/2, the upper one's bottom an edge along y at
  // z = c - sqrt(2)/2 with c = 1.5: the gap along z (the edge-edge cross axis) is 0.0858 m.
  Box lower = cube({0, 0, 0});
  lower.rotation = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitX()).toRotationMatrix();
  Box upper = cube({0, 0, 1.5});
  upper.rotation = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitY()).toRotationMatrix();
  EXPECT_NEAR(box_penetration(lower, upper), 2 * std::sqrt(0.5) - 1.5, 1e-12);
}

TEST(BoxDistanceTest, HandComputedGaps) {
  Eigen::Vector3d pa, pb;
  // Face to face: 0.25 m, closest points on the facing faces.
  EXPECT_NEAR(box_distance(cube({0, 0, 0}), cube({1.25, 0.3, 0}), &pa, &pb), 0.25, 1e-9);
  EXPECT_NEAR(pa.x(), 0.5, 1e-9);
  EXPECT_NEAR(pb.x(), 0.75, 1e-9);
  // Corner to corner along the diagonal: (0.5, 0.5, 0.5) to (1, 1, 1) is sqrt(3)/2.
  EXPECT_NEAR(box_distance(cube({0, 0, 0}), cube({1.5, 1.5, 1.5})), std::sqrt(3.0) / 2, 1e-9);
  // A 45-degree cube's corner at x = 1.3 - sqrt(2)/2 to the face at x = 0.5.
  EXPECT_NEAR(box_distance(cube({0, 0, 0}), cube({1.3, 0, 0}, M_PI / 4)), 1.3 - std::sqrt(0.5) - 0.5, 1e-9);
  // Crossed edges (see EdgeEdgeSeparation): 1.5 - sqrt(2).
  Box lower = cube({0, 0, 0});
  lower.rotation = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitX()).toRotationMatrix();
  Box upper = cube({0, 0, 1.5});
  upper.rotation = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitY()).toRotationMatrix();
  EXPECT_NEAR(box_distance(lower, upper), 1.5 - 2 * std::sqrt(0.5), 1e-9);
  // Overlapping boxes are at distance 0.
  EXPECT_EQ(box_distance(cube({0, 0, 0}), cube({0.9, 0, 0})), 0.0);
}

}  // namespace
}  // namespace leeway
