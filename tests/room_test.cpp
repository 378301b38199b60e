// The room the bounds keep: one-joint free ranges, the kept shares and the tool's room, against
// values worked out by hand on the one-link arm.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "leeway/core/kinematics.hpp"
#include "leeway/core/room.hpp"
#include "room_ceiling.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

// The one-link arm of test_util.hpp (a 1 m link of half-height 0.05 m about z, range [-3, 3]) with
// a wall whose near face is the plane y = 0.95, on the +y side only. The link's corner (1, 0.05)
// touches it at sin(t) + 0.05 cos(t) = 0.95: t = asin(0.95 / sqrt(1.0025)) - atan(0.05) = 1.19950.
// Turned the other way, nothing is in reach: the free range is [-3, 1.19950].
const char* kWall = R"(<geom name="wall" type="box" size="1 0.05 1" pos="0 1 1"/>)";
const double kTouch = std::asin(0.95 / std::sqrt(1.0025)) - std::atan(0.05);

WaypointBounds box(double q, double lower, double upper) {
  return WaypointBounds(Eigen::VectorXd::Constant(1, q), Eigen::VectorXd::Constant(1, lower),
                        Eigen::VectorXd::Constant(1, upper));
}

class RoomTest : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = std::make_unique<Scene>(Scene::load(dir_.write("one_link.xml", test::one_link_cell(kWall))));
  }
  test::TempDir dir_;
  std::unique_ptr<Scene> scene_;
};

TEST_F(RoomTest, TheFreeRangeEndsAtTheWallAndAtTheLimit) {
  RobotState state(*scene_);
  const auto free = one_joint_free_ranges(state, Eigen::VectorXd::Constant(1, 0.2), 1e-5);
  ASSERT_EQ(free.size(), 1u);
  EXPECT_NEAR(free[0].upper, kTouch, 2e-5);
  EXPECT_LE(free[0].upper, kTouch);
  EXPECT_DOUBLE_EQ(free[0].lower, -3.0);
}

// A needle 1 m long and 2 mm wide (link2, turned by j2 about z) and a post 2 mm square standing
// 0.8 m from the axis on the robot's base: a self pair (link1 lies between them). Turning from 0
// toward +y, the needle's leading face (at 1 mm from its axis) meets the post's corner
// (0.001, 0.799) when 0.799 cos(t) - 0.001 sin(t) = 0.001: t = acos(0.001 / R) - atan(0.001 / 0.799),
// R = sqrt(0.799^2 + 0.001^2), 1.56830 rad; it has passed the post 5 mrad later. A sweep in fixed
// steps of 0.02 rad (samples at 1.56 and 1.58) steps over it.
TEST(RoomSelfTest, TheFreeRangeEndsAtAThinPartOfTheRobotItself) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("needle.xml", R"(<mujoco model="needle">
  <compiler angle="radian" autolimits="true"/>
  <worldbody>
    <body name="base">
      <geom name="post" type="box" size="0.001 0.001 0.3" pos="0 0.8 0.3"/>
      <body name="link1" pos="0 0 0.3">
        <joint name="j1" type="hinge" axis="1 0 0" range="-0.1 0.1"/>
        <inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>
        <body name="link2">
          <joint name="j2" type="hinge" axis="0 0 1" range="-3 3"/>
          <geom name="needle" type="box" size="0.5 0.001 0.01" pos="0.5 0 0"/>
          <site name="tool0" pos="1 0 0"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
)"));
  ASSERT_EQ(scene.self_pairs().size(), 1u);
  const double r = std::hypot(0.799, 0.001);
  const double touch = std::acos(0.001 / r) - std::atan(0.001 / 0.799);
  RobotState state(scene);
  const auto free = one_joint_free_ranges(state, Eigen::VectorXd::Zero(2), 1e-5);
  EXPECT_NEAR(free[1].upper, touch, 2e-5);
  EXPECT_LE(free[1].upper, touch);
  EXPECT_DOUBLE_EQ(free[1].lower, -3.0);  // turned the other way, the needle's far side misses the post
}

TEST_F(RoomTest, ANominalInsideTheWallHasNoFreeRangeAndNoShare) {
  // At 1.5 rad the link passes through the wall.
  const RoomReport r = measure_room(*scene_, {box(1.5, 1.5, 1.5)});
  ASSERT_EQ(r.waypoints.size(), 1u);
  EXPECT_EQ(r.waypoints[0].free[0].lower, 1.5);
  EXPECT_EQ(r.waypoints[0].free[0].upper, 1.5);
  EXPECT_TRUE(std::isnan(r.waypoints[0].share[0]));
  EXPECT_TRUE(std::isnan(r.mean_share));
}

