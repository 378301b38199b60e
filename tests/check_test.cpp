#include "leeway/core/check.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "leeway/core/box.hpp"
#include "leeway/core/kinematics.hpp"

#include "stl_util.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using test::one_link_cell;
using test::workcell;
using ::testing::HasSubstr;

class CheckTest : public test::MujocoTest {
 protected:
  test::TempDir dir_;
  CheckReport run(const std::string& world, const std::string& keys = "") {
    scene_ = std::make_unique<Scene>(Scene::load(dir_.write("cell.xml", one_link_cell(world, keys))));
    return check_scene(*scene_);
  }
  bool has_problem(const CheckReport& r, const std::string& fragment) {
    for (const auto& p : r.problems)
      if (p.find(fragment) != std::string::npos) return true;
    return false;
  }
  std::unique_ptr<Scene> scene_;
};

TEST_F(CheckTest, CleanCellPasses) {
  // The tip moves on the circle of radius 1 m at z = 0.5 m; the goal (0, 1, 0.5) lies on it, 0.1 m
  // above a table whose top is at 0.4 m.
  const auto r = run(R"(<geom name="table" type="box" size="0.2 0.2 0.2" pos="0 1 0.2"/>
    <site name="goal" pos="0 1 0.5"/>)",
                     R"(<key name="home" qpos="0"/>)");
  EXPECT_TRUE(r.ok()) << ::testing::PrintToString(r.problems);
  ASSERT_EQ(r.goals.size(), 1u);
  EXPECT_EQ(scene_->geom_label(r.goals[0].goal_obstacle), "table");
  EXPECT_TRUE(r.goals[0].reachable);
}

TEST_F(CheckTest, KnownCollisionInAKeyframe) {
  const auto r = run(R"(<geom name="wall" type="box" size="1 0.05 1" pos="0 1 1"/>)",
                     R"(<key name="home" qpos="0"/><key name="left" qpos="1.5707963"/>)");
  EXPECT_FALSE(r.ok());
  ASSERT_EQ(r.keyframes.size(), 2u);
  EXPECT_TRUE(r.keyframes[0].collisions.empty());
  // At q = 0 the link (y within +-0.05, z 0.45 .. 0.55) is 0.90 m from the wall's face at y = 0.95.
  EXPECT_NEAR(r.keyframes[0].clearance.distance, 0.90, 1e-9);
  EXPECT_EQ(r.keyframes[1].clearance.distance, 0.0);
  ASSERT_EQ(r.keyframes[1].collisions.size(), 1u);
  EXPECT_NEAR(r.keyframes[1].collisions[0].depth, 0.05, 1e-6);
  EXPECT_TRUE(has_problem(r, "keyframe 'left': link 'link_box' collides with obstacle 'wall'"));
}

