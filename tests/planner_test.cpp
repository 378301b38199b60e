#include "leeway/path/planner.hpp"
#include "leeway/path/endpoints.hpp"
#include "leeway/path/nominal_path.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <thread>

#include "leeway/core/error.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using test::one_link_cell;
using test::workcell;

// The fine re-check of every edge: no joint moves more than 2 mrad (hinges) or 2 mm (slides)
// between checked configurations, five times finer than the planner's default resolution.
constexpr double kFine = 0.002;

// The Dallara cell plus a 1.8 m high wall across the straight joint-space path from home to patch
// (and from patch to mould): the planner must find a detour. Written beside a link to the bundled
// robots, because MJCF includes resolve from the main file's folder.
std::string wall_cell(const test::TempDir& dir) {
  std::filesystem::create_directories(dir.path() / "cells");
  std::filesystem::create_directory_symlink(std::string(LEEWAY_MJCF_DIR) + "/robots", dir.path() / "robots");
  std::ifstream in(workcell("dallara"));
  std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string wall =
      R"(<geom name="wall" type="box" pos="1.151 -0.706 0.9" size="0.55 0.05 0.9" euler="0 0 -0.55")"
      R"( contype="0" conaffinity="1"/>)";
  xml.replace(xml.find("</worldbody>"), 0, wall + "\n");
  return dir.write("cells/wall.xml", xml);
}

// Every waypoint within the limits, every edge free at the fine resolution (with the margin).
void expect_free_path(const Scene& scene, const std::vector<Eigen::VectorXd>& path, double clearance,
                      const std::string& what) {
  ASSERT_GE(path.size(), 2u) << what;
  RobotState state(scene);
  long checks = 0;
  for (size_t i = 0; i < path.size(); ++i)
    EXPECT_TRUE(scene.joints_outside_limits(path[i]).empty()) << what << " waypoint " << i;
  for (size_t i = 1; i < path.size(); ++i)
    EXPECT_TRUE(edge_is_free(state, path[i - 1], path[i], kFine, kFine, clearance, checks))
        << what << " edge " << i - 1 << " -> " << i;
}

class PlannerTest : public test::MujocoTest {};

TEST_F(PlannerTest, PlaceSlidesPutsTheRailAbeamOfTheGoal) {
  const Scene scene = Scene::load(workcell("dlr"));
  const Eigen::VectorXd home = scene.keyframe("home").q;
  // The arm base (joint 1) is above the world origin at rail_x = 0: the rail goes to the goal's x.
  for (const char* site : {"patch", "mould"}) {
    const Eigen::Vector3d goal = site_position(scene, site);
    const Eigen::VectorXd q = place_slides(scene, goal, home);
    EXPECT_NEAR(q[0], goal.x(), 1e-12) << site;
    EXPECT_NEAR(q[0], scene.keyframe(site).q[0], 1e-6) << site;  // the keyframes' policy
    EXPECT_EQ(q.tail(6), home.tail(6)) << site;                  // hinges untouched
  }
  // Clamped to the rail's range [-9, 1] m.
  EXPECT_DOUBLE_EQ(place_slides(scene, {5, 1, 1}, home)[0], 1.0);
  EXPECT_DOUBLE_EQ(place_slides(scene, {-20, 1, 1}, home)[0], -9.0);
  // Without slides nothing changes.
  const Scene dallara = Scene::load(workcell("dallara"));
  const Eigen::VectorXd q = dallara.keyframe("patch").q;
  EXPECT_EQ(place_slides(dallara, {1, 1, 1}, q), q);
  EXPECT_THROW(place_slides(scene, {NAN, 0, 0}, home), InputError);
}

TEST_F(PlannerTest, GripperIkReproducesTheDlrKeyframesFromAnywhereOnTheRail) {
  // Seeded with the carriage at home (-4 m) and the arm near the keyframe's branch: the policy
  // moves the carriage abeam of the site and the IK lands on the keyframe (tools/dlr_keyframes.sh).
  const Scene scene = Scene::load(workcell("dlr"));
  RobotState state(scene);
  for (const char* site : {"patch", "mould"}) {
    const Eigen::VectorXd key = scene.keyframe(site).q;
    Eigen::VectorXd seed = key;
    seed[0] = scene.keyframe("home").q[0];
    seed.segment<3>(1).array() += 0.05;
    const IkResult r = gripper_ik(state, site_position(scene, site), seed);
    ASSERT_TRUE(r.success) << site;
    EXPECT_LT((r.q - key).cwiseAbs().maxCoeff(), 1e-5) << site;
    const Pose pose = state.fk(r.q);
    EXPECT_LT((pose.position - site_position(scene, site)).norm(), 1e-3) << site;
    EXPECT_NEAR(pose.rotation(2, 2), -1.0, 1e-5) << site;
  }
}

