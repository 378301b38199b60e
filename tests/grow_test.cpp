// Growth beyond the guide in the certified mode: on hand-worked arms the grown bound reaches the
// analytic touch angle less the margin, never more; caps and joint choices are kept; every grown
// region is free when sampled densely. And the run boxes of dense paths (the same two-link arm and
// dense sampling): what they prove is free.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "leeway/core/certify.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/params.hpp"
#include "leeway/core/room.hpp"
#include "leeway/core/safety.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using ::testing::HasSubstr;

// One-link arm (test_util.hpp) and the wall y >= 0.95: the link's corner (1, 0.05) touches it at
// t = asin(0.95 / sqrt(1.0025)) - atan(0.05) = 1.19950 rad and comes within 1 mm of it
// 0.001 / (cos t - 0.05 sin t) = 0.00316 rad earlier. Its range is [-3, 3]; nothing is on the -y side.
const char* kWall = R"(<geom name="wall" type="box" size="1 0.05 1" pos="0 1 1"/>)";
const double kTouch = std::asin(0.95 / std::sqrt(1.0025)) - std::atan(0.05);
const double kWithinMargin = 0.001 / (std::cos(kTouch) - 0.05 * std::sin(kTouch));

// A two-link planar arm: j1 about z at (0, 0, 0.5) with a 1 m link along x, j2 about z at its tip
// with a 0.5 m link (box half-size 0.25 x 0.05 x 0.05), ranges [-2.5, 2.5]; a wall whose near face is
// the plane y = 0.45 over x in [0.75, 1.75]. With j1 = 0, link 2's corner (0.5, 0.05) from j2 reaches
// it at 0.5 sin t + 0.05 cos t = 0.45: t2 = asin(0.45 / sqrt(0.2525)) - atan(0.1) = 1.01052 rad, and
// comes within 1 mm 0.001 / (0.5 cos t2 - 0.05 sin t2) = 0.00449 rad earlier.
const char* kTwoLink = R"(<mujoco model="two-link">
  <compiler angle="radian" autolimits="true"/>
  <worldbody>
    <body name="base">
      <geom name="base_box" type="box" size="0.1 0.1 0.25" pos="0 0 0.25"/>
      <body name="link1" pos="0 0 0.5">
        <joint name="j1" type="hinge" axis="0 0 1" range="-2.5 2.5" user="1.5"/>
        <geom name="link1_box" type="box" size="0.5 0.05 0.05" pos="0.5 0 0"/>
        <body name="link2" pos="1 0 0">
          <joint name="j2" type="hinge" axis="0 0 1" range="-2.5 2.5" user="1.5"/>
          <geom name="link2_box" type="box" size="0.25 0.05 0.05" pos="0.25 0 0"/>
          <site name="tool0" pos="0.5 0 0"/>
        </body>
      </body>
    </body>
    <geom name="wall" type="box" size="0.5 0.05 1" pos="1.25 0.5 1"/>
  </worldbody>
</mujoco>
)";
const double kTouch2 = std::asin(0.45 / std::sqrt(0.2525)) - std::atan(0.1);
const double kWithinMargin2 = 0.001 / (0.5 * std::cos(kTouch2) - 0.05 * std::sin(kTouch2));

WaypointBounds box(const Eigen::VectorXd& q, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  return WaypointBounds(q, lower, upper);
}
Eigen::VectorXd v1(double a) { return Eigen::VectorXd::Constant(1, a); }
Eigen::VectorXd v2(double a, double b) { return (Eigen::VectorXd(2) << a, b).finished(); }

// The smallest exact clearance over the segments' regions: corners of every end box and `samples`
// seeded configurations per segment (t uniform, each joint at a bound or uniform in between).
double sampled_clearance(const Scene& scene, const std::vector<WaypointBounds>& b, int samples) {
  RobotState state(scene);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  double best = INFINITY;
  const int n = scene.dof();
  for (const auto& w : b)
    for (int c = 0; c < (1 << n); ++c) {
      Eigen::VectorXd q(n);
      for (int i = 0; i < n; ++i) q[i] = (c >> i) & 1 ? w.upper[i] : w.lower[i];
      best = std::min(best, state.clearance(q).distance);
    }
  for (size_t s = 0; s + 1 < std::max<size_t>(2, b.size()); ++s) {
    const WaypointBounds& a = b[s];
    const WaypointBounds& e = b[std::min(s + 1, b.size() - 1)];
    for (int k = 0; k < samples; ++k) {
      const double t = u(rng);
      Eigen::VectorXd q(n);
      for (int i = 0; i < n; ++i) {
        const double lo = (1 - t) * a.lower[i] + t * e.lower[i], hi = (1 - t) * a.upper[i] + t * e.upper[i];
        const double pick = u(rng);
        q[i] = pick < 0.25 ? lo : pick < 0.5 ? hi : lo + (hi - lo) * u(rng);
      }
      best = std::min(best, state.clearance(q).distance);
    }
  }
  return best;
}