TEST_F(CheckTest, AKeyframeFoldedIntoItselfFailsNamingBothGeoms) {
  // j3 = pi/2 turns l3 down along l2: the tool (z 0.3 .. 0.4 m) sinks 0.1 m into l1 (z 0.2 .. 0.4 m),
  // and l3's end meets l1's top; no obstacle is touched.
  scene_ = std::make_unique<Scene>(Scene::load(
      dir_.write("cell.xml", test::three_link_cell("", R"(<key name="folded" qpos="0 0 1.5707963"/>)"))));
  const CheckReport r = check_scene(*scene_);
  EXPECT_FALSE(r.ok());
  ASSERT_EQ(r.keyframes.size(), 2u);
  EXPECT_TRUE(r.keyframes[0].self_collisions.empty());
  const KeyframeFindings& folded = r.keyframes[1];
  EXPECT_TRUE(folded.collisions.empty());
  ASSERT_FALSE(folded.self_collisions.empty());
  EXPECT_EQ(scene_->geom_label(folded.self_collisions[0].geom1), "l1_box");
  EXPECT_EQ(scene_->geom_label(folded.self_collisions[0].geom2), "tool_box");
  EXPECT_NEAR(folded.self_collisions[0].depth, 0.1, 1e-6);
  EXPECT_TRUE(has_problem(r,
                          "keyframe 'folded': robot geoms 'l1_box' and 'tool_box' collide "
                          "(self-collision, depth 0.1 m)"));
  EXPECT_THAT(to_text(*scene_, r),
              HasSubstr("self-collision: 5 robot geom pairs checked, 0 excluded by the cell"));
  const nlohmann::json j = to_json(*scene_, r);
  EXPECT_EQ(j.at("robot").at("self_pairs"), 5);
  EXPECT_EQ(j.at("keyframes").at(1).at("self_collisions").at(0).at("a"), "l1_box");
  EXPECT_EQ(j.at("keyframes").at(1).at("self_collisions").at(0).at("b"), "tool_box");

  // Excluded, the same keyframe passes, and the report says how each pair was excluded.
  scene_ = std::make_unique<Scene>(Scene::load(dir_.write(
      "excluded.xml", test::three_link_cell(R"(<contact><exclude body1="link1" body2="link3"/></contact>
  <custom><text name="leeway_exclude_tool" data="l1_box tool_box"/></custom>)",
                                            R"(<key name="folded" qpos="0 0 1.5707963"/>)"))));
  const CheckReport ok = check_scene(*scene_);
  EXPECT_TRUE(ok.ok()) << ::testing::PrintToString(ok.problems);
  const nlohmann::json e = to_json(*scene_, ok).at("robot");
  EXPECT_EQ(e.at("self_pairs"), 3);
  EXPECT_EQ(e.at("excluded_pairs"),
            nlohmann::json::parse(R"([{"a": "l1_box", "b": "l3_box", "by": "body exclude"},
                                      {"a": "l1_box", "b": "tool_box", "by": "leeway_exclude"}])"));
}

TEST_F(CheckTest, JointLimitViolation) {
  const auto r = run("", R"(<key name="over" qpos="3.1"/>)");
  ASSERT_EQ(r.keyframes[0].limit_violations.size(), 1u);
  EXPECT_TRUE(has_problem(r, "keyframe 'over': joint 'j1' = 3.1 rad is outside its range -3 .. 3 rad"));
}

TEST_F(CheckTest, CollidablePlaneIsAProblemNotAGoalObstacle) {
  // The plane rule (box.hpp, has_bounding_box): check and categorize both leave planes out of
  // Algorithm 1, so the goal above the table finds the table and the other goal finds nothing.
  const auto r = run(R"(<geom name="ground" type="plane" size="5 5 0.1"/>
    <geom name="table" type="box" size="0.2 0.2 0.2" pos="0 1 0.2"/>
    <site name="goal" pos="0 1 0.5"/><site name="bare" pos="0 -1 0.5"/>)",
                     R"(<key name="home" qpos="0"/>)");
  EXPECT_TRUE(has_problem(r, "obstacle ground is a collidable plane"));
  ASSERT_EQ(r.goals.size(), 2u);
  EXPECT_EQ(scene_->geom_label(r.goals[0].goal_obstacle), "table");
  EXPECT_EQ(r.goals[1].goal_obstacle, -1);
  const int ground = scene_->obstacle_geoms().front();
  EXPECT_FALSE(has_bounding_box(scene_->model(), ground));
  EXPECT_TRUE(has_bounding_box(scene_->model(), scene_->obstacle_geoms().back()));
}

TEST_F(CheckTest, GoalWithNoObstacleBelow) {
  const auto r = run(R"(<geom name="table" type="box" size="0.2 0.2 0.2" pos="0 -1 0.2"/>
    <site name="goal" pos="0 1 0.5"/>)");
  ASSERT_EQ(r.goals.size(), 1u);
  EXPECT_EQ(r.goals[0].goal_obstacle, -1);
  EXPECT_TRUE(r.goals[0].reachable);
  EXPECT_TRUE(has_problem(r, "goal site 'goal' at (0, 1, 0.5) m: no obstacle lies below it"));
}

TEST_F(CheckTest, GoalFarOutsideReach) {
  // The tip moves on a circle of radius 1 m at z = 0.5 m: a site at (4, 0, 0.5) is 3 m away.
  const auto r = run(R"(<geom name="pad" type="box" size="0.2 0.2 0.2" pos="4 0 0.2"/>
    <site name="far" pos="4 0 0.5"/>)");
  ASSERT_EQ(r.goals.size(), 1u);
  EXPECT_FALSE(r.goals[0].reachable);
  EXPECT_NEAR(r.goals[0].reach_error, 3.0, 1e-6);
  EXPECT_TRUE(has_problem(r, "goal site 'far' at (4, 0, 0.5) m is outside the robot's reach"));
}

