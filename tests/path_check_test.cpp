// The dense check of the nominal path: the library against positions derived by hand
// from the geometry, and `leeway bounds` / `leeway sweep` as a user runs them.
#include "leeway/path/path_check.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "leeway/core/error.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/path/nominal_path.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using nlohmann::json;
using test::read_json;
using test::run_cli;
using test::workcell;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr double kStep = 0.002;  // PathCheckOptions' default resolutions [rad, m]

// The one-link arm of test_util.hpp (hinge about z at height 0.5 m, link box 1 m x 0.1 m x 0.1 m
// along +x from the axis) and a wall occupying y in [0.95, 1.05] for |x| <= 1. The link's corner
// (1, 0.05) in the link frame is at y = sin(t) + 0.05 cos(t) at angle t, so the link first touches
// the wall at sin(t) + 0.05 cos(t) = 0.95: t = asin(0.95 / sqrt(1 + 0.05^2)) - atan(0.05).
const char* kWall = R"(<geom name="wall" type="box" size="1 0.05 1" pos="0 1 1"/>)";
const char* kWallKeys = R"(<key name="home" qpos="0"/>
    <key name="hit" qpos="1.5708"/>
    <key name="behind" qpos="2.5"/>)";
const double kTouch = std::asin(0.95 / std::sqrt(1.0 + 0.05 * 0.05)) - std::atan(0.05);  // 1.19950 rad

// A carriage (box of half-size 0.05 m) on a slide along x over [0, 2] m and a plate 8 mm thick
// across its way, its near face at x = 1.0007 - 0.004 = 0.9967: the carriage touches it at
// x = 0.9967 - 0.05 = 0.9467 m and leaves it behind at 1.0047 + 0.05 = 1.0547 m.
const char* kSlideCell = R"(<mujoco model="slide">
  <compiler angle="radian" autolimits="true"/>
  <worldbody>
    <body name="carriage" pos="0 0 0.5">
      <joint name="x" type="slide" axis="1 0 0" range="0 2"/>
      <geom name="carriage_box" type="box" size="0.05 0.05 0.05"/>
      <site name="tool0"/>
    </body>
    <geom name="plate" type="box" size="0.004 0.5 0.5" pos="1.0007 0 0.5"/>
  </worldbody>
</mujoco>
)";
constexpr double kPlateTouch = 0.9467;

Eigen::VectorXd q1(double v) { return Eigen::VectorXd::Constant(1, v); }

class PathCheckTest : public test::MujocoTest {
 protected:
  Scene one_link() const {
    return Scene::load(dir_.write("one_link.xml", test::one_link_cell(kWall, kWallKeys)));
  }
  Scene slide() const { return Scene::load(dir_.write("slide.xml", kSlideCell)); }
  test::TempDir dir_;
};

TEST_F(PathCheckTest, OneLinkArmHitsTheWallWhereTheGeometrySays) {
  const Scene scene = one_link();
  const double goal = 1.5708;
  const auto r = check_path(scene, {q1(0), q1(goal)});
  ASSERT_TRUE(r.collision.has_value());
  const PathCollision& c = *r.collision;
  // ceil(1.5708 / 0.002) = 786 samples; the first colliding one is the first at or past the touch.
  const double n = 786, s_touch = kTouch / goal;
  EXPECT_GE(c.s, s_touch - 1e-9);
  EXPECT_LE(c.s, s_touch + 1.0 / n + 1e-9);
  EXPECT_NEAR(c.s * n, std::round(c.s * n), 1e-9);  // a sample of the 786
  EXPECT_EQ(c.waypoint, -1);
  EXPECT_EQ(c.edge, 0);
  EXPECT_DOUBLE_EQ(c.path_parameter, c.s);
  EXPECT_DOUBLE_EQ(c.path_fraction, c.s);
  EXPECT_NEAR(c.q[0], c.s * goal, 1e-12);
  EXPECT_EQ(c.obstacle, "wall");
  EXPECT_EQ(c.link, "link_box");
  EXPECT_EQ(scene.geom_label(c.obstacle_geom), "wall");
  EXPECT_EQ(c.joint, -1);
  // The corner moves dy/dt = cos(t) - 0.05 sin(t) = 0.3151 m/rad: at most one step deep.
  EXPECT_GT(c.depth, 0.0);
  EXPECT_LE(c.depth, kStep * (std::cos(kTouch) - 0.05 * std::sin(kTouch)) + 1e-6);
  // The first: the sample before it is free, and every sample up to it was checked once.
  RobotState state(scene);
  EXPECT_FALSE(state.in_collision(q1(c.q[0] - goal / n)));
  EXPECT_EQ(r.checks, 1 + std::lround(c.s * n));
  EXPECT_EQ(describe_collision(scene, c),
            "hits 'wall' on edge 0 -> 1 at s = " + format_number(std::round(c.s * 1000) / 1000) +
                " (link 'link_box', depth " + format_number(c.depth) + " m)");
  // Deterministic.
  const auto again = check_path(scene, {q1(0), q1(goal)});
  EXPECT_EQ(again.checks, r.checks);
  EXPECT_EQ(again.collision->s, c.s);
}