// A dense two-link path: 81 waypoints, j1 from -0.3 to -0.1 rad and j2 from 0.5 to 0.7 rad (2.5 mrad
// apart), the guide j1 +-0.1 and j2 0.3 below and 0.8 above the nominal: through the wall (link 2's
// far corner is at y = sin j1 + 0.5 sin(j1 + j2) + 0.05 cos(j1 + j2), 0.22 m at the last nominal,
// 0.50 m at its guide's upper corner; the wall is at 0.45).
std::vector<WaypointBounds> dense_path_through_the_wall() {
  std::vector<WaypointBounds> b;
  for (int k = 0; k <= 80; ++k) {
    const Eigen::VectorXd q = v2(-0.3 + 0.0025 * k, 0.5 + 0.0025 * k);
    b.push_back(box(q, q - v2(0.1, 0.3), q + v2(0.1, 0.8)));
  }
  return b;
}

class GrowTest : public ::testing::Test {
 protected:
  test::TempDir dir_;
};

TEST_F(GrowTest, OneLinkGrowsToTheWallLessTheMarginAndToTheLimitOnTheFreeSide) {
  const Scene scene = Scene::load(dir_.write("one_link.xml", test::one_link_cell(kWall)));
  // A narrow guide the certificate accepts at once: only growth can widen it.
  std::vector<WaypointBounds> b = {box(v1(0.0), v1(-0.1), v1(0.1)), box(v1(0.3), v1(0.2), v1(0.4))};
  const SafetyReport r = make_safe(scene, b, SafetyParams{});
  ASSERT_TRUE(r.all_passed);
  EXPECT_TRUE(r.grow.ran);
  EXPECT_EQ(r.grow.grown, 2);
  for (const auto& w : b) {
    EXPECT_LE(w.upper[0], kTouch - kWithinMargin + 1e-9);
    EXPECT_GE(w.upper[0], kTouch - kWithinMargin - 0.005);
    EXPECT_NEAR(w.lower[0], -3.0, 0.005);
  }
  EXPECT_GE(sampled_clearance(scene, b, 20000), 0.001 - 1e-9);
}

// Growth to a joint limit writes the limit itself: with the range +-3.14159 and the nominal value
// 0.9, 0.9 - (0.9 + 3.14159) is -3.1415900000000004 in doubles, beyond the limit, and a bounds file
// whose interval leaves the limits is refused.
TEST_F(GrowTest, GrowthToAJointLimitStaysWithinIt) {
  std::string cell = test::one_link_cell(kWall);
  const std::string range = R"(range="-3 3")";
  cell.replace(cell.find(range), range.size(), R"(range="-3.14159 3.14159")");
  const Scene scene = Scene::load(dir_.write("one_link_pi.xml", cell));
  ASSERT_LT(0.9 - (0.9 + 3.14159), -3.14159);
  std::vector<WaypointBounds> b = {box(v1(0.9), v1(0.8), v1(1.0))};
  const SafetyReport r = make_safe(scene, b, SafetyParams{});
  ASSERT_TRUE(r.all_passed);
  EXPECT_EQ(b[0].lower[0], -3.14159);
  EXPECT_LE(b[0].upper[0], kTouch - kWithinMargin + 1e-9);
  EXPECT_GE(b[0].upper[0], kTouch - kWithinMargin - 0.005);
}