TEST_F(RoomTest, ShareAndToolRoomByHand) {
  // Bounds [-0.5, 1.0] around 0: they keep 1.5 of the free 3 + 1.19950 rad. The tool (1 m from the
  // axis) moves by the chord 2 sin(1.0 / 2) = 0.95885 m and turns by 1.0 rad at the upper corner.
  const RoomReport r = measure_room(*scene_, {box(0.0, -0.5, 1.0), box(0.0, -0.25, 0.25)});
  ASSERT_EQ(r.waypoints.size(), 2u);
  EXPECT_NEAR(r.waypoints[0].share[0], 1.5 / (kTouch + 3), 1e-4);
  EXPECT_NEAR(r.waypoints[1].share[0], 0.5 / (kTouch + 3), 1e-4);
  EXPECT_NEAR(r.joint_share[0], 1.0 / (kTouch + 3), 1e-4);
  EXPECT_NEAR(r.mean_share, r.joint_share[0], 1e-12);
  EXPECT_NEAR(r.waypoints[0].tool_translation, 2 * std::sin(0.5), 1e-9);
  EXPECT_NEAR(r.waypoints[0].tool_rotation, 1.0, 1e-6);
  EXPECT_NEAR(r.waypoints[1].tool_translation, 2 * std::sin(0.125), 1e-9);
  EXPECT_NEAR(r.waypoints[1].tool_rotation, 0.25, 1e-6);
}

TEST_F(RoomTest, ALongPathIsMeasuredAtEvenlySpacedWaypointsAndTheResultIsDeterministic) {
  std::vector<WaypointBounds> path;
  for (int k = 0; k < 200; ++k) path.push_back(box(0.004 * k, 0.004 * k - 0.1, 0.004 * k + 0.1));
  RoomOptions options;
  options.max_waypoints = 50;
  const RoomReport one = measure_room(*scene_, path, options, 1);
  const RoomReport two = measure_room(*scene_, path, options, 2);
  ASSERT_EQ(one.waypoints.size(), 50u);
  EXPECT_EQ(one.waypoints.front().waypoint, 0u);
  EXPECT_EQ(one.waypoints.back().waypoint, 199u);
  for (size_t j = 1; j < one.waypoints.size(); ++j) {
    EXPECT_GT(one.waypoints[j].waypoint, one.waypoints[j - 1].waypoint);
    EXPECT_EQ(one.waypoints[j].waypoint, two.waypoints[j].waypoint);
    EXPECT_EQ(one.waypoints[j].share[0], two.waypoints[j].share[0]);
    EXPECT_EQ(one.waypoints[j].tool_translation, two.waypoints[j].tool_translation);
  }
  options.max_waypoints = 0;
  EXPECT_EQ(measure_room(*scene_, path, options).waypoints.size(), 200u);
}

// The ceiling study's sampled growth (bench/room_ceiling.hpp), on the one-link arm: one waypoint at
// 0.2 rad grown from zero width. Its one joint's box is checked at both corners, so it ends below
// the touch angle and at most one last step (1/512 of the free side, 1 rad) short of it; the free
// side is the joint limit, reached exactly (32 steps of 1/32).
TEST_F(RoomTest, TheCeilingOfOneWaypointReachesTheWallAndTheLimit) {
  RoomCeiling ceiling(*scene_, {box(0.2, 0.2, 0.2)}, CeilingOptions{});
  const CeilingExtents grown = ceiling.grow(ceiling.zero(), false);
  const double upper = ceiling.upper(grown, 0)[0], lower = ceiling.lower(grown, 0)[0];
  EXPECT_LE(upper, kTouch);
  EXPECT_GE(upper, kTouch - (kTouch - 0.2) / 512 - 1e-4);
  EXPECT_NEAR(lower, -3.0, 1e-9);
  EXPECT_NEAR(ceiling.mean_share(grown), (upper - lower) / (ceiling.free_ranges(0)[0].upper + 3.0), 1e-12);
}

// The ceiling's extents given to the certificate (RoomCeiling::certify), on the one-link arm: one
// waypoint at 0.2 rad, 3.2 rad below it (to the limit) and above it to 20 mrad short of the touch
// angle, where the link's corner is (cos(t) - 0.05 sin(t)) * 0.02 = 6.3 mm from the wall, more than
// the 1 mm margin: certified. To 20 mrad past the touch angle it is in the wall: not certified; at
// half those extents it is (0.2 + (kTouch - 0.18) / 2 < kTouch), and the share is half the
// full extents' (kTouch - 0.18 + 3.2) / (kTouch + 3) (the free range's end is found to 1e-4 rad).
TEST_F(RoomTest, TheCeilingsBoxesScaledAreGivenToTheCertificate) {
  RoomCeiling ceiling(*scene_, {box(0.2, 0.2, 0.2)}, CeilingOptions{});
  const Certifier certifier(*scene_, CertifyOptions{});
  CertifyContext ctx(*scene_);
  auto extents = [](double above) {
    return CeilingExtents{{Eigen::VectorXd::Constant(1, 3.2)}, {Eigen::VectorXd::Constant(1, above)}};
  };
  const CeilingProof short_of = ceiling.certify(extents(kTouch - 0.22), 1.0, 65536, certifier, ctx);
  EXPECT_EQ(short_of.segments, 1);
  EXPECT_EQ(short_of.certified, 1);
  EXPECT_GT(short_of.leaves, 0);
  EXPECT_NEAR(short_of.share, (kTouch - 0.22 + 3.2) / (kTouch + 3.0), 5e-5);
  const CeilingProof past = ceiling.certify(extents(kTouch - 0.18), 1.0, 65536, certifier, ctx);
  EXPECT_EQ(past.certified, 0);
  const CeilingProof half = ceiling.certify(extents(kTouch - 0.18), 0.5, 65536, certifier, ctx);
  EXPECT_EQ(half.certified, 1);
  EXPECT_DOUBLE_EQ(half.scale, 0.5);
  EXPECT_NEAR(half.share, 0.5 * (kTouch - 0.18 + 3.2) / (kTouch + 3.0), 5e-5);
  // Past the free range's end the share is capped at the whole range.
  EXPECT_DOUBLE_EQ(past.share, 1.0);
}

