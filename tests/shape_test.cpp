// Geoms as MuJoCo collides them (shape.hpp): support functions, GJK distances against values worked
// out by hand, mesh geoms as their hulls, and the certificate against round and mesh obstacles and
// a round link, each at an angle worked out by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "leeway/core/certify.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/scene.hpp"
#include "leeway/core/shape.hpp"
#include "stl_util.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

Shape make(int type, const Eigen::Vector3d& pos, const Eigen::Vector3d& size,
           const Eigen::Matrix3d& rot = Eigen::Matrix3d::Identity()) {
  // A shape as geom_shape builds it, without a model: the bounding box from a box of the same size.
  Shape s;
  s.type = type;
  s.origin = pos;
  s.rotation = rot;
  s.size = size;
  s.box.center = pos;
  s.box.rotation = rot;
  switch (type) {
    case mjGEOM_SPHERE:
      s.box.half_size = Eigen::Vector3d::Constant(size[0]);
      s.radius = size[0];
      break;
    case mjGEOM_CAPSULE:
      s.box.half_size = Eigen::Vector3d(size[0], size[0], size[0] + size[1]);
      s.radius = size[0] + size[1];
      break;
    case mjGEOM_CYLINDER:
      s.box.half_size = Eigen::Vector3d(size[0], size[0], size[1]);
      s.radius = std::hypot(size[0], size[1]);
      break;
    default:
      s.box.half_size = size;
      s.radius = size.norm();
      break;
  }
  return s;
}