TEST_F(CheckTest, OverlappingObstacles) {
  // Two boxes overlapping by 0.1 m along x; a third resting on the first (touching only).
  const auto r = run(R"(<geom name="a" type="box" size="0.5 0.5 0.5" pos="2 2 0.5"/>
    <geom name="b" type="box" size="0.5 0.5 0.5" pos="2.9 2 0.5"/>
    <geom name="c" type="box" size="0.2 0.2 0.2" pos="2 2 1.2"/>)");
  ASSERT_EQ(r.overlaps.size(), 1u);
  EXPECT_NEAR(r.overlaps[0].depth, 0.1, 1e-6);
  EXPECT_TRUE(has_problem(r, "obstacles 'a' and 'b' overlap by 0.1 m"));
}

TEST_F(CheckTest, UnnamedObstacleAndNonBoxObstacle) {
  // A sphere is checked by its real shape: no warning.
  const auto r = run(R"(<geom type="box" size="0.1 0.1 0.1" pos="3 3 0.1"/>
    <geom name="ball" type="sphere" size="0.1" pos="-3 3 0.1"/>)");
  EXPECT_TRUE(has_problem(r, "unnamed geom"));
  for (const auto& w : r.warnings) EXPECT_EQ(w.find("ball"), std::string::npos) << w;
}

// An L-shaped mesh (two closed boxes, [0, 1] x [0, 0.2] and [0, 0.2] x [0.2, 1], 0.1 m thick): the
// mesh holds 0.036 m^3 and its hull, over the pentagon (0, 0), (1, 0), (1, 0.2), (0.2, 1), (0, 1)
// of area 0.68 m^2, 0.068 m^3, so the hull fills in 0.032 m^3 (47.1 % of it). A box mesh: 0 %.
TEST_F(CheckTest, MeshObstacleReportsWhatItsHullFillsIn) {
  test::write_binary_stl((dir_.path() / "ell.stl").string(), [] {
    auto a = test::cuboid(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0.2, 0.1));
    const auto b = test::cuboid(Eigen::Vector3d(0, 0.2, 0), Eigen::Vector3d(0.2, 1, 0.1));
    a.insert(a.end(), b.begin(), b.end());
    return a;
  }());
  test::write_binary_stl((dir_.path() / "brick.stl").string(),
                         test::cuboid(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.3, 0.2, 0.1)));
  std::string xml = one_link_cell(R"(<geom name="ell" type="mesh" mesh="ell" pos="2 2 0"/>
    <geom name="brick" type="mesh" mesh="brick" pos="-2 2 0"/>)");
  xml.replace(
      xml.find("<worldbody>"), 11,
      R"(<asset><mesh name="ell" file="ell.stl"/><mesh name="brick" file="brick.stl"/></asset><worldbody>)");
  scene_ = std::make_unique<Scene>(Scene::load(dir_.write("cell.xml", xml)));
  const CheckReport r = check_scene(*scene_);
  std::vector<std::string> about_ell, about_brick;
  for (const auto& w : r.warnings) {
    if (w.find("obstacle ell is a mesh") != std::string::npos) about_ell.push_back(w);
    if (w.find("brick") != std::string::npos) about_brick.push_back(w);
  }
  ASSERT_EQ(about_ell.size(), 1u) << ::testing::PrintToString(r.warnings);
  EXPECT_NE(about_ell[0].find("fills in 0.032 m^3 beyond the mesh (47.1 % of the hull"), std::string::npos)
      << about_ell[0];
  EXPECT_NE(about_ell[0].find("leeway import-mesh"), std::string::npos);
  EXPECT_TRUE(about_brick.empty()) << ::testing::PrintToString(about_brick);
}