// A planar two-link arm (link 1 of 1 m about z at the base, j1 within [-0.65, 0.65] rad; link 2 of
// 0.5 m about z at its tip) turning j1 from -0.6 to 0.6 rad with j2 at 0, and a post at 0.9 rad,
// 1.2 m from the base. Only near the end can link 2 reach the post (from j1 = 0.6 the post is
// 0.38 m from link 1's tip; from j1 <= 0 it is more than 0.97 m away, beyond link 2's 0.5 m):
// alone, the first waypoint's j2 is limited only where its own j1 side turns link 2 toward the
// post; with lower and upper linear between the waypoints, the segment's end narrows it further.
const char* kTwoLinkPostCell = R"(<mujoco model="two-link-post">
  <compiler angle="radian" autolimits="true"/>
  <worldbody>
    <body name="base">
      <geom name="base_box" type="box" size="0.1 0.1 0.2" pos="0 0 0.2"/>
      <body name="link1" pos="0 0 0.5">
        <joint name="j1" type="hinge" axis="0 0 1" range="-0.65 0.65"/>
        <geom name="l1_box" type="box" size="0.5 0.05 0.05" pos="0.5 0 0"/>
        <body name="link2" pos="1 0 0">
          <joint name="j2" type="hinge" axis="0 0 1" range="-2.5 2.5"/>
          <geom name="l2_box" type="box" size="0.25 0.05 0.05" pos="0.25 0 0"/>
          <site name="tool0" pos="0.5 0 0"/>
        </body>
      </body>
    </body>
    <geom name="post" type="box" size="0.05 0.05 0.5" pos="0.7460 0.9400 0.5"/>
  </worldbody>
</mujoco>
)";

TEST(RoomCeilingTest, TheSegmentContractKeepsLessThanTheWaypointsAloneAndIsFree) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", kTwoLinkPostCell));
  auto at = [](double j1) {
    const Eigen::Vector2d q(j1, 0.0);
    return WaypointBounds(q, q, q);
  };
  RoomCeiling ceiling(scene, {at(-0.6), at(0.6)}, CeilingOptions{});
  const CeilingExtents alone = ceiling.grow(ceiling.zero(), false);
  const CeilingExtents segment = ceiling.grow(ceiling.zero(), true);
  EXPECT_LT(ceiling.upper(segment, 0)[1], ceiling.upper(alone, 0)[1] - 0.3);
  // The segment's region, checked independently: corners at 101 parameters and 20,000 samples.
  // Sampling can miss thin collisions (the estimate errs high): at most 0.1 % of them collide.
  RobotState state(scene);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Eigen::Vector2d la = ceiling.lower(segment, 0), ua = ceiling.upper(segment, 0);
  const Eigen::Vector2d lb = ceiling.lower(segment, 1), ub = ceiling.upper(segment, 1);
  int hits = 0;
  for (int s = 0; s <= 100; ++s) {
    const double t = s / 100.0;
    const Eigen::Vector2d lo = la + t * (lb - la), hi = ua + t * (ub - ua);
    for (int c = 0; c < 4; ++c)
      hits += state.in_collision(Eigen::Vector2d(c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1]));
  }
  for (int j = 0; j < 20000; ++j) {
    const double t = unit(rng);
    const Eigen::Vector2d lo = la + t * (lb - la), hi = ua + t * (ub - ua);
    hits += state.in_collision(
        Eigen::Vector2d(lo[0] + unit(rng) * (hi[0] - lo[0]), lo[1] + unit(rng) * (hi[1] - lo[1])));
  }
  EXPECT_LE(hits, 20);
  std::printf(
      "two-link post: j2 upper at the start %.4f alone, %.4f on the segment; %d of 20404 checks collide\n",
      ceiling.upper(alone, 0)[1], ceiling.upper(segment, 0)[1], hits);
  // The same seed gives the same boxes.
  RoomCeiling again(scene, {at(-0.6), at(0.6)}, CeilingOptions{});
  const CeilingExtents repeat = again.grow(again.zero(), true);
  for (size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(repeat.lo[k], segment.lo[k]);
    EXPECT_EQ(repeat.hi[k], segment.hi[k]);
  }
}

}  // namespace
}  // namespace leeway
