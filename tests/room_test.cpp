// The room the bounds keep: one-joint free ranges, the kept shares and the tool's room, against
// values worked out by hand on the one-link arm.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "leeway/core/kinematics.hpp"
#include "leeway/core/room.hpp"
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

}  // namespace
}  // namespace leeway
