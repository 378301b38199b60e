// The certificate's parts on their own: the swept-link bound, the separating-axis test and the
// blame, against values worked out by hand on a one-link and a two-link arm.
#include "leeway/core/swept_link.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "leeway/core/certify.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/scene.hpp"
#include "lever_bound.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

// Two hinges about z: j1 at (0, 0, 0.5), j2 0.5 m out along x, and the 10 cm cube `tip` 0.5 m
// beyond j2. Levers by hand: j1 0.5 + 0.5 = 1 m, j2 0.5 m; the cube's corner 0.05 sqrt(3) m.
const char* kTwoLinkCell = R"(<mujoco model="two-link">
  <compiler angle="radian" autolimits="true"/>
  <worldbody>
    <body name="l1" pos="0 0 0.5">
      <joint name="j1" type="hinge" axis="0 0 1" range="-3 3"/>
      <inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/>
      <body name="l2" pos="0.5 0 0">
        <joint name="j2" type="hinge" axis="0 0 1" range="-3 3"/>
        <geom name="tip" type="box" size="0.05 0.05 0.05" pos="0.5 0 0"/>
        <site name="tool0" pos="0.5 0 0"/>
      </body>
    </body>
    <geom name="wall" type="box" size="0.1 0.1 0.1" pos="0 2 0.5"/>
  </worldbody>
</mujoco>
)";

// The one-link arm's link (test::one_link_cell): j1 about z at (0, 0, 0.5), the box 0.5 x 0.05 x
// 0.05 m (half sizes) centred 0.5 m out: lever 0.5 m, corner |(0.5, 0.05, 0.05)| = 0.504975 m.
LinkChain one_link_chain(const Scene& scene) {
  LinkChain c;
  c.geom = mj_name2id(&scene.model(), mjOBJ_GEOM, "link_box");
  c.joints = {0};
  c.mj_joints = {scene.joints()[0].id};
  c.slide = {false};
  c.lever = {0.5};
  c.corner_lever = std::sqrt(0.25 + 0.0025 + 0.0025);
  return c;
}

LinkChain two_link_chain(const Scene& scene) {
  LinkChain c;
  c.geom = mj_name2id(&scene.model(), mjOBJ_GEOM, "tip");
  c.joints = {0, 1};
  c.mj_joints = {scene.joints()[0].id, scene.joints()[1].id};
  c.slide = {false, false};
  c.lever = {1.0, 0.5};
  c.corner_lever = 0.05 * std::sqrt(3.0);
  return c;
}

class SweptLinkTest : public test::MujocoTest {};

TEST_F(SweptLinkTest, APointInJointSpaceSweepsOnlyTheBox) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", test::one_link_cell("")));
  RobotState state(scene);
  state.set(Eigen::VectorXd::Zero(1));
  const LinkChain chain = one_link_chain(scene);
  SweptLink s;
  s.new_leaf();
  s.start(chain, 0, Eigen::VectorXd::Zero(1), 0, scene.model(), state.data());
  EXPECT_NEAR(s.cheap_radius(), 0.504975, 1e-6);
  s.build();
  EXPECT_NEAR(s.radius(), 0.504975, 1e-6);
  EXPECT_NEAR((s.box().center - Eigen::Vector3d(0.5, 0, 0.5)).norm(), 0.0, 1e-12);
  for (const Eigen::Vector3d n :
       {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()}) {
    EXPECT_EQ(s.motion_extent(n), 0.0);
    EXPECT_EQ(s.remainder_cheap(n), 0.0);
    EXPECT_EQ(s.remainder_refined(n), 0.0);
  }
  EXPECT_NEAR(s.box_extent(Eigen::Vector3d::UnitX()), 0.5, 1e-12);
  EXPECT_NEAR(s.box_extent(Eigen::Vector3d(1, 1, 0).normalized()), 0.55 / std::sqrt(2.0), 1e-12);
}

