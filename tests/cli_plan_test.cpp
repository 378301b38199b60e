// The plan subcommand and bounds --path as a user runs them: exit codes, files, messages.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "leeway/core/kinematics.hpp"
#include "leeway/path/endpoints.hpp"
#include "leeway/path/nominal_path.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using nlohmann::json;
using test::read_json;
using test::run_cli;
using test::workcell;
using ::testing::HasSubstr;

// The one-link arm (test_util.hpp) with a wall along +y: `hit` touches it, `behind` lies beyond
// it (no path from home), the site `far` is out of reach.
const char* kWallKeys = R"(<key name="home" qpos="0"/>
    <key name="hit" qpos="1.5708"/>
    <key name="behind" qpos="2.5"/>)";
const char* kWallWorld = R"(<geom name="wall" type="box" size="1 0.05 1" pos="0 1 1"/>
    <site name="far" pos="3 0 0.5"/>)";

class CliPlanTest : public ::testing::Test {
 protected:
  std::string file(const std::string& name) const { return (dir_.path() / name).string(); }
  std::string one_link() const {
    return dir_.write("one_link.xml", test::one_link_cell(kWallWorld, kWallKeys));
  }
  // The Dallara cell with a wall across the straight path from home to patch (as in
  // planner_test.cpp): RRT-Connect has to find a detour.
  std::string wall_cell() const { return test::dallara_with_wall(dir_); }
  test::TempDir dir_;
};