// safety.grow_leaves multiplies growth's leaf budgets: on the one-link arm with
// safety.max_leaves = 64, growth runs out of leaves far short of the wall (analytic touch less the
// margin, 1.1963 rad) and of the free side's limit (-3 rad); with four times the budgets it reaches
// both, within 5 mrad and never beyond, and the grown region stays clear by the margin.
TEST_F(GrowTest, LargerGrowthBudgetsReachTheWallLessTheMargin) {
  const Scene scene = Scene::load(dir_.write("one_link.xml", test::one_link_cell(kWall)));
  const std::vector<WaypointBounds> guide = {box(v1(0.0), v1(-0.1), v1(0.1)), box(v1(0.3), v1(0.2), v1(0.4))};
  SafetyParams params;
  params.max_leaves = 64;
  params.turn = false;  // the rounds' budgets alone (the turn of the last hinge: the test below)
  std::vector<WaypointBounds> b = guide;
  const SafetyReport small = make_safe(scene, b, params);
  ASSERT_TRUE(small.all_passed);
  for (const auto& w : b) {
    EXPECT_LT(w.upper[0], kTouch - kWithinMargin - 0.005);
    EXPECT_GT(w.lower[0], -3.0 + 0.005);
  }
  params.grow_leaves = 4;
  b = guide;
  const SafetyReport large = make_safe(scene, b, params);
  ASSERT_TRUE(large.all_passed);
  for (const auto& w : b) {
    EXPECT_LE(w.upper[0], kTouch - kWithinMargin + 1e-9);
    EXPECT_GE(w.upper[0], kTouch - kWithinMargin - 0.005);
    EXPECT_EQ(w.lower[0], -3.0);
  }
  EXPECT_GT(large.grow.stats.leaves, small.grow.stats.leaves);
  EXPECT_GE(sampled_clearance(scene, b, 20000), 0.001 - 1e-9);
}

// The same arm and budget with the last hinge's turn (safety.turn, the default): j1 is the arm's
// last hinge (Certifier::turns_last), so before the rounds each side goes straight to its target
// in one proof of four slab budgets. Nothing lies below: the free side reaches the joint's limit,
// -3.0 exactly, where the rounds stopped short of it. Toward the wall the probe stops the step short
// of the touch and the rounds go on from there: never past the touch less the margin.
TEST_F(GrowTest, TheLastHingeTurnsStraightToItsLimitWhereTheRoundsStopShort) {
  const Scene scene = Scene::load(dir_.write("one_link.xml", test::one_link_cell(kWall)));
  const std::vector<WaypointBounds> guide = {box(v1(0.0), v1(-0.1), v1(0.1)), box(v1(0.3), v1(0.2), v1(0.4))};
  SafetyParams params;
  params.max_leaves = 64;
  std::vector<WaypointBounds> b = guide;
  ASSERT_TRUE(make_safe(scene, b, params).all_passed);
  for (const auto& w : b) {
    EXPECT_EQ(w.lower[0], -3.0);
    EXPECT_LE(w.upper[0], kTouch - kWithinMargin + 1e-9);
  }
  EXPECT_GE(sampled_clearance(scene, b, 20000), 0.001 - 1e-9);
  params.turn = false;
  b = guide;
  ASSERT_TRUE(make_safe(scene, b, params).all_passed);
  for (const auto& w : b) EXPECT_GT(w.lower[0], -3.0 + 0.005);
}

TEST_F(GrowTest, TwoLinkElbowGrowsToItsTouchLessTheMarginWhenOnlyItGrows) {
  const Scene scene = Scene::load(dir_.write("two_link.xml", kTwoLink));
  // One waypoint; j1 held at its nominal value (a zero-width interval) and not grown.
  std::vector<WaypointBounds> b = {box(v2(0, 0), v2(0, -0.1), v2(0, 0.1))};
  SafetyParams params;
  params.grow = "j2";
  const SafetyReport r = make_safe(scene, b, params);
  ASSERT_TRUE(r.all_passed);
  EXPECT_EQ(b[0].lower[0], 0.0);
  EXPECT_EQ(b[0].upper[0], 0.0);
  EXPECT_LE(b[0].upper[1], kTouch2 - kWithinMargin2 + 1e-9);
  EXPECT_GE(b[0].upper[1], kTouch2 - kWithinMargin2 - 0.005);
  EXPECT_NEAR(b[0].lower[1], -2.5, 0.005);
  EXPECT_GE(sampled_clearance(scene, b, 20000), 0.001 - 1e-9);
}