TEST_F(PathCheckTest, TheEdgeAndThePathParameterOfALaterEdge) {
  const Scene scene = one_link();
  // Edges 0 -> 0.4 -> 0.8 -> 1.5708: the touch lies on edge 2 at s = (t - 0.8) / 0.7708.
  const auto r = check_path(scene, {q1(0), q1(0.4), q1(0.8), q1(1.5708)});
  ASSERT_TRUE(r.collision.has_value());
  const PathCollision& c = *r.collision;
  const double n = 386;  // ceil(0.7708 / 0.002)
  const double s_touch = (kTouch - 0.8) / 0.7708;
  EXPECT_EQ(c.edge, 2);
  EXPECT_EQ(c.waypoint, -1);
  EXPECT_GE(c.s, s_touch - 1e-9);
  EXPECT_LE(c.s, s_touch + 1.0 / n + 1e-9);
  EXPECT_DOUBLE_EQ(c.path_parameter, 2 + c.s);
  EXPECT_DOUBLE_EQ(c.path_fraction, (2 + c.s) / 3);
  // Waypoint 0, then 200 + 200 samples on the free edges, then the samples of edge 2 up to the hit.
  EXPECT_EQ(r.checks, 1 + 200 + 200 + std::lround(c.s * n));
  EXPECT_THAT(describe_collision(scene, c), HasSubstr("hits 'wall' on edge 2 -> 3 at s = 0."));
  EXPECT_THAT(describe_collision(scene, c, true),
              HasSubstr("hits 'wall' at s = " + format_number(std::round(c.path_fraction * 1000) / 1000) +
                        " (link 'link_box'"));
}

TEST_F(PathCheckTest, AFreePathCountsEveryCheck) {
  const Scene scene = one_link();
  // Away from the wall: 0 -> -1.5 -> 0.3 rad, 750 and 900 steps of 2 mrad plus the first waypoint.
  auto r = check_path(scene, {q1(0), q1(-1.5), q1(0.3)});
  EXPECT_TRUE(r.free());
  EXPECT_FALSE(r.collision.has_value());
  EXPECT_EQ(r.checks, 1 + 750 + 900);
  // The hinge resolution is a parameter: 10 mrad gives 150 + 180 steps.
  PathCheckOptions coarse;
  coarse.resolution = 0.01;
  r = check_path(scene, {q1(0), q1(-1.5), q1(0.3)}, coarse);
  EXPECT_TRUE(r.free());
  EXPECT_EQ(r.checks, 1 + 150 + 180);
  // A repeated waypoint is one step; a single free waypoint is one check.
  EXPECT_EQ(check_path(scene, {q1(0.2), q1(0.2)}).checks, 2);
  EXPECT_EQ(check_path(scene, {q1(0.2)}).checks, 1);
}