Eigen::Matrix3d rot_z(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

TEST(ShapeTest, SupportOfRoundShapesIsAnalytic) {
  const Eigen::Vector3d n = Eigen::Vector3d(1, 2, 2) / 3;  // unit
  const Eigen::Vector3d c(0.1, -0.2, 0.3);
  EXPECT_NEAR(make(mjGEOM_SPHERE, c, {0.5, 0, 0}).support(n), n.dot(c) + 0.5, 1e-12);
  // Capsule along z, radius 0.1, half-length 0.4: the ball's radius plus the segment's end.
  EXPECT_NEAR(make(mjGEOM_CAPSULE, c, {0.1, 0.4, 0}).support(n), n.dot(c) + 0.1 + 0.4 * 2.0 / 3, 1e-12);
  // Cylinder along z, radius 0.3, half-height 0.2: r |n_xy| + h |n_z|.
  EXPECT_NEAR(make(mjGEOM_CYLINDER, c, {0.3, 0.2, 0}).support(n),
              n.dot(c) + 0.3 * std::sqrt(5.0) / 3 + 0.2 * 2.0 / 3, 1e-12);
  // Ellipsoid with semi-axes a: sqrt(sum (a_k n_k)^2).
  const Eigen::Vector3d a(0.2, 0.1, 0.4);
  EXPECT_NEAR(make(mjGEOM_ELLIPSOID, c, a).support(n), n.dot(c) + a.cwiseProduct(n).norm(), 1e-12);
  // A rotated box: sum_k h_k |n . e_k|.
  const Shape box = make(mjGEOM_BOX, c, {0.5, 0.1, 0.2}, rot_z(0.4));
  EXPECT_NEAR(box.support(n),
              n.dot(c) + (rot_z(0.4).transpose() * n).cwiseAbs().dot(Eigen::Vector3d(0.5, 0.1, 0.2)), 1e-12);
  // A mesh's support is its farthest vertex.
  const float vertices[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  Shape tetra = make(mjGEOM_MESH, c, {0, 0, 0});
  tetra.vertices = vertices;
  tetra.count = 4;
  EXPECT_NEAR(tetra.support(n), n.dot(c) + 2.0 / 3, 1e-7);
  EXPECT_NEAR(tetra.support(-n), -n.dot(c), 1e-7);
}

TEST(ShapeTest, DistancesMatchHandWorkedValues) {
  const Eigen::Vector3d o = Eigen::Vector3d::Zero();
  struct Case {
    const char* what;
    Shape a, b;
    double expected;
  };
  const double s3 = std::sqrt(3.0);
  const Case cases[] = {
      {"sphere-sphere", make(mjGEOM_SPHERE, o, {0.2, 0, 0}), make(mjGEOM_SPHERE, {1, 1, 0}, {0.3, 0, 0}),
       std::sqrt(2.0) - 0.5},
      // The box corner (0.5, 0.5, 0.5) is the point nearest the sphere's centre (1, 1, 1).
      {"box-sphere at a corner", make(mjGEOM_BOX, o, {0.5, 0.5, 0.5}),
       make(mjGEOM_SPHERE, {1, 1, 1}, {0.2, 0, 0}), s3 / 2 - 0.2},
      // Capsules crossing at right angles, one along z at the origin, the other along x at y = 1.
      {"capsule-capsule crossed", make(mjGEOM_CAPSULE, o, {0.1, 0.5, 0}),
       make(mjGEOM_CAPSULE, {0, 1, 0}, {0.05, 0.5, 0},
            Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix()),
       0.85},
      // The cylinder's top rim point (0.3, 0, 0.2) is nearest the sphere's centre (1, 0, 0.5).
      {"cylinder rim-sphere", make(mjGEOM_CYLINDER, o, {0.3, 0.2, 0}),
       make(mjGEOM_SPHERE, {1, 0, 0.5}, {0.1, 0, 0}), std::sqrt(0.49 + 0.09) - 0.1},
      // An ellipsoid's tip on its long axis faces a box face 0.3 m away.
      {"ellipsoid-box", make(mjGEOM_ELLIPSOID, o, {0.5, 0.1, 0.2}), make(mjGEOM_BOX, {1, 0, 0}, {0.2, 1, 1}),
       0.3},
      {"touching spheres", make(mjGEOM_SPHERE, o, {0.5, 0, 0}), make(mjGEOM_SPHERE, {0.9, 0, 0}, {0.5, 0, 0}),
       0.0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const ShapeDistance d = convex_distance(c.a, c.b);
    EXPECT_LE(d.lower, c.expected + 1e-9);
    EXPECT_GE(d.upper, c.expected - 1e-9);
    EXPECT_NEAR(d.lower, c.expected, 1e-8);
    EXPECT_NEAR(shape_distance(c.a, c.b), c.expected, 1e-8);
  }
  // The lower bound is a separating plane's gap: every point of b lies beyond it along the axis.
  const ShapeDistance d = convex_distance(cases[1].a, cases[1].b);
  EXPECT_NEAR(d.axis.dot(Eigen::Vector3d(1, 1, 1) / s3), 1.0, 1e-6);
}

// Random pairs of shapes: GJK's bounds bracket the distance found by dense sampling of both surfaces'
// support points, and the lower bound is a separating plane's gap.
TEST(ShapeTest, GjkLowerBoundNeverExceedsASampledDistance) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1), pos(0.05, 0.4);
  const int types[] = {mjGEOM_SPHERE, mjGEOM_CAPSULE, mjGEOM_CYLINDER, mjGEOM_ELLIPSOID, mjGEOM_BOX};
  int apart = 0;
  for (int trial = 0; trial < 300; ++trial) {
    auto random_shape = [&](const Eigen::Vector3d& centre) {
      const Eigen::Matrix3d r =
          Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
      return make(types[trial % 5], centre, {pos(rng), pos(rng), pos(rng)}, r);
    };
    const Shape a = random_shape(Eigen::Vector3d::Zero());
    const Shape b = random_shape(Eigen::Vector3d(u(rng), u(rng), u(rng)) * 1.2);
    const ShapeDistance d = convex_distance(a, b);
    double sampled = INFINITY;
    for (int k = 0; k < 2000; ++k) {
      const Eigen::Vector3d n = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
      const Eigen::Vector3d m = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
      sampled = std::min(sampled, (a.support_point(n) - b.support_point(m)).norm());
    }
    EXPECT_LE(d.lower, sampled + 1e-9) << "trial " << trial;
    EXPECT_LE(d.lower, d.upper + 1e-12);
    if (d.lower > 0) {
      ++apart;
      EXPECT_NEAR(b.support(-d.axis) * -1 - a.support(d.axis), d.lower, 1e-6) << "trial " << trial;
    }
  }
  EXPECT_GT(apart, 50);
}

// The support of a mesh climbs its hull's edges (MuJoCo's mesh_graph); on a convex polytope that
// ends at the maximum: the same value as the pass over every vertex, in 2,000 random directions, on
// a lumpy sphere of 1,152 triangles (a UV sphere with radii varying by latitude and longitude).
TEST(ShapeTest, MeshSupportClimbingTheHullEqualsThePassOverEveryVertex) {
  test::TempDir dir;
  std::vector<test::Triangle> sphere;
  const int rings = 24, sectors = 24;
  auto point = [&](int i, int j) {
    const double theta = M_PI * i / rings, phi = 2 * M_PI * j / sectors;
    const double r = 0.3 + 0.05 * std::sin(3 * theta) * std::cos(2 * phi);
    return Eigen::Vector3d(r * std::sin(theta) * std::cos(phi), 1.5 * r * std::sin(theta) * std::sin(phi),
                           r * std::cos(theta));
  };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < sectors; ++j) {
      sphere.push_back({point(i, j), point(i + 1, j), point(i + 1, j + 1)});
      sphere.push_back({point(i, j), point(i + 1, j + 1), point(i, j + 1)});
    }
  test::write_binary_stl((dir.path() / "lumpy.stl").string(), sphere);
  const std::string xml = R"(<mujoco><asset><mesh name="lumpy" file="lumpy.stl"/></asset>
  <worldbody><geom name="lumpy" type="mesh" mesh="lumpy" pos="0.2 -0.1 0.3" euler="0.3 0.2 0.1"/></worldbody></mujoco>)";
  const ModelPtr m = load_model_file(dir.write("cell.xml", xml));  // throws with MuJoCo's message
  DataPtr d = make_data(*m);
  mj_kinematics(m.get(), d.get());
  const Shape climbing = geom_shape(*m, *d, 0);
  ASSERT_NE(climbing.edges, nullptr) << "MuJoCo computed no hull";
  EXPECT_GT(climbing.count, 100);
  Shape every = climbing;
  every.edges = nullptr;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g;
  for (int k = 0; k < 2000; ++k) {
    const Eigen::Vector3d n(g(rng), g(rng), g(rng));
    ASSERT_EQ(climbing.support(n), every.support(n)) << "direction " << n.transpose();
  }
}