// The two-link arm at (0, 0) with j1 in [-0.05, 0.05]: link 2's corner (0.5, 0.05) from j2, at
// absolute angle phi = j1 + j2 from j2's anchor (cos j1, sin j1), is highest at j1 = 0.05 and
// reaches the wall at sin 0.05 + 0.5 sin phi + 0.05 cos phi = 0.45, j2 = phi - 0.05 = 0.77235 rad,
// and comes within 1 mm 0.001 / (0.5 cos phi - 0.05 sin phi) = 0.00329 rad earlier.
const double kPhi = std::asin((0.45 - std::sin(0.05)) / std::sqrt(0.2525)) - std::atan(0.1);
const double kTouchAtJ1 = kPhi - 0.05;
const double kWithinMarginAtJ1 = 0.001 / (0.5 * std::cos(kPhi) - 0.05 * std::sin(kPhi));

// The box of one waypoint, proven again from scratch by a certifier of its own.
bool recertified(const Scene& scene, const WaypointBounds& w) {
  const Certifier certifier(scene);
  CertifyContext ctx(scene);
  CertifyStats stats;
  return certifier.segment_free(ctx, w.lower, w.upper, w.lower, w.upper, CertifyBudget{1 << 20}, stats);
}

// A wrist over a table: j1-j3 (held, zero width) at (0, 0, 1), j4 tilting about x, j5 turning
// about z and carrying a square plate centred on both axes (half-size 0.3 x 0.3 x 0.01); the table's
// top is the plane z = 0.85, 0.15 m below the axes. Tilted by a, the plate turned by up to 0.1 rad
// reaches 0.3 (cos 0.1 + sin 0.1) sin a + 0.01 cos a below the axes; turned freely (the pivot
// cylinder, radius 0.3 sqrt 2) r sin a + 0.01 cos a: at j4 = 0.4 that is 0.1744 m, past the table.
const char* kTiltTurn = R"(<mujoco model="tilt-turn">
  <compiler angle="radian" autolimits="true"/>
  <worldbody>
    <geom name="table" type="box" size="1 1 0.05" pos="0 0 0.8"/>
    <body name="b1" pos="0 0 1">
      <joint name="j1" type="hinge" axis="0 0 1" range="-3 3"/>
      <inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/>
      <body name="b2">
        <joint name="j2" type="hinge" axis="0 1 0" range="-3 3"/>
        <inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/>
        <body name="b3">
          <joint name="j3" type="hinge" axis="0 1 0" range="-3 3"/>
          <inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/>
          <body name="tilt">
            <joint name="j4" type="hinge" axis="1 0 0" range="-1.5 1.5"/>
            <inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/>
            <body name="plate">
              <joint name="j5" type="hinge" axis="0 0 1" range="-3 3"/>
              <geom name="plate_box" type="box" size="0.3 0.3 0.01"/>
              <site name="tool0"/>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
)";

