// The cell template: a minimal cell around a robot fragment passes the checker; its home keyframe
// and reach radius by hand; bad robots leave nothing behind.
#include "leeway/io/new_cell.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "leeway/core/check.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/scene.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

class NewCellTest : public test::MujocoTest {};

int files_in(const fs::path& dir) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.is_regular_file() ? 1 : 0;
  return n;
}

TEST_F(NewCellTest, AroundTheHandWrittenIrb6700) {
  test::TempDir dir;
  fs::create_directories(dir.path() / "cells");
  fs::create_directory_symlink(std::string(LEEWAY_MJCF_DIR) + "/robots", dir.path() / "robots");
  const std::string cell = (dir.path() / "cells/irb.xml").string();
  const NewCell c = write_new_cell((dir.path() / "robots/irb6700_body.xml").string(), cell, "irb",
                                   (dir.path() / "robots/irb6700_excludes.xml").string());
  EXPECT_EQ(c.robot_include, "../robots/irb6700_body.xml");
  // The IRB 6700's three box overlaps are excluded by its excludes fragment, included at the top.
  EXPECT_EQ(c.excludes_include, "../robots/irb6700_excludes.xml");
  EXPECT_EQ(c.included_excludes, 3);
  EXPECT_TRUE(c.cell_excludes.empty());
  EXPECT_THAT(c.mjcf, HasSubstr("  <include file=\"../robots/irb6700_excludes.xml\"/>\n  <worldbody>"));
  EXPECT_EQ(c.joints, 6);
  EXPECT_EQ(c.home, "0 0 0 0 0 0");
  // The reach bound by hand: from joint 1 (link_1's origin) down to the patch box: body offsets
  // 0.32 + 1.28 + 0.2 + 1.1825 + 0.2 + 0 (gripper) = 3.1825, the patch's offset 0.155 and its
  // bounding-sphere radius sqrt(0.4^2 + 0.3^2 + 0.005^2) = 0.500025: 3.837525, rounded up 3.9 m.
  EXPECT_DOUBLE_EQ(c.reach_radius, 3.9);
  const Scene s = Scene::load(cell);
  EXPECT_TRUE(check_scene(s).ok());
  ASSERT_EQ(s.keyframes().size(), 1u);
  EXPECT_EQ(s.keyframes()[0].name, "home");
  EXPECT_EQ(s.obstacle_geoms().size(), 0u);
  EXPECT_THAT(c.mjcf, HasSubstr("<numeric name=\"leeway_reach_radius\" data=\"3.9\"/>"));
  EXPECT_EQ(files_in(dir.path() / "cells"), 1);  // no temporary file left
}

TEST_F(NewCellTest, PairsTouchingAtHomeAreExcludedInTheCellWithoutAnExcludesFragment) {
  // irb6700_body.xml has no irb6700_body_excludes.xml beside it: the pairs that touch at home are
  // excluded in the cell itself, each with its overlap in a comment. At home that is the elbow (the
  // upper arm's and the forearm tube's boxes overlap by 5 cm at every j3) and the wrist's box
  // against the flange's.
  test::TempDir dir;
  fs::create_directories(dir.path() / "cells");
  fs::create_directory_symlink(std::string(LEEWAY_MJCF_DIR) + "/robots", dir.path() / "robots");
  const std::string cell = (dir.path() / "cells/irb.xml").string();
  const NewCell c = write_new_cell((dir.path() / "robots/irb6700_body.xml").string(), cell, "irb");
  EXPECT_TRUE(c.excludes_include.empty());
  EXPECT_EQ(c.included_excludes, 0);
  ASSERT_FALSE(c.cell_excludes.empty());
  EXPECT_EQ(c.cell_excludes[0].geom1, "link_2_box");
  EXPECT_EQ(c.cell_excludes[0].geom2, "link_4_tube_box");
  EXPECT_NEAR(c.cell_excludes[0].depth, 0.05, 0.01);
  EXPECT_THAT(c.cell_excludes[0].reason, HasSubstr("at keyframe home"));
  EXPECT_THAT(c.mjcf,
              AllOf(HasSubstr("<!-- link_2_box and link_4_tube_box: the geoms overlap by 0.0"),
                    HasSubstr("<text name=\"leeway_exclude_home_1\" data=\"link_2_box link_4_tube_box\"/>")));
  const Scene s = Scene::load(cell);
  EXPECT_EQ(s.excluded_pairs().size(), c.cell_excludes.size());
  EXPECT_EQ(static_cast<int>(s.self_pairs().size()), c.self_pairs);
  EXPECT_TRUE(check_scene(s).ok());
}

