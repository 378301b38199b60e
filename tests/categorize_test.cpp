#include "leeway/core/categorize.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "leeway/core/error.hpp"

namespace leeway {
namespace {

Box aabb(Eigen::Vector3d lo, Eigen::Vector3d hi) {
  Box b;
  b.center = (lo + hi) / 2;
  b.half_size = (hi - lo) / 2;
  return b;
}

// A 2 x 1.5 m table, top at 0.6 m, and a second one 3 m away.
const std::vector<Box> kTables = {aabb({-1, -0.75, 0}, {1, 0.75, 0.6}), aabb({2, -0.5, 0}, {3, 0.5, 0.6})};

TEST(GoalObstacleTest, FindsTableBelowGoal) {
  auto found = find_goal_obstacle({0.3, 0.2, 0.8}, kTables, 0.01);
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ(*found, 0u);
  found = find_goal_obstacle({2.5, 0.0, 1.8}, kTables, 0.01);
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ(*found, 1u);
}

TEST(GoalObstacleTest, NothingBelowBetweenTables) {
  EXPECT_FALSE(find_goal_obstacle({1.5, 0, 0.8}, kTables, 0.01).has_value());
}

TEST(GoalObstacleTest, StackedObstaclesReturnTheUpperOne) {
  // A mould resting on the table: the descent meets the mould first.
  std::vector<Box> boxes = {aabb({-1, -1, 0}, {1, 1, 0.6}), aabb({-0.5, -0.5, 0.6}, {0.5, 0.5, 1.4})};
  auto found = find_goal_obstacle({0, 0, 1.8}, boxes, 0.01);
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ(*found, 1u);
}

TEST(GoalObstacleTest, CoarseStepCanStepOverAThinBox) {
  // From z = 0.8 with dz = 0.1 the samples are 0.8, 0.7, 0.6, ...: a plate spanning 0.645..0.655
  // is stepped over; with dz = 0.01 the sample at 0.65 lands in it. This is Algorithm 1 as written.
  std::vector<Box> plate = {aabb({-1, -1, 0.645}, {1, 1, 0.655})};
  EXPECT_FALSE(find_goal_obstacle({0, 0, 0.8}, plate, 0.1).has_value());
  EXPECT_TRUE(find_goal_obstacle({0, 0, 0.8}, plate, 0.01).has_value());
}

TEST(GoalObstacleTest, GoalInsideAnObstacleReturnsIt) {
  auto found = find_goal_obstacle({0, 0, 0.3}, kTables, 0.01);
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ(*found, 0u);
}

TEST(GoalObstacleTest, RejectsBadStep) {
  for (double dz : {0.0, -0.01, std::nan(""), static_cast<double>(INFINITY)}) {
    try {
      find_goal_obstacle({0, 0, 1}, kTables, dz);
      ADD_FAILURE() << "dz " << dz << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("dz"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace leeway