// j1 in [-0.1, 0.1]: J = z x (0.5, 0, 0) = (0, 0.5, 0); d e_x / d q = z x x = y, d e_y / d q = -x.
// First-order extent on y: 0.1 * 0.5 + 0.5 * 0.1 (the box's length turning) = 0.1; on x: the box's
// width turning, 0.05 * 0.1 = 0.005; on z: 0. Remainder: r_pos = 0.5 h^2 lever = 0.0025, r_rot =
// 0.5 h^2 = 0.005, times s(n) = |n x z|: 0.0025 + 0.6 * 0.005 = 0.0055 on x and y, 0 on z.
// Spheres: 0.504975 + 0.1 * 0.5 + 0.0025 = 0.557475 m, with or without the Jacobian (|J| = lever).
TEST_F(SweptLinkTest, TurningLinkMatchesTheBoundWorkedByHand) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", test::one_link_cell("")));
  RobotState state(scene);
  state.set(Eigen::VectorXd::Zero(1));
  const LinkChain chain = one_link_chain(scene);
  SweptLink s;
  s.new_leaf();
  s.start(chain, 0, Eigen::VectorXd::Constant(1, 0.1), 0, scene.model(), state.data());
  EXPECT_NEAR(s.cheap_radius(), 0.557475, 1e-6);
  EXPECT_FALSE(s.built());
  s.build();
  EXPECT_NEAR(s.radius(), 0.557475, 1e-6);
  EXPECT_NEAR(s.lever_radius(), 0.1 * (0.5 + 0.504975), 1e-6);
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(),
                        z = Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(s.motion_extent(y), 0.1, 1e-12);
  EXPECT_NEAR(s.motion_extent(x), 0.005, 1e-12);
  EXPECT_NEAR(s.motion_extent(z), 0.0, 1e-12);
  EXPECT_NEAR(s.remainder_cheap(x), 0.0055, 1e-12);
  EXPECT_NEAR(s.remainder_cheap(y), 0.0055, 1e-12);
  EXPECT_NEAR(s.remainder_cheap(z), 0.0, 1e-12);
  EXPECT_LE(s.remainder_refined(y), s.remainder_cheap(y));
  EXPECT_NEAR(s.contribution(y, 0, 0.1), 0.05 + 0.05 + 0.0025, 1e-12);
  EXPECT_EQ(s.contribution(y, 0, 0.0), 0.0);
}

// Sound: for random joint boxes and axes, every corner of the link's box at every sampled
// configuration projects within the bound's extent about the box's centre at the box centre.
TEST_F(SweptLinkTest, BoundHoldsTheSweptCornersOfATwoLinkArm) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", kTwoLinkCell));
  RobotState centre_state(scene), state(scene);
  const LinkChain chain = two_link_chain(scene);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  SweptLink s;
  int checked = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const Eigen::Vector2d c(u(rng) * 2, u(rng) * 2), h(0.4 * std::abs(u(rng)), 0.4 * std::abs(u(rng)));
    centre_state.set(c);
    s.new_leaf();
    s.start(chain, 0, h, 0, scene.model(), centre_state.data());
    s.build();
    const Eigen::Vector3d n = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const double reach = s.motion_extent(n) + s.box_extent(n) + s.remainder_refined(n);
    EXPECT_LE(s.remainder_refined(n), s.remainder_cheap(n) + 1e-15);
    for (int k = 0; k < 50; ++k) {
      const Eigen::Vector2d q(c[0] + h[0] * u(rng), c[1] + h[1] * u(rng));
      state.set(q);
      const Box b = geom_box(scene.model(), state.data(), chain.geom);
      for (int corner = 0; corner < 8; ++corner) {
        Eigen::Vector3d local;
        for (int a = 0; a < 3; ++a) local[a] = (corner >> a & 1 ? 1 : -1) * b.half_size[a];
        const Eigen::Vector3d p = b.center + b.rotation * local;
        EXPECT_LE(std::abs(n.dot(p - s.box().center)), reach + 1e-12) << "trial " << trial;
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 40 * 50 * 8);
}