TEST_F(PlannerTest, GripperIkWithoutSlidesIsSolveIk) {
  // The published-pose IK checks live in kinematics_test.cpp; on a fixed base gripper_ik adds
  // nothing to solve_ik.
  const Scene scene = Scene::load(workcell("baltico"));
  RobotState a(scene), b(scene);
  const Eigen::Vector3d goal = site_position(scene, "mould");
  const Eigen::VectorXd seed = scene.keyframe("home").q;
  EXPECT_EQ(gripper_ik(a, goal, seed).q, solve_ik(b, goal, seed).q);
}

TEST_F(PlannerTest, ResolvesKeyframesSitesAndPoints) {
  const Scene scene = Scene::load(workcell("dallara"));
  RobotState state(scene);
  auto [a, b] = resolve_endpoints(scene, "home", "site:mould");
  EXPECT_EQ(a.keyframe, "home");
  EXPECT_EQ(a.q, scene.keyframe("home").q);
  EXPECT_EQ(b.site, "mould");
  ASSERT_TRUE(b.reachable);
  EXPECT_LT((state.fk(b.q).position - site_position(scene, "mould")).norm(), 1e-3);
  EXPECT_NEAR(state.fk(b.q).rotation(2, 2), -1.0, 1e-5);
  EXPECT_FALSE(state.in_collision(b.q));

  std::tie(a, b) = resolve_endpoints(scene, "xyz:1.2,-0.8,1.0", "patch");
  ASSERT_TRUE(a.reachable);
  EXPECT_LT((state.fk(a.q).position - Eigen::Vector3d(1.2, -0.8, 1.0)).norm(), 1e-3);
  // Seeded with the other end: the solution nearest the patch keyframe.
  EXPECT_LT((a.q - scene.keyframe("patch").q).norm(), 2.0);

  auto message = [&](const std::string& from, const std::string& to) {
    try {
      resolve_endpoints(scene, from, to);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("nowhere", "patch").find("nowhere"), std::string::npos);
  EXPECT_NE(message("home", "site:nowhere").find("nowhere"), std::string::npos);
  EXPECT_NE(message("home", "site:").find("names no site"), std::string::npos);
  EXPECT_NE(message("home", "xyz:1,2").find("three coordinates"), std::string::npos);
  EXPECT_NE(message("home", "xyz:1,2,nan").find("nan"), std::string::npos);
}

TEST_F(PlannerTest, AnUnreachableGoalIsAnOutcome) {
  const Scene scene = Scene::load(workcell("dallara"));
  const auto [a, b] = resolve_endpoints(scene, "home", "xyz:6,0,1");
  EXPECT_TRUE(a.reachable);
  EXPECT_FALSE(b.reachable);
  EXPECT_GT(b.ik.position_error, 2.0);
}

TEST_F(PlannerTest, PlansBetweenTheNamedPosesAndSitesOfEveryCell) {
  // Default options (the direct edge when free), RRT-Connect's raw path, and RRT-Connect simplified.
  PlanOptions raw, simplified;
  raw.try_direct = simplified.try_direct = false;
  raw.simplify = false;
  const std::pair<const char*, const char*> pairs[] = {
      {"home", "patch"}, {"patch", "mould"}, {"mould", "home"}, {"site:patch", "site:mould"}};
  for (const char* cell : {"dallara", "baltico", "dlr"}) {
    const Scene scene = Scene::load(workcell(cell));
    for (const auto& [from, to] : pairs) {
      const auto [a, b] = resolve_endpoints(scene, from, to);
      ASSERT_TRUE(a.reachable && b.reachable) << cell << " " << from << " -> " << to;
      for (const PlanOptions& o : {PlanOptions{}, raw, simplified}) {
        const std::string what = std::string(cell) + " " + from + " -> " + to + (o.try_direct ? "" : " rrt") +
                                 (o.simplify ? "" : " raw");
        const PlanResult r = plan_path(scene, a.q, b.q, o, from, to);
        ASSERT_TRUE(r.success) << what << ": " << r.message;
        EXPECT_EQ(r.method, o.try_direct ? "direct" : "rrt_connect") << what;
        EXPECT_EQ(r.simplified, !o.try_direct && o.simplify) << what;
        EXPECT_EQ(r.waypoints.front(), a.q) << what;
        EXPECT_EQ(r.waypoints.back(), b.q) << what;
        expect_free_path(scene, r.waypoints, 0.0, what);
      }
    }
  }
}

TEST_F(PlannerTest, FindsADetourAroundAWall) {
  test::TempDir dir;
  const Scene scene = Scene::load(wall_cell(dir));
  RobotState state(scene);
  long checks = 0;
  for (const auto& [from, to] : {std::pair{"home", "patch"}, std::pair{"patch", "mould"}}) {
    const Eigen::VectorXd a = scene.keyframe(from).q, b = scene.keyframe(to).q;
    ASSERT_FALSE(edge_is_free(state, a, b, kFine, kFine, 0, checks))
        << "the wall must block the straight edge";
    const PlanResult r = plan_path(scene, a, b);
    ASSERT_TRUE(r.success) << r.message;
    EXPECT_EQ(r.method, "rrt_connect");
    EXPECT_TRUE(r.simplified);
    EXPECT_GT(r.waypoints.size(), 2u);
    EXPECT_GT(r.checks, 0);
    expect_free_path(scene, r.waypoints, 0.0, std::string(from) + " -> " + to);
  }
}

TEST_F(PlannerTest, SameSeedSamePath) {
  test::TempDir dir;
  const Scene scene = Scene::load(wall_cell(dir));
  const Eigen::VectorXd a = scene.keyframe("home").q, b = scene.keyframe("patch").q;
  for (bool simplify : {true, false}) {
    PlanOptions o;
    o.seed = 7;
    o.simplify = simplify;
    const PlanResult first = plan_path(scene, a, b, o);
    const PlanResult again = plan_path(scene, a, b, o);
    ASSERT_TRUE(first.success && again.success);
    EXPECT_EQ(first.waypoints, again.waypoints) << "simplify " << simplify;
    EXPECT_EQ(first.checks, again.checks) << "simplify " << simplify;
    o.seed = 8;
    const PlanResult other = plan_path(scene, a, b, o);
    ASSERT_TRUE(other.success);
    EXPECT_NE(first.waypoints, other.waypoints) << "simplify " << simplify;
  }
}

TEST_F(PlannerTest, ConcurrentPlansAreIndependentAndDeterministic) {
  test::TempDir dir;
  const Scene scene = Scene::load(wall_cell(dir));
  const Eigen::VectorXd a = scene.keyframe("home").q, b = scene.keyframe("patch").q;
  PlanOptions o;
  o.seed = 11;
  const PlanResult reference = plan_path(scene, a, b, o);
  ASSERT_TRUE(reference.success);
  std::vector<PlanResult> results(4);
  std::vector<std::thread> threads;
  for (auto& r : results) threads.emplace_back([&] { r = plan_path(scene, a, b, o); });
  for (auto& t : threads) t.join();
  for (const auto& r : results) EXPECT_EQ(r.waypoints, reference.waypoints);
}

TEST_F(PlannerTest, KeepsTheClearanceMargin) {
  test::TempDir dir;
  const Scene scene = Scene::load(wall_cell(dir));
  RobotState state(scene);
  PlanOptions o;
  o.clearance = 0.03;  // the patch hangs 0.04 m above its table at the goal
  const Eigen::VectorXd a = scene.keyframe("home").q, b = scene.keyframe("patch").q;
  const PlanResult r = plan_path(scene, a, b, o);
  ASSERT_TRUE(r.success) << r.message;
  expect_free_path(scene, r.waypoints, o.clearance, "clearance 0.03");
  // A goal closer than the margin cannot end a path.
  o.clearance = 0.05;
  try {
    plan_path(scene, a, b, o, "start 'home'", "goal 'patch'");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("goal 'patch' is 0.04"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("m from obstacle 'patch_table' (link 'patch_box'), closer than the "
                                         "clearance margin 0.05 m"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(PlannerTest, StartOrGoalInCollisionOrOutsideTheLimitsIsBadInput) {
  // At q = pi/2 the one-link arm lies along +y into the wall.
  test::TempDir dir;
  const Scene scene = Scene::load(
      dir.write("cell.xml", one_link_cell(R"(<geom name="wall" type="box" size="1 0.05 1" pos="0 1 1"/>)")));
  Eigen::VectorXd free(1), hit(1), outside(1);
  free << 0.0;
  hit << M_PI / 2;
  outside << 3.5;
  auto message = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    try {
      plan_path(scene, a, b, {}, "start 'a'", "goal 'b'");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(hit, free).find(
                "start 'a' is in collision: link 'link_box' penetrates obstacle 'wall' by 0.05 m"),
            std::string::npos)
      << message(hit, free);
  EXPECT_NE(message(free, hit).find("goal 'b' is in collision"), std::string::npos);
  EXPECT_NE(message(free, outside).find("goal 'b': joint 'j1' = 3.5 rad is outside its limits [-3, 3]"),
            std::string::npos)
      << message(free, outside);
  EXPECT_NE(message(free, Eigen::VectorXd::Zero(2)).find("goal 'b'"), std::string::npos);
  EXPECT_NE(message(free, hit).find(scene.source()), std::string::npos);
}

// A one-link arm whose only way from 0 to 2.5 rad a wall blocks: no path exists.
struct WalledIn {
  test::TempDir dir;
  Scene scene = Scene::load(
      dir.write("cell.xml", one_link_cell(R"(<geom name="wall" type="box" size="1 0.05 1" pos="0 1 1"/>)")));
  Eigen::VectorXd a = Eigen::VectorXd::Constant(1, 0.0), b = Eigen::VectorXd::Constant(1, 2.5);
};

TEST_F(PlannerTest, NoPathWithinTheTimeLimitIsAnOutcome) {
  const WalledIn w;
  const Scene& scene = w.scene;
  const Eigen::VectorXd &a = w.a, &b = w.b;
  PlanOptions o;
  o.time_limit = 0.2;
  const auto t0 = std::chrono::steady_clock::now();
  const PlanResult r = plan_path(scene, a, b, o, "start 'a'", "goal 'b'");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_FALSE(r.success);
  EXPECT_TRUE(r.waypoints.empty());
  EXPECT_NE(r.message.find(
                "no collision-free path from start 'a' to goal 'b' found within the time limit of 0.2 s"),
            std::string::npos)
      << r.message;
  EXPECT_NE(r.message.find("try a longer time limit or another seed"), std::string::npos) << r.message;
  EXPECT_EQ(r.message.find("--"), std::string::npos) << r.message;
  EXPECT_LT(seconds, 1.0);
}

TEST_F(PlannerTest, TheTreesStopAtTheirStateLimitWhateverTheTimeLimit) {
  // The same impossible problem with an hour to spend: the state limit (the memory guard) ends it
  // after exactly max_states motion checks, each at least one collision check.
  const WalledIn w;
  PlanOptions o;
  o.time_limit = 3600;
  o.max_states = 200;
  const PlanResult r = plan_path(w.scene, w.a, w.b, o, "start 'a'", "goal 'b'");
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("no collision-free path from start 'a' to goal 'b' found in 200 motions"),
            std::string::npos)
      << r.message;
  EXPECT_NE(r.message.find("memory limit"), std::string::npos) << r.message;
  EXPECT_GE(r.checks, 200);
  EXPECT_LT(r.plan_seconds, 60.0);
}

TEST_F(PlannerTest, RejectsBadOptions) {
  const Scene scene = Scene::load(workcell("dallara"));
  const Eigen::VectorXd a = scene.keyframe("home").q, b = scene.keyframe("patch").q;
  auto message = [&](PlanOptions o) {
    try {
      plan_path(scene, a, b, o);
    } catch (const InputError& e) {
      // The library names its options; the programs name their flags.
      EXPECT_EQ(std::string(e.what()).find("--"), std::string::npos) << e.what();
      return std::string(e.what());
    }
    return std::string("no error");
  };
  PlanOptions o;
  o.time_limit = NAN;
  EXPECT_NE(message(o).find("plan option 'time_limit' = nan s"), std::string::npos);
  o = {};
  o.resolution = 0;
  EXPECT_NE(message(o).find("plan option 'resolution' = 0 rad"), std::string::npos);
  o = {};
  o.slide_resolution = INFINITY;
  EXPECT_NE(message(o).find("plan option 'slide_resolution' = inf m"), std::string::npos);
  o = {};
  o.clearance = -0.1;
  EXPECT_NE(message(o).find("plan option 'clearance' = -0.1 m"), std::string::npos);
  o = {};
  o.range = -1;
  EXPECT_NE(message(o).find("plan option 'range' = -1 rad"), std::string::npos);
  o = {};
  o.max_states = 15;
  EXPECT_NE(message(o).find("plan option 'max_states' = 15 must be from 16 to 16777216"), std::string::npos);
  o.max_states = 16L * 1024 * 1024 + 1;
  EXPECT_NE(message(o).find("plan option 'max_states' = 16777217"), std::string::npos);
  // The library names its options; the programs name their flags.
}

TEST_F(PlannerTest, EdgeCheckHonoursTheResolution) {
  // A 0.02 m thin wall at x = 0.7 across the arm's sweep: the tip passes it around q = 0.
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write(
      "cell.xml", one_link_cell(R"(<geom name="wall" type="box" size="0.01 0.3 1" pos="0.7 0.5 1"/>)")));
  RobotState state(scene);
  Eigen::VectorXd a(1), b(1);
  a << -1.0;
  b << 2.0;
  long checks = 0;
  EXPECT_FALSE(edge_is_free(state, a, b, 0.01, 0.01, 0, checks));
  EXPECT_LE(checks, 301);  // 300 segments, stopped at the wall
  b << -0.5;
  checks = 0;
  EXPECT_TRUE(edge_is_free(state, a, b, 0.01, 0.01, 0, checks));
  EXPECT_EQ(checks, 51);  // both ends and 49 samples 0.01 rad apart
}

TEST_F(PlannerTest, PathFileRoundTrip) {
  test::TempDir dir;
  const Scene scene = Scene::load(wall_cell(dir));
  const auto [a, b] = resolve_endpoints(scene, "home", "site:patch");
  PlanOptions o;
  o.seed = 3;
  const PlanResult r = plan_path(scene, a.q, b.q, o);
  ASSERT_TRUE(r.success);
  const nlohmann::json j = path_json(scene, r, o, a, b);
  EXPECT_EQ(j["format"], "leeway-path-1");
  EXPECT_EQ(j["joints"], scene.joint_names());
  EXPECT_EQ(j["waypoints"].size(), r.waypoints.size());
  EXPECT_EQ(j["from"]["keyframe"], "home");
  EXPECT_EQ(j["to"]["site"], "patch");
  EXPECT_EQ(j["planner"]["seed"], 3);
  const std::string file = dir.write("path.json", j.dump(2));
  EXPECT_EQ(read_path(file, scene), r.waypoints);  // doubles survive the JSON text exactly
}

TEST_F(PlannerTest, ReadPathNamesTheFileAndTheMismatch) {
  test::TempDir dir;
  const Scene scene = Scene::load(workcell("dallara"));
  const std::string joints = R"("joints": ["j1", "j2", "j3", "j4", "j5", "j6"])";
  const std::string q0 = R"({"q": [0, 0, 0, 0, 0, 0]})";
  const std::pair<std::string, std::string> cases[] = {
      {"{", "malformed JSON"},
      {R"({"waypoints": []})", "not a leeway path file"},
      {R"({"format": "other", )" + joints + R"(, "waypoints": [)" + q0 + "," + q0 + "]}", "format 'other'"},
      {R"({"joints": ["rail_x", "j1", "j2", "j3", "j4", "j5", "j6"], "waypoints": [)" + q0 + "," + q0 + "]}",
       "its joints 'rail_x j1 j2 j3 j4 j5 j6' do not match the robot in"},
      {"{" + joints + R"(, "waypoints": [)" + q0 + "]}", "at least two waypoints, got 1"},
      {"{" + joints + R"(, "waypoints": [)" + q0 + R"(, {"q": [0, 0, 0]}]})",
       "waypoint 1 'q' has 3 values, the robot has 6 joints"},
      {"{" + joints + R"(, "waypoints": [)" + q0 + R"(, {"x": 1}]})", "waypoint 1 has no 'q'"},
      {"{" + joints + R"(, "waypoints": [)" + q0 + R"(, {"q": [0, null, 0, 0, 0, 0]}]})",
       "waypoint 1 joint 'j2': null is not a finite number"},
      {"{" + joints + R"(, "waypoints": [)" + q0 + R"(, {"q": [0, 0, 1e999, 0, 0, 0]}]})",
       "malformed JSON"},  // nlohmann: number overflow
      {"{" + joints + R"(, "waypoints": [)" + q0 + R"(, {"q": [0, 2.0, 0, 0, 0, 0]}]})",
       "waypoint 1 joint 'j2' = 2 rad is outside its limits"},
  };
  for (const auto& [text, expected] : cases) {
    const std::string file = dir.write("bad.json", text);
    try {
      read_path(file, scene);
      ADD_FAILURE() << "no error for " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(file + ": "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(read_path(dir.path().string() + "/missing.json", scene), InputError);
}

}  // namespace
}  // namespace leeway