TEST_F(PathCheckTest, AWaypointInCollisionIsNamed) {
  const Scene scene = one_link();
  // The first waypoint itself ('hit'): found by the first check.
  auto r = check_path(scene, {scene.keyframe("hit").q, q1(0)});
  ASSERT_TRUE(r.collision.has_value());
  EXPECT_EQ(r.collision->waypoint, 0);
  EXPECT_EQ(r.collision->edge, 0);
  EXPECT_EQ(r.collision->s, 0.0);
  EXPECT_EQ(r.checks, 1);
  EXPECT_THAT(describe_collision(scene, *r.collision),
              HasSubstr("hits 'wall' at waypoint 0 (link 'link_box'"));
  // An end 1 mrad past the touch: the sample before it (1.9 mrad back) is free, so the first
  // colliding configuration is waypoint 1 itself, at s = 1 of edge 0.
  r = check_path(scene, {q1(0), q1(kTouch + 0.001), q1(0)});
  ASSERT_TRUE(r.collision.has_value());
  EXPECT_EQ(r.collision->waypoint, 1);
  EXPECT_EQ(r.collision->edge, 0);
  EXPECT_EQ(r.collision->s, 1.0);
  EXPECT_DOUBLE_EQ(r.collision->path_parameter, 1.0);
  EXPECT_DOUBLE_EQ(r.collision->path_fraction, 0.5);
  EXPECT_EQ(r.collision->q[0], kTouch + 0.001);
  EXPECT_EQ(r.checks, 1 + static_cast<long>(std::ceil((kTouch + 0.001) / kStep)));
  // A waypoint outside the limits [-3, 3] rad: the joint is named, there is no contact.
  r = check_path(scene, {q1(-3.1), q1(0)});
  ASSERT_TRUE(r.collision.has_value());
  EXPECT_EQ(r.collision->joint, 0);
  EXPECT_EQ(r.collision->link_geom, -1);
  EXPECT_EQ(describe_collision(scene, *r.collision),
            "leaves the limits of joint 'j1' (-3.1 rad, limits [-3, 3] rad) at waypoint 0");
}

TEST_F(PathCheckTest, TheSlideResolutionIsHonoured) {
  const Scene scene = slide();
  // 0 -> 2 m in 1000 steps of 2 mm: the first colliding sample is the first at or past 0.9467 m.
  auto r = check_path(scene, {q1(0), q1(2)});
  ASSERT_TRUE(r.collision.has_value());
  EXPECT_GE(r.collision->q[0], kPlateTouch - 1e-9);
  EXPECT_LE(r.collision->q[0], kPlateTouch + kStep + 1e-9);
  EXPECT_NEAR(r.collision->s, r.collision->q[0] / 2, 1e-12);
  EXPECT_EQ(r.collision->obstacle, "plate");
  EXPECT_EQ(r.collision->link, "carriage_box");
  EXPECT_EQ(r.checks, 1 + std::lround(r.collision->s * 1000));
  // The hinge resolution does not apply to a slide.
  PathCheckOptions o;
  o.resolution = 0.3;
  EXPECT_EQ(check_path(scene, {q1(0), q1(2)}, o).collision->s, r.collision->s);
  // Slide steps of 0.3 m (7 samples, 2/7 m apart: 0.857 and 1.143 m straddle the plate's
  // 0.9467 .. 1.0547 m) miss the 8 mm plate; 0.1 m steps find it at 1.0 m (s = 0.5).
  o = {};
  o.slide_resolution = 0.3;
  r = check_path(scene, {q1(0), q1(2)}, o);
  EXPECT_TRUE(r.free());
  EXPECT_EQ(r.checks, 1 + 7);
  o.slide_resolution = 0.1;
  r = check_path(scene, {q1(0), q1(2)}, o);
  ASSERT_TRUE(r.collision.has_value());
  EXPECT_DOUBLE_EQ(r.collision->s, 0.5);
  EXPECT_EQ(r.checks, 1 + 10);
}

TEST_F(PathCheckTest, HingesAndASlideTogetherTakeTheFinerStepCount) {
  // DLR, home -> patch: the rail moves 3.083558 m, the largest hinge motion is 3.141593 rad.
  const Scene scene = Scene::load(workcell("dlr"));
  const std::vector<Eigen::VectorXd> path = {scene.keyframe("home").q, scene.keyframe("patch").q};
  PathCheckOptions o;
  auto r = check_path(scene, path, o);  // hinges: ceil(1570.8) = 1571, rail: ceil(1541.8) = 1542
  EXPECT_TRUE(r.free());
  EXPECT_EQ(r.checks, 1 + 1571);
  o.slide_resolution = 0.001;  // rail: ceil(3083.6) = 3084
  r = check_path(scene, path, o);
  EXPECT_TRUE(r.free());
  EXPECT_EQ(r.checks, 1 + 3084);
}