// The one-link arm over a table (top z = 0.4, the link's bottom face at 0.45) with j1 in
// [-0.1, 0.1]: separated on the table's z axis, 5 cm clear (motion and remainder are 0 along z).
// A wall whose face is at y = 0.12 is not: along y the link reaches 0.05 + 0.1 + 0.0055 = 0.1555,
// 3.55 cm past it (and really hits it: the far corner reaches 1.0 sin 0.1 + 0.05 cos 0.1 = 0.1496).
TEST_F(SweptLinkTest, SeparatingAxisTestFindsTheAxisWorkedByHand) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", test::one_link_cell("")));
  RobotState state(scene);
  state.set(Eigen::VectorXd::Zero(1));
  const LinkChain chain = one_link_chain(scene);
  SweptLink s;
  s.new_leaf();
  s.start(chain, 0, Eigen::VectorXd::Constant(1, 0.1), 0, scene.model(), state.data());
  s.build();
  SweepObstacle table;
  table.box.center = Eigen::Vector3d(0, 0, 0.2);
  table.box.half_size = Eigen::Vector3d(2, 2, 0.2);
  table.radius = table.box.half_size.norm();
  const Separation apart = separate(s, table, 0.001);
  EXPECT_TRUE(apart.separated);
  EXPECT_NEAR(apart.gap, 0.05, 1e-12);
  EXPECT_NEAR(std::abs(apart.axis.z()), 1.0, 1e-12);

  SweepObstacle wall;
  wall.box.center = Eigen::Vector3d(0.5, 0.17, 0.5);
  wall.box.half_size = Eigen::Vector3d(0.5, 0.05, 0.5);
  wall.radius = wall.box.half_size.norm();
  const Separation hit = separate(s, wall, 0.001);
  EXPECT_FALSE(hit.separated);
  EXPECT_NEAR(hit.gap, -0.0355, 1e-12);
  EXPECT_NEAR(std::abs(hit.axis.y()), 1.0, 1e-12);
  // The lever reference inflates the box by 0.1005 m on every side: it cannot separate the table,
  // 5 cm below, either.
  EXPECT_FALSE(LeverBound().separated(s, table, 0.001));

  // A plane: only its normal is tried. The floor z = 0 is 0.45 m below the link.
  SweepObstacle floor;
  floor.plane = true;
  floor.radius = INFINITY;
  const Separation over = separate(s, floor, 0.001);
  EXPECT_TRUE(over.separated);
  EXPECT_NEAR(over.gap, 0.45, 1e-12);
}

// Blame at q = 0 along y: j1 moves the tip by w1 (|J1| = 1) + 0.05 w1 (the cube turning) +
// 0.5 w1^2 * 1, j2 by 0.5 w2 + 0.05 w2 + 0.5 w2^2 * 0.5. Equal weights 0.1: 0.11 against 0.0575,
// j1. Weights (0.1, 0.3): 0.11 against 0.1875, j2. A held j1 is never blamed; zero weights blame
// none. The lever reference: w (lever + 0.0866): 0.1087 against 0.176, j2.
TEST_F(SweptLinkTest, BlameNamesTheJointThatMovesTheLinkMost) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", kTwoLinkCell));
  RobotState state(scene);
  state.set(Eigen::VectorXd::Zero(2));
  const LinkChain chain = two_link_chain(scene);
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  SweptLink s;
  s.new_leaf();
  s.start(chain, 0, Eigen::Vector2d(0.1, 0.3), 0, scene.model(), state.data());
  s.build();
  EXPECT_NEAR(s.contribution(y, 0, 0.1), 0.11, 1e-12);
  EXPECT_NEAR(s.contribution(y, 1, 0.1), 0.0575, 1e-12);
  EXPECT_NEAR(s.contribution(y, 1, 0.3), 0.1875, 1e-12);
  EXPECT_EQ(blame(s, y, Eigen::Vector2d(0.1, 0.1)), 0);
  EXPECT_EQ(blame(s, y, Eigen::Vector2d(0.1, 0.3)), 1);
  EXPECT_EQ(blame(s, y, Eigen::Vector2d(0.0, 0.0)), -1);
  const LeverBound lever;
  EXPECT_EQ(blame(s, y, Eigen::Vector2d(0.1, 0.3), &lever), 1);
  EXPECT_EQ(blame(s, y, Eigen::Vector2d(0.2, 0.1), &lever), 0);
  // j1 held (a self pair whose common body is l1's): its half-width is zeroed and never blamed.
  s.new_leaf();
  s.start(chain, 0, Eigen::Vector2d(1.0, 0.1), 1, scene.model(), state.data());
  s.build();
  EXPECT_EQ(s.half_widths()[0], 0.0);
  EXPECT_EQ(blame(s, y, Eigen::Vector2d(1.0, 0.1)), 1);
}

// A context is scratch for one scene: a certifier refuses another scene's instead of reading the
// wrong mjData.
TEST_F(SweptLinkTest, CertifierRefusesAContextOfAnotherScene) {
  test::TempDir dir;
  const Scene one = Scene::load(dir.write("one.xml", test::one_link_cell("")));
  const Scene other = Scene::load(dir.write("other.xml", test::one_link_cell("")));
  const Certifier certifier(one);
  CertifyContext mine(one), theirs(other);
  CertifyStats stats;
  EXPECT_TRUE(certifier.leaf_free(mine, Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1), stats));
  EXPECT_THROW(certifier.leaf_free(theirs, Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1), stats),
               InputError);
}

}  // namespace
}  // namespace leeway