// A cell with a mesh geom: MuJoCo re-centres the mesh at its centroid, and the shape follows: its
// world box is the STL's cuboid at the geom's position, and its distance to a box is the box twin's.
TEST(ShapeTest, MeshGeomIsItsHullWhereMujocoPlacesIt) {
  test::TempDir dir;
  test::write_binary_stl((dir.path() / "part.stl").string(),
                         test::cuboid(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.4, 0.2, 0.1)));
  const std::string xml = R"(<mujoco>
  <asset><mesh name="part" file="part.stl"/></asset>
  <worldbody>
    <geom name="part" type="mesh" mesh="part" pos="1 2 3"/>
    <geom name="block" type="box" size="0.1 0.1 0.1" pos="2 2.1 3.05"/>
  </worldbody>
</mujoco>)";
  const ModelPtr m = load_model_file(dir.write("cell.xml", xml));  // throws with MuJoCo's message
  DataPtr d = make_data(*m);
  mj_kinematics(m.get(), d.get());
  const Shape part = geom_shape(*m, *d, 0);
  const Eigen::AlignedBox3d box = aligned(part);
  EXPECT_TRUE(box.min().isApprox(Eigen::Vector3d(1, 2, 3), 1e-6)) << box.min().transpose();
  EXPECT_TRUE(box.max().isApprox(Eigen::Vector3d(1.4, 2.2, 3.1), 1e-6)) << box.max().transpose();
  EXPECT_NEAR(aligned(geom_box(*m, *d, 0)).max().x(), 1.4, 1e-6);  // the tight box, not the sphere's cube
  // The block's near face x = 1.9 is 0.5 m from the part's x = 1.4.
  EXPECT_NEAR(shape_distance(part, geom_shape(*m, *d, 1)), 0.5, 1e-6);
}