// The guide holds j4 in [-0.4, 0.4] and j5 in [-0.1, 0.1]: the plate then stays 0.15 - 0.1371 m
// above the table, and the certified mode keeps the box. j5 turns last, but not with j4 at 0.4 (a
// configuration of that turn comes within the margin of the table: checked below), so j4, the
// wrist hinge before it, keeps a quarter of its extents, 0.1, and j5 turns to its limits. The rounds
// then grow j4 back, never past the pivot cylinder's touch less the margin: r sin a + 0.01 cos a =
// 0.149. Without the turn (safety.turn false) j5 stays short of its limits.
TEST_F(GrowTest, TheWristGivesUpThreeQuartersWhereTheLastHingeCannotTurnOtherwise) {
  const Scene scene = Scene::load(dir_.write("tilt_turn.xml", kTiltTurn));
  const double r = 0.3 * std::sqrt(2.0);
  const double cylinder_touch = std::asin(0.149 / std::hypot(r, 0.01)) - std::atan2(0.01, r);
  ASSERT_NEAR(cylinder_touch, 0.33516, 1e-4);
  RobotState state(scene);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(5);
  q[3] = 0.4;
  q[4] = std::atan(1.0);
  ASSERT_LT(state.clearance(q).distance, 0.001);
  q[3] = 0.0;
  q[4] = 0.0;
  Eigen::VectorXd lower = q, upper = q;
  lower[3] = -0.4;
  upper[3] = 0.4;
  lower[4] = -0.1;
  upper[4] = 0.1;
  const std::vector<WaypointBounds> guide = {box(q, lower, upper)};
  SafetyParams params;
  params.grow = "j4,j5";
  std::vector<WaypointBounds> b = guide;
  ASSERT_TRUE(make_safe(scene, b, params).all_passed);
  EXPECT_EQ(b[0].lower[4], -3.0);
  EXPECT_EQ(b[0].upper[4], 3.0);
  EXPECT_LE(b[0].lower[3], -0.1 + 1e-12);
  EXPECT_GE(b[0].upper[3], 0.1 - 1e-12);
  EXPECT_GE(b[0].lower[3], -cylinder_touch - 1e-9);
  EXPECT_LE(b[0].upper[3], cylinder_touch + 1e-9);
  for (int j = 0; j < 3; ++j) {
    EXPECT_EQ(b[0].lower[j], 0.0);
    EXPECT_EQ(b[0].upper[j], 0.0);
  }
  EXPECT_TRUE(recertified(scene, b[0]));
  EXPECT_GE(sampled_clearance(scene, b, 20000), 0.001 - 1e-9);
  params.turn = false;
  b = guide;
  ASSERT_TRUE(make_safe(scene, b, params).all_passed);
  EXPECT_GT(b[0].lower[4], -3.0 + 0.005);
  EXPECT_LT(b[0].upper[4], 3.0 - 0.005);
}

// The lever shape on the two-link arm: j2's share costs the tool 0.5 m per radian of its free
// range (about 3.5 rad), j1's 1.5 m per radian (about 2.8 rad), so j2 grows first, and straight to
// its free range's end with j1 still within its guide: the touch at j1 = 0.05 less the margin.
// j1 then finds j2 at the wall above and grows below only, to its limit.
TEST_F(GrowTest, LeverShapeGivesTheCheaperShareAllItCanTakeFirst) {
  const Scene scene = Scene::load(dir_.write("two_link.xml", kTwoLink));
  std::vector<WaypointBounds> b = {box(v2(0, 0), v2(-0.05, -0.05), v2(0.05, 0.05))};
  SafetyParams params;
  params.shape = "lever";
  const SafetyReport r = make_safe(scene, b, params);
  ASSERT_TRUE(r.all_passed);
  EXPECT_LE(b[0].upper[1], kTouchAtJ1 - kWithinMarginAtJ1 + 1e-9);
  EXPECT_GE(b[0].upper[1], kTouchAtJ1 - kWithinMarginAtJ1 - 0.005);
  EXPECT_NEAR(b[0].lower[1], -2.5, 0.005);
  EXPECT_LE(b[0].upper[0], 0.05 + 0.005);
  EXPECT_NEAR(b[0].lower[0], -2.5, 0.005);
  EXPECT_TRUE(recertified(scene, b[0]));
  EXPECT_GE(sampled_clearance(scene, b, 50000), 0.001 - 1e-9);
}

// Greedy's rounds share the room instead: in the first round j1 rises to a third of its free range
// above (0.09 rad), and j2 then stops short of the wall well below the lever shape's 0.77 rad. On
// this arm the lever shape keeps the larger mean share; both results are certified.
TEST_F(GrowTest, GreedyAndLeverShapesDifferAndBothAreCertified) {
  const Scene scene = Scene::load(dir_.write("two_link.xml", kTwoLink));
  const std::vector<WaypointBounds> guide = {box(v2(0, 0), v2(-0.05, -0.05), v2(0.05, 0.05))};
  std::vector<WaypointBounds> greedy = guide, lever = guide;
  SafetyParams params;
  params.turn = false;  // j2 turns last: its turn would take the room first under both shapes
  ASSERT_TRUE(make_safe(scene, greedy, params).all_passed);
  params.shape = "lever";
  ASSERT_TRUE(make_safe(scene, lever, params).all_passed);
  EXPECT_GT(greedy[0].upper[0], 0.08);
  EXPECT_LT(greedy[0].upper[1], lever[0].upper[1] - 0.1);
  EXPECT_GT(measure_room(scene, lever).mean_share, measure_room(scene, greedy).mean_share);
  EXPECT_TRUE(recertified(scene, greedy[0]));
  EXPECT_TRUE(recertified(scene, lever[0]));
}