TEST_F(PathCheckTest, BadInputThrowsWithoutNamingFlags) {
  const Scene scene = one_link();
  auto message = [&](const std::vector<Eigen::VectorXd>& path, const PathCheckOptions& o) {
    try {
      check_path(scene, path, o);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_THAT(message({}, {}), HasSubstr("the path has no waypoints"));
  PathCheckOptions o;
  o.resolution = 0;
  EXPECT_THAT(message({q1(0)}, o), HasSubstr("the resolution 0 rad must be a finite number > 0"));
  o = {};
  o.slide_resolution = NAN;
  EXPECT_THAT(message({q1(0)}, o), HasSubstr("m must be a finite number > 0"));
  EXPECT_THAT(message({q1(0), Eigen::VectorXd::Zero(2)}, {}), HasSubstr("path waypoint 1"));
  EXPECT_THAT(message({q1(0), q1(NAN)}, {}), HasSubstr("path waypoint 1"));
  for (const auto& m : {message({}, {}), message({q1(0)}, o)}) EXPECT_THAT(m, Not(HasSubstr("--")));
}

// ---- resolve_nominal_path: the one policy of every command ---------------------------------

TEST_F(PathCheckTest, ResolveRefusesACollidingStraightPathWhenNotToPlanAround) {
  const Scene scene = one_link();
  PathRequest r;
  r.from = "home";
  r.to = "behind";
  r.plan_around = false;
  const NominalPath p = resolve_nominal_path(scene, r);
  EXPECT_EQ(p.refusal, PathRefusal::kCollision);
  EXPECT_STREQ(refusal_name(p.refusal), "collision");
  EXPECT_TRUE(p.waypoints.empty());
  // The touch at 1.1995 rad of 2.5: s = 0.480.
  EXPECT_THAT(p.message,
              HasSubstr(scene.source() + ": the straight path from home to behind hits 'wall' at s = 0.48"));
  EXPECT_THAT(p.message, Not(HasSubstr("itself")));
}

TEST_F(PathCheckTest, ResolveNamesAKeyframeThatIsNotFreeAndThePlannersReason) {
  const Scene scene = one_link();
  PathRequest r;
  r.from = "hit";
  r.to = "home";
  const NominalPath stuck = resolve_nominal_path(scene, r);
  EXPECT_EQ(stuck.refusal, PathRefusal::kCollision);
  EXPECT_THAT(stuck.message, HasSubstr("keyframe 'hit' itself is not free, so no path avoids it"));
  // Beyond the wall: no way around it for a one-link arm within its limits.
  r.from = "home";
  r.to = "behind";
  r.plan.time_limit = 0.2;
  const NominalPath none = resolve_nominal_path(scene, r);
  EXPECT_EQ(none.refusal, PathRefusal::kNoPath);
  EXPECT_STREQ(refusal_name(none.refusal), "no path");
  EXPECT_THAT(none.message, HasSubstr("the straight path from home to behind hits 'wall'"));
  r.from.clear();
  EXPECT_THROW(resolve_nominal_path(scene, r), InputError);
}

TEST_F(PathCheckTest, ResolveChecksAFreeStraightPathAndPlansAroundAWall) {
  const Scene free_cell = Scene::load(workcell("dallara"));
  PathRequest r;
  r.from = "home";
  r.to = "patch";
  const NominalPath straight = resolve_nominal_path(free_cell, r);
  ASSERT_TRUE(straight.ok()) << straight.message;
  EXPECT_TRUE(straight.linear);
  EXPECT_FALSE(straight.planned);
  EXPECT_EQ(straight.label, "home -> patch");
  EXPECT_EQ(straight.waypoints.size(), 2u);
  EXPECT_TRUE(straight.replaced.empty());
  // Joint 4 turns by pi: ceil(pi / 0.002) = 1571 steps plus the start.
  EXPECT_EQ(straight.record.at("checks"), 1572);
  EXPECT_EQ(straight.record.at("planned"), false);

  const Scene walled = Scene::load(test::dallara_with_wall(dir_));
  const NominalPath around = resolve_nominal_path(walled, r);
  ASSERT_TRUE(around.ok()) << around.message;
  EXPECT_TRUE(around.planned);
  EXPECT_GT(around.waypoints.size(), 2u);
  EXPECT_EQ(around.label, "home -> patch (planned around 'wall')");
  EXPECT_THAT(around.replaced, HasSubstr("hits 'wall'"));
  EXPECT_EQ(around.record.at("replaced_straight_path").at("obstacle"), "wall");
  EXPECT_TRUE(check_path(walled, around.waypoints).free());  // what it returns is free
}

TEST_F(PathCheckTest, ResolveRefusesAnUnreachableGoal) {
  const Scene scene = Scene::load(workcell("dallara"));
  PathRequest r;
  r.from = "home";
  r.to = "xyz:5,5,5";
  const NominalPath p = resolve_nominal_path(scene, r);
  EXPECT_EQ(p.refusal, PathRefusal::kUnreachable);
  EXPECT_THAT(p.message, HasSubstr(": goal 'xyz:5,5,5' at (5, 5, 5) m: no collision-free configuration"));
}

// ---- The command line ------------------------------------------------------------------------

// The number after "s = " in a message (-1 when there is none).
double s_in(const std::string& message) {
  std::smatch m;
  if (!std::regex_search(message, m, std::regex("s = ([0-9.]+)"))) return -1;
  return std::stod(m[1]);
}

class CliPathCheckTest : public ::testing::Test {
 protected:
  std::string file(const std::string& name) const { return (dir_.path() / name).string(); }
  std::string one_link() const { return dir_.write("one_link.xml", test::one_link_cell(kWall, kWallKeys)); }
  // The Dallara cell with a wall across the straight path from home to patch.
  std::string wall_cell() const { return test::dallara_with_wall(dir_); }
  test::TempDir dir_;
};

TEST_F(CliPathCheckTest, AFreeStraightPathIsCheckedAndRecorded) {
  const std::string out = file("b.json");
  const auto r =
      run_cli("bounds " + workcell("dallara") + " --from home --to patch --max-cells 300 --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_THAT(r.out, Not(HasSubstr("hits")));
  const json n = read_json(out).at("nominal_path");
  EXPECT_EQ(n.at("checked"), true);
  EXPECT_EQ(n.at("resolution"), 0.002);
  EXPECT_EQ(n.at("slide_resolution"), 0.002);
  EXPECT_EQ(n.at("planned"), false);
  EXPECT_FALSE(n.contains("replaced_straight_path"));
  // Joint 4 turns by pi (0 -> -3.14159): ceil(3.14159 / 0.002) = 1571 steps plus the start.
  EXPECT_EQ(n.at("checks"), 1572);
}

TEST_F(CliPathCheckTest, ACollidingStraightPathIsPlannedAround) {
  const std::string cell = wall_cell(), out = file("b.json");
  const auto r = run_cli("bounds " + cell + " --from home --to patch --max-cells 300 --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("the straight path from home to patch hits 'wall' at s = "));
  EXPECT_THAT(r.out, HasSubstr("planned a path with"));
  // The s printed is the library's, to three decimals.
  const Scene scene = Scene::load(cell);
  const auto straight = check_path(scene, keyframe_path(scene, "home", "patch", 2));
  ASSERT_TRUE(straight.collision.has_value());
  EXPECT_NEAR(s_in(r.out), straight.collision->path_fraction, 5e-4 + 1e-12);
  const json b = read_json(out);
  const json& n = b.at("nominal_path");
  EXPECT_EQ(n.at("planned"), true);
  const json& replaced = n.at("replaced_straight_path");
  EXPECT_EQ(replaced.at("obstacle"), "wall");
  EXPECT_EQ(replaced.at("from"), "home");
  EXPECT_EQ(replaced.at("to"), "patch");
  EXPECT_EQ(replaced.at("waypoints"), 2);
  EXPECT_EQ(replaced.at("s").get<double>(), straight.collision->path_fraction);
  EXPECT_EQ(replaced.at("checks"), straight.checks);
  // The bounded path is the planned one: from home to patch, around the wall, free when re-checked.
  const auto path = read_path(out, scene);
  ASSERT_GT(path.size(), 2u);
  EXPECT_EQ(path.front(), scene.keyframe("home").q);
  EXPECT_EQ(path.back(), scene.keyframe("patch").q);
  EXPECT_THAT(r.out, HasSubstr("planned a path with " + std::to_string(path.size()) + " waypoints"));
  const auto recheck = check_path(scene, path);
  EXPECT_TRUE(recheck.free());
  EXPECT_EQ(n.at("checks"), recheck.checks);

  // With more waypoints, s is along the whole straight path and the planned path replaces them.
  const auto five = run_cli("bounds " + cell +
                            " --from home --to patch --waypoints 5 --max-cells 300 --out " + file("b5.json"));
  ASSERT_EQ(five.exit_code, 0) << five.out;
  EXPECT_THAT(five.out, HasSubstr("the straight path from home to patch (5 waypoints) hits 'wall' at s = "));
  EXPECT_THAT(five.out, HasSubstr("which replaces the 5 straight waypoints"));
  // Samples 2 mrad apart on each quarter rather than on the whole: within a step of each other.
  EXPECT_NEAR(s_in(five.out), straight.collision->path_fraction, 1.0 / 1571 + 5e-4 + 1e-9);
  EXPECT_EQ(read_json(file("b5.json")).at("waypoints"), b.at("waypoints"));  // same seed, same plan
}

TEST_F(CliPathCheckTest, NoPlanExitsOneAndWritesNothing) {
  const std::string cell = wall_cell(), out = file("b.json");
  const auto r = run_cli("bounds " + cell + " --from home --to patch --no-plan --out " + out);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("leeway: collision: " + cell +
                               ": the straight path from home to patch hits 'wall' at s = "));
  EXPECT_THAT(r.out, HasSubstr("; nothing written"));
  EXPECT_THAT(r.out, Not(HasSubstr("planned a path")));
  EXPECT_FALSE(std::filesystem::exists(out));
  // leeway sweep and render get their path the same way: with --no-plan they refuse with the same
  // message, and without it they plan around the wall as bounds does.
  const std::string refusal = r.out.substr(0, r.out.find(" (link"));
  const auto sweep =
      run_cli("sweep " + cell + " --from home --to patch --no-plan --max-cells 100 --csv " + out);
  EXPECT_EQ(sweep.exit_code, 1) << sweep.out;
  EXPECT_THAT(sweep.out, HasSubstr(refusal));
  EXPECT_FALSE(std::filesystem::exists(out));
  const std::string png = file("r.png");
  const auto render = run_cli("render " + cell + " --from home --to patch --no-plan --out " + png);
  EXPECT_EQ(render.exit_code, 1) << render.out;
  EXPECT_THAT(render.out, HasSubstr(refusal));
  EXPECT_FALSE(std::filesystem::exists(png));
  const auto planned = run_cli("sweep " + cell + " --from home --to patch --max-cells 100 --csv " + out);
  EXPECT_EQ(planned.exit_code, 0) << planned.out;
  EXPECT_THAT(planned.out, HasSubstr("the straight path from home to patch hits 'wall' at s = "));
  EXPECT_THAT(planned.out, HasSubstr("; planned a path with "));
  EXPECT_TRUE(std::filesystem::exists(out));
}

TEST_F(CliPathCheckTest, NoPathAroundExitsOneWithThePlannersReason) {
  const std::string cell = one_link(), out = file("b.json");
  // 'behind' (2.5 rad) lies beyond the wall, which the arm cannot pass: the straight path hits it
  // at t = 1.1995 rad, s = 1.1995 / 2.5 = 0.480, and there is no way around.
  auto r = run_cli("bounds " + cell + " --from home --to behind --time-limit 0.2 --out " + out);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("leeway: no path: " + cell +
                               ": the straight path from home to behind hits 'wall' at s = 0.48 (link "
                               "'link_box'"));
  EXPECT_THAT(r.out, HasSubstr("no collision-free path from start 'home' to goal 'behind' found within the "
                               "time limit of 0.2 s (seed 1)"));
  EXPECT_FALSE(std::filesystem::exists(out));
  // A keyframe in collision cannot be planned around: no planner run, same exit code.
  r = run_cli("bounds " + cell + " --from hit --to home --out " + out);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("the straight path from hit to home hits 'wall' at s = 0 (link 'link_box'"));
  EXPECT_THAT(r.out, HasSubstr("keyframe 'hit' itself is not free"));
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST_F(CliPathCheckTest, ACollidingPathFileExitsOneNamingTheEdge) {
  const std::string cell = one_link(), path = file("p.json"), out = file("b.json");
  std::ofstream(path) << R"({"format": "leeway-path-1", "joints": ["j1"],
    "waypoints": [{"q": [0]}, {"q": [0.4]}, {"q": [0.8]}, {"q": [1.5708]}]})";
  const auto r = run_cli("bounds " + cell + " --path " + path + " --out " + out);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.out,
              HasSubstr("leeway: collision: " + path + ": the path hits 'wall' on edge 2 -> 3 at s = "));
  EXPECT_THAT(r.out, HasSubstr("(link 'link_box', depth "));
  EXPECT_THAT(r.out, HasSubstr("; nothing written"));
  // s on edge 2 (0.8 -> 1.5708 rad, 386 samples): the touch at (t - 0.8) / 0.7708 = 0.5182, the
  // first sample past it, rounded to three decimals.
  const double s_touch = (kTouch - 0.8) / 0.7708;
  EXPECT_GE(s_in(r.out), s_touch - 5e-4);
  EXPECT_LE(s_in(r.out), s_touch + 1.0 / 386 + 5e-4);
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST_F(CliPathCheckTest, APlannedPathIsReCheckedFiner) {
  // A 4 mm wide link and a 2 mm pin 0.9 m out at 0.5025 rad; the goal site at 0.995 rad. The
  // planner's direct edge, checked every 0.995 / 100 = 9.95 mrad, has samples at 0.4975 and
  // 0.50745 rad, both clear of the pin (it blocks the link from 0.4988 to 0.5062 rad: 0.002 m
  // half-width plus the pin's half-diagonal projection, over 0.9 m), so the planner returns it.
  // At 2 mrad (498 samples) the link hits the pin at s = 0.4988 / 0.995 = 0.501 or one step later.
  const double pin = 0.5025, goal = 0.995;
  std::ostringstream xml;
  xml << std::setprecision(17) << R"(<mujoco model="thin-link">
  <compiler angle="radian" autolimits="true"/>
  <worldbody>
    <body name="base">
      <geom name="base_box" type="box" size="0.1 0.1 0.25" pos="0 0 0.25"/>
      <body name="link" pos="0 0 0.5">
        <joint name="j1" type="hinge" axis="0 0 1" range="-3 3"/>
        <geom name="link_box" type="box" size="0.5 0.002 0.05" pos="0.5 0 0"/>
        <site name="tool0" pos="1 0 0" euler="3.141592653589793 0 0"/>
      </body>
    </body>
    <geom name="pin" type="box" size="0.001 0.001 0.5" pos=")"
      << 0.9 * std::cos(pin) << " " << 0.9 * std::sin(pin) << R"( 0.5"/>
    <site name="goal" pos=")"
      << std::cos(goal) << " " << std::sin(goal) << R"( 0.5"/>
  </worldbody>
  <keyframe><key name="home" qpos="0"/></keyframe>
</mujoco>
)";
  const std::string cell = dir_.write("pin.xml", xml.str()), out = file("b.json");
  // `plan` checks the path it found at 2 mrad before writing it, as `bounds` does.
  const std::string path_file = file("p.json");
  const auto plan = run_cli("plan " + cell + " --from home --to site:goal --out " + path_file);
  EXPECT_EQ(plan.exit_code, 1) << plan.out;
  EXPECT_THAT(plan.out,
              HasSubstr(": the path planned from home to site:goal hits 'pin' on edge 0 -> 1 at s = "));
  EXPECT_THAT(plan.out, HasSubstr("when checked at 0.002 rad (the planner checks at 0.01 rad: use a finer "
                                  "--resolution or another --seed); nothing written"));
  EXPECT_FALSE(std::filesystem::exists(path_file));
  const auto r = run_cli("bounds " + cell + " --from home --to site:goal --out " + out);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_THAT(r.out,
              HasSubstr("leeway: collision: " + cell +
                        ": the path planned from home to site:goal hits 'pin' on edge 0 -> 1 at s = "));
  EXPECT_THAT(r.out,
              HasSubstr("when checked at 0.002 rad (the planner checks at 0.01 rad); nothing written"));
  // The link's edge reaches the pin's nearest corner at 0.9 sin(pin - t) = 0.002 + 0.001 (sin t + cos t).
  const double touch = pin - std::asin((0.002 + 0.001 * (std::sin(0.4988) + std::cos(0.4988))) / 0.9);
  EXPECT_GE(s_in(r.out), touch / goal - 5e-4);
  EXPECT_LE(s_in(r.out), touch / goal + 1.0 / 498 + 5e-4);
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace leeway