TEST_F(NewCellTest, TheExcludesBesideTheRobotAreIncluded) {
  // robot.xml and robot_excludes.xml side by side, as import-urdf writes them; the fragment excludes
  // the mast on the base against the outer link (a pair chosen for the test).
  test::TempDir dir;
  const std::string robot = dir.write("robot.xml", R"(<mujoco>
  <body name="base"><geom name="base_box" type="box" size="0.1 0.1 0.25" pos="0 0 0.25" contype="1" conaffinity="0"/>
    <geom name="mast_box" type="box" size="0.05 0.05 0.5" pos="0.5 0 0.5" contype="1" conaffinity="0"/>
    <body name="link" pos="0 0 0.5">
      <joint name="j1" type="hinge" axis="0 0 1" range="-3 3" user="1"/>
      <geom name="link_box" type="box" size="0.5 0.05 0.05" pos="0.5 0 0" contype="1" conaffinity="0"/>
      <body name="link2" pos="1 0 0">
        <joint name="j2" type="hinge" axis="0 0 1" range="-3 3" user="1"/>
        <geom name="link2_box" type="box" size="0.3 0.05 0.05" pos="0.3 0 0" contype="1" conaffinity="0"/>
        <site name="tool0" pos="0.6 0 0"/>
      </body>
    </body>
  </body>
</mujoco>)");
  // The rule checks base_box and mast_box against link2_box (link_box is the base's child).
  dir.write("robot_excludes.xml", R"(<mujoco><custom>
  <text name="leeway_exclude_a" data="mast_box link2_box"/></custom></mujoco>)");
  const NewCell c = write_new_cell(robot, (dir.path() / "cell.xml").string(), "two");
  EXPECT_EQ(c.excludes_include, "robot_excludes.xml");
  EXPECT_EQ(c.included_excludes, 1);
  EXPECT_EQ(c.self_pairs, 1);  // base_box - link2_box
  EXPECT_TRUE(c.cell_excludes.empty());
  // A named excludes file that is missing is an error.
  EXPECT_THROW(
      write_new_cell(robot, (dir.path() / "c2.xml").string(), "two", (dir.path() / "no.xml").string()),
      InputError);
}

TEST_F(NewCellTest, HomeIsTheValueNearestZeroWithinTheLimits) {
  test::TempDir dir;
  const std::string robot = dir.write("arm.xml", R"(<mujoco>
  <body name="base"><geom name="base_box" type="box" size="0.1 0.1 0.25" pos="0 0 0.25" contype="1" conaffinity="0"/>
    <body name="link" pos="0 0 0.5">
      <joint name="j1" type="hinge" axis="0 0 1" range="0.5 3" user="1"/>
      <geom name="link_box" type="box" size="0.5 0.05 0.05" pos="0.5 0 0" contype="1" conaffinity="0"/>
      <site name="tool0" pos="1 0 0"/>
    </body>
  </body>
</mujoco>)");
  const NewCell c = write_new_cell(robot, (dir.path() / "cell.xml").string(), "one");
  EXPECT_EQ(c.home, "0.5");
  EXPECT_EQ(c.robot_include, "arm.xml");
  // 0.5 (box offset) + sqrt(0.5^2 + 0.05^2 + 0.05^2) = 1.00499: 1.1 m.
  EXPECT_DOUBLE_EQ(c.reach_radius, 1.1);
}

TEST(NewCellCliTest, BadRobotsExitTwoAndWriteNothing) {
  test::TempDir dir;
  const auto missing = test::run_cli("new-cell --robot " + (dir.path() / "absent.xml").string() + " --out " +
                                     (dir.path() / "c1.xml").string());
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_THAT(missing.out, AllOf(HasSubstr("absent.xml"), HasSubstr("cannot open the robot file")));
  // A whole model is no fragment (it would not compile inside <worldbody>): the message names the
  // robot file and its first model section, not the cell being written.
  const auto whole = test::run_cli("new-cell --robot " + std::string(LEEWAY_MJCF_DIR) +
                                   "/robots/irb6700.xml --out " + (dir.path() / "c2.xml").string());
  EXPECT_EQ(whole.exit_code, 2);
  EXPECT_THAT(whole.out, HasSubstr("leeway: error: " + std::string(LEEWAY_MJCF_DIR) +
                                   "/robots/irb6700.xml: has <compiler> (line 6): a whole MJCF model, "
                                   "not a robot fragment"));
  EXPECT_EQ(std::count(whole.out.begin(), whole.out.end(), '\n'), 1) << whole.out;
  EXPECT_EQ(files_in(dir.path()), 0);
}

}  // namespace
}  // namespace leeway