// On the one-link arm there is nothing to share: both shapes reach the wall less the margin.
TEST_F(GrowTest, LeverShapeOnOneLinkReachesTheWallLessTheMargin) {
  const Scene scene = Scene::load(dir_.write("one_link.xml", test::one_link_cell(kWall)));
  std::vector<WaypointBounds> b = {box(v1(0.0), v1(-0.1), v1(0.1)), box(v1(0.3), v1(0.2), v1(0.4))};
  SafetyParams params;
  params.shape = "lever";
  ASSERT_TRUE(make_safe(scene, b, params).all_passed);
  for (const auto& w : b) {
    EXPECT_LE(w.upper[0], kTouch - kWithinMargin + 1e-9);
    EXPECT_GE(w.upper[0], kTouch - kWithinMargin - 0.005);
    EXPECT_NEAR(w.lower[0], -3.0, 0.005);
  }
  EXPECT_GE(sampled_clearance(scene, b, 20000), 0.001 - 1e-9);
}

TEST_F(GrowTest, TwoLinkGrowingBothJointsStaysFree) {
  const Scene scene = Scene::load(dir_.write("two_link.xml", kTwoLink));
  std::vector<WaypointBounds> b = {box(v2(0, 0), v2(-0.05, -0.05), v2(0.05, 0.05)),
                                   box(v2(-0.3, 0.4), v2(-0.35, 0.35), v2(-0.25, 0.45))};
  const SafetyReport r = make_safe(scene, b, SafetyParams{});
  ASSERT_TRUE(r.all_passed);
  EXPECT_GT(r.grow.grown, 0);
  // Both joints widened somewhere, and the region is free with the margin.
  EXPECT_GT(b[0].upper[0] - b[0].lower[0], 0.1 + 1e-3);
  EXPECT_GT(b[1].upper[1] - b[1].lower[1], 0.1 + 1e-3);
  EXPECT_GE(sampled_clearance(scene, b, 50000), 0.001 - 1e-9);
}

TEST_F(GrowTest, RunBoxesOfADenseTwoLinkPathNearTheWallAreFree) {
  // dense_path_through_the_wall: phase-0 segments shrink and the others start
  // warm and are proven by their chain's run boxes. The result must be free with the margin between the
  // waypoints too, the same for one thread and two, and about as wide as proving every segment
  // on its own.
  const Scene scene = Scene::load(dir_.write("two_link.xml", kTwoLink));
  std::vector<WaypointBounds> b = dense_path_through_the_wall();
  std::vector<WaypointBounds> two_threads = b, without = b;
  SafetyParams params;
  const SafetyReport r = make_safe(scene, b, params, 1);
  make_safe(scene, two_threads, params, 2);
  params.runs = false;
  const SafetyReport off = make_safe(scene, without, params, 1);
  ASSERT_TRUE(r.all_passed);
  ASSERT_TRUE(off.all_passed);
  EXPECT_GT(r.run_segments, 40);
  EXPECT_LT(r.stats.leaves, off.stats.leaves);
  EXPECT_GE(sampled_clearance(scene, b, 2000), 0.001 - 1e-9);
  double width = 0, width_off = 0;
  for (size_t k = 0; k < b.size(); ++k) {
    SCOPED_TRACE(k);
    EXPECT_EQ(b[k].lower, two_threads[k].lower);
    EXPECT_EQ(b[k].upper, two_threads[k].upper);
    width += b[k].upper[1] - b[k].lower[1];
    width_off += without[k].upper[1] - without[k].lower[1];
  }
  EXPECT_GT(width, 0.95 * width_off);
}