// The one-link arm (hinge j1 about z at height 0.5 m, link box 1 x 0.1 x 0.1 m along +x) and a round
// obstacle of radius 0.1 m in the link's plane, centred at P = (0.6, 0.5): a sphere, a vertical
// capsule and a vertical cylinder all cut that plane in the same circle. The link's near long face
// y' = 0.05 meets the circle when P's y' coordinate, 0.5 cos t - 0.6 sin t = |P| cos(t + atan2(0.6,
// 0.5)), is 0.15 m, so clearance c holds up to t = acos((0.15 + c) / |P|) - atan2(0.6, 0.5) (P's x'
// coordinate, 0.77 m there, lies along the link).
double round_angle(double c) { return std::acos((0.15 + c) / std::hypot(0.6, 0.5)) - std::atan2(0.6, 0.5); }

Eigen::VectorXd v1(double a) { return Eigen::VectorXd::Constant(1, a); }

// Region [0, upper] certified or not, with the failure's pair.
bool certified(const Scene& scene, double upper, CertifyFailure* failure = nullptr) {
  Certifier certifier(scene);  // margin 1 mm
  CertifyContext ctx(scene);
  CertifyStats stats;
  return certifier.region_free(ctx, v1(0), v1(upper), stats, failure);
}

class ShapeCertifyTest : public test::MujocoTest {};

TEST_F(ShapeCertifyTest, RoundObstaclesCertifiedUpToTheirRealShapeMinusTheMargin) {
  EXPECT_NEAR(round_angle(0), 0.501482, 1e-6);
  const char* obstacles[] = {
      R"(<geom name="round" type="sphere" size="0.1" pos="0.6 0.5 0.5"/>)",
      R"(<geom name="round" type="capsule" size="0.1 0.3" pos="0.6 0.5 0.5"/>)",
      R"(<geom name="round" type="cylinder" size="0.1 0.3" pos="0.6 0.5 0.5"/>)",
  };
  for (const char* obstacle : obstacles) {
    SCOPED_TRACE(obstacle);
    test::TempDir dir;
    const Scene scene = Scene::load(dir.write("cell.xml", test::one_link_cell(obstacle)));
    RobotState state(scene);
    EXPECT_NEAR(state.clearance(v1(round_angle(0.001))).distance, 0.001, 1e-8);
    EXPECT_FALSE(state.in_collision(v1(round_angle(0) - 1e-3)));
    EXPECT_TRUE(state.in_collision(v1(round_angle(0) + 1e-3)));
    EXPECT_TRUE(certified(scene, round_angle(0.001) - 5e-4));
    CertifyFailure failure;
    EXPECT_FALSE(certified(scene, round_angle(0.001) + 5e-4, &failure));
    EXPECT_EQ(scene.geom_label(failure.obstacle_geom), "round");
    EXPECT_TRUE(failure.centre_hits);
  }
  // The sphere's bounding cube reaches the link earlier: the box twin is not certified as far.
  test::TempDir dir;
  const Scene cube = Scene::load(dir.write(
      "cube.xml",
      test::one_link_cell(R"(<geom name="round" type="box" size="0.1 0.1 0.1" pos="0.6 0.5 0.5"/>)")));
  EXPECT_FALSE(certified(cube, round_angle(0.001) - 5e-4));
}