TEST_F(CheckTest, JsonHasTheDocumentedFields) {
  const auto r =
      run(R"(<geom name="wall" type="box" size="1 0.05 1" pos="0 1 1"/><site name="goal" pos="0 1 2.5"/>)",
          R"(<key name="left" qpos="1.5707963"/>)");
  const auto j = to_json(*scene_, r);
  EXPECT_FALSE(j.at("ok").get<bool>());
  EXPECT_FALSE(j.at("problems").empty());
  EXPECT_EQ(j.at("keyframes")[0].at("name"), "left");
  EXPECT_EQ(j.at("keyframes")[0].at("collisions")[0].at("obstacle"), "wall");
  EXPECT_TRUE(j.at("keyframes")[0].at("limit_violations").empty());
  EXPECT_EQ(j.at("keyframes")[0].at("clearance").at("distance").get<double>(), 0.0);
  EXPECT_EQ(j.at("goals")[0].at("site"), "goal");
  EXPECT_EQ(j.at("goals")[0].at("goal_obstacle"), "wall");
}

TEST_F(CheckTest, ObstacleOverlapsAreEveryOverlappingPairInIndexOrder) {
  // 400 small boxes, some rotated, many overlapping, spread over 3 x 3 m beside the arm: the
  // overlaps check_scene reports (through the midphase's grid) are exactly the pairs whose
  // separating-axis depth exceeds the tolerance, in the order of a double loop over the obstacles.
  std::mt19937_64 rng(9);
  auto u = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  std::string world;
  for (int i = 0; i < 400; ++i) {
    char g[256];
    std::snprintf(
        g, sizeof(g),
        R"(<geom name="o%d" type="box" pos="%.4f %.4f %.4f" size="%.4f %.4f %.4f" euler="0 %.3f %.3f"/>)", i,
        u(1.5, 4.5), u(-1.5, 1.5), u(0.1, 0.4), u(0.02, 0.12), u(0.02, 0.12), u(0.02, 0.1),
        i % 3 ? 0.0 : u(-1, 1), i % 2 ? 0.0 : u(-1, 1));
    world += g;
  }
  const CheckReport r = run(world);
  const mjModel& m = scene_->model();
  DataPtr d = make_data(m);
  mj_kinematics(&m, d.get());
  const auto& obstacles = scene_->obstacle_geoms();
  ASSERT_EQ(obstacles.size(), 400u);
  std::vector<std::pair<int, int>> expected;
  for (size_t i = 0; i < obstacles.size(); ++i)
    for (size_t j = i + 1; j < obstacles.size(); ++j)
      if (box_penetration(geom_box(m, *d, obstacles[i]), geom_box(m, *d, obstacles[j])) >
          CheckOptions{}.overlap_tolerance)
        expected.emplace_back(obstacles[i], obstacles[j]);
  size_t with_base = 0;
  for (int o : obstacles)
    for (int b : scene_->base_geoms())
      if (box_penetration(geom_box(m, *d, o), geom_box(m, *d, b)) > CheckOptions{}.overlap_tolerance)
        ++with_base;
  // Every pair counted; the first kMaxListedOverlaps listed (the obstacle pairs come first).
  ASSERT_GT(expected.size(), kMaxListedOverlaps);  // not vacuous, and beyond the listed ones
  EXPECT_EQ(r.overlap_count, expected.size() + with_base);
  std::vector<std::pair<int, int>> got;
  for (const Overlap& o : r.overlaps)
    if (scene_->role(o.geom_b) == GeomRole::kObstacle) got.emplace_back(o.geom_a, o.geom_b);
  const std::vector<std::pair<int, int>> listed(expected.begin(), expected.begin() + kMaxListedOverlaps);
  EXPECT_EQ(got, listed);
  EXPECT_THAT(r.problems.back(), HasSubstr("... and " + std::to_string(r.overlap_count - kMaxListedOverlaps) +
                                           " more overlapping pairs"));
  // The text names the first 20 of the 400 and says how many it left out; the JSON has all.
  const std::string text = to_text(*scene_, r);
  EXPECT_THAT(text, HasSubstr("obstacles: 400 (o0, o1, "));
  EXPECT_THAT(text, HasSubstr(", o19, ... and 380 more: --json lists them all)\n"));
  EXPECT_EQ(text.find("o20,"), std::string::npos);
  EXPECT_EQ(to_json(*scene_, r)["obstacles"].size(), 400u);
}

}  // namespace
}  // namespace leeway