// A dense path (steps of 5 mrad, guide +-0.1 rad: every segment short) grows by blocks of 16
// segments, each block's waypoints to one extent, its hull proven. One-link arm toward the wall:
// nothing is on the -y side, so every waypoint reaches the joint's lower limit -3; on the
// wall's side the hull of each block stops within 1 mm of the wall, so the block's furthest
// waypoint comes within 5 mrad of the touch angle less the margin, and none goes beyond it.
TEST_F(GrowTest, DenseOneLinkPathGrowsByBlocksToTheWallLessTheMargin) {
  const Scene scene = Scene::load(dir_.write("one_link.xml", test::one_link_cell(kWall)));
  std::vector<WaypointBounds> b;
  for (int k = 0; k <= 60; ++k)
    b.push_back(box(v1(0.8 + 0.005 * k), v1(0.7 + 0.005 * k), v1(0.9 + 0.005 * k)));
  const SafetyReport r = make_safe(scene, b, SafetyParams{});
  ASSERT_TRUE(r.all_passed);
  ASSERT_TRUE(r.grow.ran);
  EXPECT_GT(r.run_segments, 0);  // a dense path: its warm segments run in chains
  const double limit = kTouch - kWithinMargin;
  for (size_t k = 0; k < b.size(); ++k) {
    SCOPED_TRACE(k);
    EXPECT_NEAR(b[k].lower[0], -3.0, 1e-9);
    EXPECT_LE(b[k].upper[0], limit + 1e-9);
  }
  for (size_t first = 0; first + 1 < b.size(); first += 16) {
    SCOPED_TRACE(first);
    double furthest = -INFINITY;
    for (size_t k = first; k <= std::min(first + 16, b.size() - 1); ++k)
      furthest = std::max(furthest, b[k].upper[0]);
    EXPECT_GE(furthest, limit - 0.005);
  }
  EXPECT_GE(sampled_clearance(scene, b, 2000), 0.001 - 1e-9);
}

// dense_path_through_the_wall, grown: both joints widen
// beyond the certified bounds somewhere, every certified interval is kept (growth never narrows),
// the result is free with the margin between the waypoints too (1 mm over the corners and 2,000
// samples per segment), and it is the same for one thread and two.
TEST_F(GrowTest, DenseTwoLinkPathNearTheWallGrowsAndStaysFree) {
  const Scene scene = Scene::load(dir_.write("two_link.xml", kTwoLink));
  std::vector<WaypointBounds> b = dense_path_through_the_wall();
  std::vector<WaypointBounds> two_threads = b, certified = b;
  SafetyParams params;
  const SafetyReport r = make_safe(scene, b, params, 1);
  make_safe(scene, two_threads, params, 2);
  params.grow = "none";
  make_safe(scene, certified, params, 1);
  ASSERT_TRUE(r.all_passed);
  EXPECT_GT(r.grow.grown, 40);
  int wider[2] = {0, 0};
  for (size_t k = 0; k < b.size(); ++k) {
    SCOPED_TRACE(k);
    EXPECT_EQ(b[k].lower, two_threads[k].lower);
    EXPECT_EQ(b[k].upper, two_threads[k].upper);
    for (int i = 0; i < 2; ++i) {
      EXPECT_LE(b[k].lower[i], certified[k].lower[i]);
      EXPECT_GE(b[k].upper[i], certified[k].upper[i]);
      wider[i] += b[k].upper[i] - b[k].lower[i] > certified[k].upper[i] - certified[k].lower[i] + 0.01;
    }
  }
  EXPECT_GT(wider[0], 10);
  EXPECT_GT(wider[1], 10);
  EXPECT_GE(sampled_clearance(scene, b, 2000), 0.001 - 1e-9);
}

