#include "leeway/core/box.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

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

TEST(BoxDistanceTest, ClosestPointsSatisfyTheSeparatingPlaneCertificate) {
  // For disjoint convex sets, points pa in A and pb in B are a closest pair exactly when the plane
  // through pa normal to n = (pb - pa) / |pb - pa| has all of A behind it and the plane through pb
  // all of B in front: every corner v of A has (v - pa) . n <= 0, every corner w of B has
  // (w - pb) . n >= 0. Checked on 4,000 random pairs, half of them with nearly parallel faces (the
  // case where alternating projections stopped early and overstated the distance).
  std::mt19937_64 rng(21);
  auto u = [&](double lo, double hi) {
    return lo + (hi - lo) * std::uniform_real_distribution<double>(0, 1)(rng);
  };
  auto rotation = [&](double spread) {
    const Eigen::Vector3d axis = Eigen::Vector3d(u(-1, 1), u(-1, 1), u(-1, 1)).normalized();
    return Eigen::AngleAxisd(u(-spread, spread), axis).toRotationMatrix();
  };
  int disjoint = 0;
  for (int k = 0; k < 4000; ++k) {
    Box a, b;
    a.half_size = {u(0.05, 1), u(0.05, 1), u(0.05, 1)};
    b.half_size = {u(0.05, 1), u(0.05, 1), u(0.05, 1)};
    a.rotation = rotation(M_PI);
    // Nearly parallel: B turned from A by at most 1e-4 rad, shifted mostly along one of A's axes.
    b.rotation = k % 2 ? rotation(M_PI) : Eigen::Matrix3d(rotation(1e-4) * a.rotation);
    a.center = {u(-1, 1), u(-1, 1), u(-1, 1)};
    const Eigen::Vector3d dir = k % 2 ? Eigen::Vector3d(u(-1, 1), u(-1, 1), u(-1, 1)).normalized()
                                      : Eigen::Vector3d(a.rotation.col(k % 3));
    b.center = a.center + dir * u(0.5, 3.5) + Eigen::Vector3d(u(-0.3, 0.3), u(-0.3, 0.3), u(-0.3, 0.3));
    Eigen::Vector3d pa, pb;
    const double d = box_distance(a, b, &pa, &pb);
    if (d == 0) {
      EXPECT_GE(box_penetration(a, b), 0) << "pair " << k;
      continue;
    }
    ++disjoint;
    ASSERT_NEAR((pb - pa).norm(), d, 1e-12) << "pair " << k;
    EXPECT_TRUE(contains(Box{a.center, a.rotation, a.half_size.array() + 1e-9}, pa)) << "pair " << k;
    EXPECT_TRUE(contains(Box{b.center, b.rotation, b.half_size.array() + 1e-9}, pb)) << "pair " << k;
    const Eigen::Vector3d n = (pb - pa) / d;
    for (int c = 0; c < 8; ++c) {
      Eigen::Vector3d s;
      for (int i = 0; i < 3; ++i) s[i] = (c >> i & 1) ? 1.0 : -1.0;
      const Eigen::Vector3d v = a.center + a.rotation * s.cwiseProduct(a.half_size);
      const Eigen::Vector3d w = b.center + b.rotation * s.cwiseProduct(b.half_size);
      ASSERT_LE((v - pa).dot(n), 1e-9) << "pair " << k << ": a corner of A lies beyond its plane";
      ASSERT_GE((w - pb).dot(n), -1e-9) << "pair " << k << ": a corner of B lies before its plane";
    }
  }
  EXPECT_GT(disjoint, 3000);
}

TEST(BoxDistanceTest, NearlyParallelFacesGiveTheGapBetweenThem) {
  // Two unit cubes, the second turned by 1e-6 rad about z and moved 2.0 m along x: the faces
  // x = 0.5 and x ~ 1.5 are 1 m apart up to the tilt, the gap is 1 - 0.5 (cos t + sin t - 1) ~
  // 1 - 0.5e-6 m (the nearer corner of the turned cube). Alternating projections gave a distance
  // too large here.
  const double t = 1e-6;
  const Box a = cube({0, 0, 0}), b = cube({2.0, 0, 0}, t);
  const double expected = 2.0 - 0.5 - 0.5 * (std::cos(t) + std::sin(t));
  EXPECT_NEAR(box_distance(a, b), expected, 1e-12);
}

}  // namespace
}  // namespace leeway