// A thin plate (1.2 x 0.02 x 0.8 m) as an STL mesh turned by a = 0.3 rad about z, its near face the
// line n . x = 0.5 with n = (-sin a, cos a). The link's tip corner (1, 0.05) reaches n . x =
// sin(t - a) + 0.05 cos(t - a), so clearance c holds up to t = a + asin((0.5 - c) / sqrt(1.0025)) -
// atan(0.05); the corner meets the face 0.87 m along it, inside the plate.
TEST_F(ShapeCertifyTest, RotatedThinMeshPlateCertifiedUpToItsFaceMinusTheMargin) {
  const double a = 0.3;
  auto plate_angle = [&](double c) { return a + std::asin((0.5 - c) / std::sqrt(1.0025)) - std::atan(0.05); };
  test::TempDir dir;
  test::write_binary_stl((dir.path() / "plate.stl").string(),
                         test::cuboid(Eigen::Vector3d(-0.6, -0.01, -0.4), Eigen::Vector3d(0.6, 0.01, 0.4)));
  const Eigen::Vector2d n(-std::sin(a), std::cos(a)), u(std::cos(a), std::sin(a));
  const Eigen::Vector2d centre = 0.51 * n + 0.8 * u;
  const std::string plate = R"(<geom name="plate" type="mesh" mesh="plate" pos=")" +
                            std::to_string(centre.x()) + " " + std::to_string(centre.y()) +
                            R"( 0.5" euler="0 0 0.3"/>)";
  std::string xml = test::one_link_cell(plate);
  xml.replace(xml.find("<worldbody>"), 11, R"(<asset><mesh name="plate" file="plate.stl"/></asset>
  <worldbody>)");
  const Scene scene = Scene::load(dir.write("cell.xml", xml));
  RobotState state(scene);
  // std::to_string keeps 6 decimals: the face is within 1e-6 m of n . x = 0.5.
  EXPECT_NEAR(state.clearance(v1(plate_angle(0.001))).distance, 0.001, 2e-6);
  EXPECT_TRUE(certified(scene, plate_angle(0.001) - 5e-4));
  CertifyFailure failure;
  EXPECT_FALSE(certified(scene, plate_angle(0.001) + 5e-4, &failure));
  EXPECT_EQ(scene.geom_label(failure.obstacle_geom), "plate");
}

// A capsule link (radius 0.05 m, from the axis to x' = 1) against the box wall whose near face is
// y = 0.5: its tip ball's centre (cos t, sin t) comes within c at sin t = 0.45 - c. Its bounding box
// (to x' = 1.05) would stop short of that: the certificate uses the capsule itself.
TEST_F(ShapeCertifyTest, CapsuleLinkCertifiedByItsOwnShape) {
  std::string xml =
      test::one_link_cell(R"(<geom name="wall" type="box" size="0.6 0.1 0.5" pos="0.6 0.6 0.5"/>)");
  xml.replace(xml.find(R"(<geom name="link_box" type="box" size="0.5 0.05 0.05" pos="0.5 0 0"/>)"), 71,
              R"(<geom name="link_capsule" type="capsule" fromto="0 0 0 1 0 0" size="0.05"/>)");
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", xml));
  auto angle = [](double c) { return std::asin(0.45 - c); };
  RobotState state(scene);
  EXPECT_NEAR(state.clearance(v1(angle(0.001))).distance, 0.001, 1e-8);
  EXPECT_TRUE(certified(scene, angle(0.001) - 5e-4));
  EXPECT_FALSE(certified(scene, angle(0.001) + 5e-4));
  // The capsule's bounding box's corner (1.05, 0.05) reaches y = 0.499 at 1.05 sin t + 0.05 cos t = 0.499.
  const double box_angle = std::asin(0.499 / std::hypot(1.05, 0.05)) - std::atan2(0.05, 1.05);
  EXPECT_GT(angle(0.001) - 5e-4, box_angle + 0.01);
}

}  // namespace
}  // namespace leeway