// Blocks share their end waypoints: an even block grows its ends first, and when the odd block
// beside it cannot grow, those ends must go back to the bounds its segments were certified with.
// One-link arm, 49 waypoints at 1.055 + 0.15 sin(pi k / 48) rad (steps under 10 mrad, guide
// +-0.1): the nominal path enters the wall (1.1995 rad) only inside block 1 (waypoints 16-32), so
// some of its segments are not certified and it does not grow; blocks 0 and 2 grow to the lower
// limit -3 inside, and waypoints 16 and 32 keep exactly their certified bounds.
TEST_F(GrowTest, AnOddBlockThatCannotGrowGivesItsEndsBack) {
  const Scene scene = Scene::load(dir_.write("one_link.xml", test::one_link_cell(kWall)));
  std::vector<WaypointBounds> b;
  for (int k = 0; k <= 48; ++k) {
    const double q = 1.055 + 0.15 * std::sin(M_PI * k / 48);
    b.push_back(box(v1(q), v1(q - 0.1), v1(q + 0.1)));
  }
  std::vector<WaypointBounds> certified = b;
  const SafetyReport r = make_safe(scene, b, SafetyParams{});
  SafetyParams none;
  none.grow = "none";
  make_safe(scene, certified, none);
  ASSERT_TRUE(r.grow.ran);
  bool block1_failed = false;
  for (size_t s = 16; s < 32; ++s) block1_failed = block1_failed || !r.segments[s].passed;
  ASSERT_TRUE(block1_failed);
  for (size_t s : {size_t{0}, size_t{15}, size_t{32}, size_t{47}}) ASSERT_TRUE(r.segments[s].passed) << s;
  for (size_t k : {size_t{1}, size_t{8}, size_t{15}, size_t{33}, size_t{40}, size_t{47}})
    EXPECT_NEAR(b[k].lower[0], -3.0, 1e-9) << k;
  for (size_t k = 16; k <= 32; ++k) {
    SCOPED_TRACE(k);
    EXPECT_EQ(b[k].lower[0], certified[k].lower[0]);
    EXPECT_EQ(b[k].upper[0], certified[k].upper[0]);
  }
  // The certified blocks are free with the margin, their ends included.
  const std::vector<WaypointBounds> block0(b.begin(), b.begin() + 17), block2(b.begin() + 32, b.end());
  EXPECT_GE(sampled_clearance(scene, block0, 2000), 0.001 - 1e-9);
  EXPECT_GE(sampled_clearance(scene, block2, 2000), 0.001 - 1e-9);
}

TEST_F(GrowTest, CapsNarrowAndNoneKeepsTheCertifiedBounds) {
  const Scene scene = Scene::load(dir_.write("one_link.xml", test::one_link_cell(kWall)));
  const std::vector<WaypointBounds> guide = {box(v1(0.0), v1(-0.4), v1(0.4)), box(v1(0.3), v1(0.2), v1(0.4))};
  SafetyParams capped;
  capped.max_half_width = {{"j1", 0.25}};
  std::vector<WaypointBounds> b = guide;
  make_safe(scene, b, capped);
  EXPECT_DOUBLE_EQ(b[0].lower[0], -0.25);
  EXPECT_DOUBLE_EQ(b[0].upper[0], 0.25);
  EXPECT_DOUBLE_EQ(b[1].lower[0], 0.3 - 0.25);
  EXPECT_DOUBLE_EQ(b[1].upper[0], 0.3 + 0.25);
  SafetyParams none;
  none.grow = "none";
  b = guide;
  const SafetyReport r = make_safe(scene, b, none);
  EXPECT_FALSE(r.grow.ran);
  for (size_t k = 0; k < b.size(); ++k) {
    EXPECT_EQ(b[k].lower[0], guide[k].lower[0]);
    EXPECT_EQ(b[k].upper[0], guide[k].upper[0]);
  }
}

TEST_F(GrowTest, GrowthDoesNotDependOnTheThreadCount) {
  const Scene scene = Scene::load(dir_.write("two_link.xml", kTwoLink));
  std::vector<WaypointBounds> one = {box(v2(0, 0), v2(-0.05, -0.05), v2(0.05, 0.05)),
                                     box(v2(-0.2, 0.2), v2(-0.25, 0.15), v2(-0.15, 0.25)),
                                     box(v2(-0.4, 0.4), v2(-0.45, 0.35), v2(-0.35, 0.45))};
  std::vector<WaypointBounds> two = one;
  make_safe(scene, one, SafetyParams{}, 1);
  make_safe(scene, two, SafetyParams{}, 2);
  for (size_t k = 0; k < one.size(); ++k) {
    EXPECT_EQ(one[k].lower, two[k].lower);
    EXPECT_EQ(one[k].upper, two[k].upper);
  }
}

TEST_F(GrowTest, UnknownJointsAreRefusedNamingThem) {
  const Scene scene = Scene::load(dir_.write("one_link.xml", test::one_link_cell(kWall)));
  std::vector<WaypointBounds> b = {box(v1(0.0), v1(-0.1), v1(0.1))};
  SafetyParams params;
  params.grow = "j1,elbow";
  try {
    make_safe(scene, b, params);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("'safety.grow' = 'j1,elbow' names joint 'elbow'"));
  }
  params.grow = "all";
  params.max_half_width = {{"wrist", 0.1}};
  try {
    make_safe(scene, b, params);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("'safety.max_half_width' names joint 'wrist'"));
  }
}

}  // namespace
}  // namespace leeway