TEST_F(CliPlanTest, PlanWritesAPathFile) {
  const std::string out = file("p.json");
  const auto r = run_cli("plan " + workcell("dallara") + " --from home --to patch --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("wrote " + out));
  const json j = read_json(out);
  EXPECT_EQ(j.at("format"), "leeway-path-1");
  EXPECT_EQ(j.at("joints").size(), 6u);
  ASSERT_GE(j.at("waypoints").size(), 2u);
  for (const auto& w : j.at("waypoints")) EXPECT_EQ(w.at("q").size(), 6u);
  const Scene scene = Scene::load(workcell("dallara"));
  EXPECT_EQ(read_path(out, scene).front(), scene.keyframe("home").q);
  EXPECT_EQ(read_path(out, scene).back(), scene.keyframe("patch").q);
  for (const char* key : {"from", "to", "planner", "length", "time", "collision_checks", "simplified"})
    EXPECT_TRUE(j.contains(key)) << key;
}

TEST_F(CliPlanTest, SameSeedSamePath) {
  const std::string cell = wall_cell();
  auto waypoints = [&](const std::string& seed, const std::string& name) {
    const auto r =
        run_cli("plan " + cell + " --from home --to patch --seed " + seed + " --out " + file(name));
    EXPECT_EQ(r.exit_code, 0) << r.out;
    return read_json(file(name)).at("waypoints");
  };
  const json a = waypoints("5", "a.json");
  EXPECT_GT(a.size(), 2u);  // a detour around the wall
  EXPECT_EQ(waypoints("5", "b.json"), a);
  EXPECT_NE(waypoints("6", "c.json"), a);
}

TEST_F(CliPlanTest, PlansFromAKeyframeToASite) {
  const std::string out = file("p.json");
  const auto r =
      run_cli("plan " + workcell("dlr") + " --from patch --to site:mould --out " + out + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const Scene scene = Scene::load(workcell("dlr"));
  RobotState state(scene);
  const Eigen::VectorXd goal = read_path(out, scene).back();
  EXPECT_LT((state.fk(goal).position - site_position(scene, "mould")).norm(), 1e-3);
  EXPECT_NEAR(goal[0], site_position(scene, "mould").x(), 1e-9);  // the rail policy
  const json j = read_json(out);
  EXPECT_EQ(j.at("to").at("site"), "mould");
  EXPECT_EQ(j.at("from").at("keyframe"), "patch");
}

TEST_F(CliPlanTest, BoundsAlongAPathFile) {
  const std::string cell = wall_cell(), path = file("p.json"), bounds = file("b.json");
  ASSERT_EQ(run_cli("plan " + cell + " --from home --to patch --out " + path).exit_code, 0);
  const auto r = run_cli("bounds " + cell + " --path " + path + " --max-cells 300 --out " + bounds);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const json p = read_json(path), b = read_json(bounds);
  ASSERT_EQ(b.at("waypoints").size(), p.at("waypoints").size());
  for (size_t i = 0; i < p.at("waypoints").size(); ++i)
    EXPECT_EQ(b.at("waypoints")[i].at("q"), p.at("waypoints")[i].at("q")) << i;
  // A bounds file has the same shape: its nominal path can be bounded again.
  const auto again = run_cli("bounds " + cell + " --path " + bounds + " --max-cells 300 --json");
  ASSERT_EQ(again.exit_code, 0) << again.out;
  EXPECT_EQ(json::parse(again.out).at("waypoints").size(), p.at("waypoints").size());
}

TEST_F(CliPlanTest, BoundsPlansFirstForASiteGoal) {
  const auto r =
      run_cli("bounds " + workcell("dallara") + " --from home --to site:patch --max-cells 300 --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const json j = json::parse(r.out);
  ASSERT_GE(j.at("waypoints").size(), 2u);
  EXPECT_EQ(j.at("goal_obstacle"), "patch_table");
}

TEST_F(CliPlanTest, StartOrGoalInCollisionIsBadInput) {
  const std::string cell = one_link(), out = file("p.json");
  auto r = run_cli("plan " + cell + " --from hit --to home --out " + out);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_THAT(r.out, HasSubstr("leeway: error: " + cell +
                               ": start 'hit' is in collision: link 'link_box' penetrates obstacle 'wall'"));
  r = run_cli("plan " + cell + " --from home --to hit --out " + out);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_THAT(r.out, HasSubstr("goal 'hit' is in collision"));
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST_F(CliPlanTest, UnreachableSiteExitsOne) {
  const std::string cell = one_link(), out = file("p.json");
  const auto r = run_cli("plan " + cell + " --from home --to site:far --out " + out);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("leeway: unreachable: " + cell + ": goal 'site:far' at (3, 0, 0.5) m"));
  EXPECT_THAT(r.out, HasSubstr("nothing written"));
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST_F(CliPlanTest, NoPathWithinTheTimeLimitExitsOne) {
  const std::string cell = one_link(), out = file("p.json");
  auto r = run_cli("plan " + cell + " --from home --to behind --time-limit 0.2 --out " + out);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("leeway: no path: " + cell +
                               ": no collision-free path from start 'home' to goal 'behind' found within the "
                               "time limit of 0.2 s (seed 1)"));
  EXPECT_FALSE(std::filesystem::exists(out));
  // bounds plans first, and stops the same way on an unreachable goal.
  r = run_cli("bounds " + cell + " --from home --to site:far --out " + out);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST_F(CliPlanTest, PathFileOfAnotherCellIsBadInput) {
  const std::string path = file("p.json"), out = file("b.json");
  ASSERT_EQ(run_cli("plan " + workcell("dallara") + " --from home --to patch --out " + path).exit_code, 0);
  const auto r = run_cli("bounds " + workcell("dlr") + " --path " + path + " --out " + out);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_THAT(r.out,
              HasSubstr("leeway: error: " + path +
                        ": its joints 'j1 j2 j3 j4 j5 j6' do not match the robot in " + workcell("dlr")));
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST_F(CliPlanTest, BadCombinationsAndValuesAreBadInput) {
  const std::string path = file("p.json");
  ASSERT_EQ(run_cli("plan " + workcell("dallara") + " --from home --to patch --out " + path).exit_code, 0);
  const std::pair<std::string, std::string> cases[] = {
      {"bounds " + workcell("dallara") + " --path " + path + " --from home", "--path excludes --from"},
      {"bounds " + workcell("dallara") + " --path " + path + " --waypoints 4", "--waypoints applies to"},
      {"bounds " + workcell("dallara"), "give the path with --from and --to"},
      {"bounds " + workcell("dallara") + " --path " + file("missing.json"), "cannot open the path file"},
      {"plan " + workcell("dallara") + " --from home --to patch --time-limit 0", "'time_limit' = 0 s"},
      {"plan " + workcell("dallara") + " --from home --to patch --resolution -1", "'resolution' = -1 rad"},
      {"plan " + workcell("dallara") + " --from home --to nowhere", "no keyframe 'nowhere'"},
      {"plan " + workcell("dallara") + " --from home --to site:nowhere", "no goal site 'nowhere'"},
      {"plan " + workcell("dallara") + " --from home --to xyz:1,2", "three coordinates"},
      {"plan " + workcell("dallara") + " --from home", "--to is required"},
  };
  for (const auto& [args, message] : cases) {
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.out;
    EXPECT_THAT(r.out, HasSubstr(message)) << args;
  }
}

}  // namespace
}  // namespace leeway
