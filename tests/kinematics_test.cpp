#include "leeway/core/kinematics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "leeway/core/error.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using test::one_link_cell;
using test::workcell;

// The thesis's published joint values and gripper positions (chapter 4, sections 4.2.1-4.2.2).
struct PublishedPose {
  const char* cell;
  const char* key;
  double q[6];
  double position_mm[3];
};
const PublishedPose kPublished[] = {
    {"dallara", "patch", {-1.11219, 0.734922, 0.0866255, -3.14159, -0.749248, -1.11219}, {943, -1910, 800}},
    {"dallara", "mould", {0.251572, 0.282489, -0.107214, -3.14159, -1.39552, 0.251572}, {1817, 467, 1800}},
    {"baltico", "patch", {0.978215, 0.766918, 0.0255917, -3.14159, -0.778286, 0.978215}, {1218, 1809, 800}},
    {"baltico",
     "mould",
     {2.59301, -0.629514, -2.18935, 1.00597e-16, -1.89352, -0.548579},
     {1381, -844, 1800}},
};

Eigen::VectorXd published_q(const PublishedPose& p) { return Eigen::Map<const Eigen::VectorXd>(p.q, 6); }
Eigen::Vector3d published_position(const PublishedPose& p) {
  return Eigen::Vector3d(p.position_mm[0], p.position_mm[1], p.position_mm[2]) / 1000.0;
}

class KinematicsTest : public test::MujocoTest {};

TEST_F(KinematicsTest, PublishedPairsWithinOneMillimetre) {
  for (const auto& p : kPublished) {
    const Scene scene = Scene::load(workcell(p.cell));
    RobotState state(scene);
    const Pose pose = state.fk(published_q(p));
    const double err_mm = (pose.position - published_position(p)).norm() * 1000;
    EXPECT_LT(err_mm, 1.0) << p.cell << " " << p.key;
    // Every thesis pose has the tool pointing straight down.
    EXPECT_NEAR(pose.rotation(2, 2), -1.0, 1e-5) << p.cell << " " << p.key;
    // The cell's keyframe holds the published values.
    EXPECT_LT((scene.keyframe(p.key).q - published_q(p)).cwiseAbs().maxCoeff(), 1e-9)
        << p.cell << " " << p.key;
  }
}

TEST_F(KinematicsTest, HomePoseMatchesTheDatasheet) {
  // All zeros: flange at (320 + 1182.5 + 200, 0, 780 + 1280 + 200) mm, tool z-axis along +x.
  const Scene scene = Scene::load(workcell("dallara"));
  RobotState state(scene);
  const Pose pose = state.fk(Eigen::VectorXd::Zero(6));
  EXPECT_NEAR(pose.position.x(), 1.7025, 1e-9);
  EXPECT_NEAR(pose.position.y(), 0.0, 1e-9);
  EXPECT_NEAR(pose.position.z(), 2.26, 1e-9);
  EXPECT_NEAR(pose.rotation(0, 2), 1.0, 1e-4);
}

TEST_F(KinematicsTest, OneLinkArmAnalytic) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", one_link_cell("")));
  RobotState state(scene);
  Eigen::VectorXd q(1);
  q << 0.5;
  const Pose pose = state.fk(q);
  EXPECT_NEAR(pose.position.x(), std::cos(0.5), 1e-12);
  EXPECT_NEAR(pose.position.y(), std::sin(0.5), 1e-12);
  EXPECT_NEAR(pose.position.z(), 0.5, 1e-12);
}

TEST_F(KinematicsTest, ContactDepthAgainstAWall) {
  // At q = pi/2 the link spans y = 0 .. 1; a wall whose near face is at y = 0.95 is penetrated
  // by 0.05 m. At q = 0 the link lies along x and is clear.
  test::TempDir dir;
  const Scene scene = Scene::load(
      dir.write("cell.xml", one_link_cell(R"(<geom name="wall" type="box" size="1 0.05 1" pos="0 1 1"/>)")));
  RobotState state(scene);
  Eigen::VectorXd q(1);
  q << M_PI / 2;
  const auto contacts = state.contacts(q);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(scene.geom_label(contacts[0].link_geom), "link_box");
  EXPECT_EQ(scene.geom_label(contacts[0].obstacle_geom), "wall");
  EXPECT_NEAR(contacts[0].depth, 0.05, 1e-6);
  q << 0.0;
  EXPECT_FALSE(state.in_collision(q));
}

TEST_F(KinematicsTest, IkRecoversThePublishedPosesOnTheirBranch) {
  for (const auto& p : kPublished) {
    const Scene scene = Scene::load(workcell(p.cell));
    RobotState state(scene);
    Eigen::VectorXd seed = published_q(p);
    seed.head<3>().array() += 0.05;  // seeded near, not at, the published joints
    const IkResult r = solve_ik(state, published_position(p), seed);
    ASSERT_TRUE(r.success) << p.cell << " " << p.key;
    EXPECT_LT((state.fk(r.q).position - published_position(p)).norm() * 1000, 1.0) << p.cell << " " << p.key;
    // Same branch: the arm joints that fix the position come back to the published values.
    EXPECT_LT((r.q.head<3>() - published_q(p).head<3>()).cwiseAbs().maxCoeff(), 2e-3)
        << p.cell << " " << p.key;
    EXPECT_NEAR(state.fk(r.q).rotation(2, 2), -1.0, 1e-4);
  }
}

TEST_F(KinematicsTest, DlrKeyframesAreOurIk) {
  // The DLR keyframes are derived, not published (docs/workcells.md): tool0 at the thesis's
  // gripper position, tool down, carriage at the goal's x, elbow up, j6 = j1.
  const Scene scene = Scene::load(workcell("dlr"));
  RobotState state(scene);
  const std::pair<const char*, Eigen::Vector3d> goals[] = {{"patch", {-0.916442, 2.115, 0.800}},
                                                           {"mould", {-7.60193, 1.70258, 1.200}}};
  IkOptions opt;
  opt.locked = {true, false, false, false, false, false, false};  // rail_x
  for (const auto& [key, goal] : goals) {
    const Eigen::VectorXd q_file = scene.keyframe(key).q;
    EXPECT_NEAR(q_file[0], goal.x(), 1e-6) << key;  // carriage policy
    const Pose pose = state.fk(q_file);
    EXPECT_LT((pose.position - goal).norm() * 1000, 1.0) << key;
    EXPECT_NEAR(pose.rotation(2, 2), -1.0, 1e-5) << key;
    Eigen::VectorXd seed = q_file;
    seed.segment<3>(1).array() += 0.05;
    const IkResult r = solve_ik(state, goal, seed, opt);
    ASSERT_TRUE(r.success) << key;
    EXPECT_LT((r.q - q_file).cwiseAbs().maxCoeff(), 1e-5) << key;
  }
}

TEST_F(KinematicsTest, DefaultIkSeedIsTheFirstKeyframeOrZeroWithinTheLimits) {
  test::TempDir dir;
  const Scene keyed = Scene::load(
      dir.write("keyed.xml", one_link_cell("", R"(<key name="a" qpos="1.25"/><key name="b" qpos="2"/>)")));
  EXPECT_EQ(default_ik_seed(keyed)[0], 1.25);
  const Scene bare = Scene::load(dir.write("bare.xml", one_link_cell("")));
  EXPECT_EQ(default_ik_seed(bare)[0], 0.0);
  std::string xml = one_link_cell("");
  xml.replace(xml.find("range=\"-3 3\""), 12, "range=\"0.5 3\"");
  const Scene offset = Scene::load(dir.write("offset.xml", xml));
  EXPECT_EQ(default_ik_seed(offset)[0], 0.5);  // zero clamped into the limits
}

TEST_F(KinematicsTest, IkOneLinkAnalyticAndUnreachable) {
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", one_link_cell("")));
  RobotState state(scene);
  IkOptions opt;
  opt.tool_down = false;
  const Eigen::VectorXd seed = Eigen::VectorXd::Zero(1);
  IkResult r = solve_ik(state, {std::cos(1.0), std::sin(1.0), 0.5}, seed, opt);
  ASSERT_TRUE(r.success);
  EXPECT_NEAR(r.q[0], 1.0, 1e-5);
  // A target 3 m out on the x-axis: the tip (1 m long link) gets no closer than 2 m.
  r = solve_ik(state, {3.0, 0.0, 0.5}, seed, opt);
  EXPECT_FALSE(r.success);
  EXPECT_NEAR(r.position_error, 2.0, 1e-6);
}

TEST_F(KinematicsTest, IkIsDeterministicForASeed) {
  const Scene scene = Scene::load(workcell("dallara"));
  RobotState a(scene), b(scene);
  const Eigen::Vector3d target(1.2, -0.8, 1.0);
  IkOptions opt;
  opt.seed = 7;
  const IkResult ra = solve_ik(a, target, Eigen::VectorXd::Zero(6), opt);
  const IkResult rb = solve_ik(b, target, Eigen::VectorXd::Zero(6), opt);
  ASSERT_TRUE(ra.success);
  EXPECT_EQ(ra.q, rb.q);
}

TEST_F(KinematicsTest, RejectsBadConfigurations) {
  const Scene scene = Scene::load(workcell("dallara"));
  RobotState state(scene);
  EXPECT_THROW(state.fk(Eigen::VectorXd::Zero(5)), InputError);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(6);
  q[2] = INFINITY;
  EXPECT_THROW(state.fk(q), InputError);
  EXPECT_THROW(solve_ik(state, {std::nan(""), 0, 1}, Eigen::VectorXd::Zero(6)), InputError);
}

// Every pose array of `a` equals `b`'s bit for bit (memcmp: -0.0 and NaN patterns included).
void expect_same_poses(const mjModel& m, const mjData& a, const mjData& b, const std::string& what) {
  auto same = [&](const mjtNum* x, const mjtNum* y, int n, const char* name) {
    EXPECT_EQ(std::memcmp(x, y, sizeof(mjtNum) * static_cast<size_t>(n)), 0) << what << ": " << name;
  };
  same(a.xpos, b.xpos, 3 * m.nbody, "xpos");
  same(a.xquat, b.xquat, 4 * m.nbody, "xquat");
  same(a.xmat, b.xmat, 9 * m.nbody, "xmat");
  same(a.xipos, b.xipos, 3 * m.nbody, "xipos");
  same(a.ximat, b.ximat, 9 * m.nbody, "ximat");
  same(a.xanchor, b.xanchor, 3 * m.njnt, "xanchor");
  same(a.xaxis, b.xaxis, 3 * m.njnt, "xaxis");
  same(a.geom_xpos, b.geom_xpos, 3 * m.ngeom, "geom_xpos");
  same(a.geom_xmat, b.geom_xmat, 9 * m.ngeom, "geom_xmat");
  same(a.site_xpos, b.site_xpos, 3 * m.nsite, "site_xpos");
  same(a.site_xmat, b.site_xmat, 9 * m.nsite, "site_xmat");
}

// RobotState::set() updates only what moves; the result must be mj_kinematics's bit for bit, over
// a sequence of configurations (nothing stale from the previous one).
void expect_partial_kinematics_exact(const Scene& scene, int samples) {
  const mjModel& m = scene.model();
  RobotState state(scene);
  DataPtr full = make_data(m);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Eigen::VectorXd lo = scene.lower_limits(), hi = scene.upper_limits();
  for (int k = 0; k < samples; ++k) {
    Eigen::VectorXd q(scene.dof());
    for (int i = 0; i < scene.dof(); ++i) q[i] = lo[i] + (hi[i] - lo[i]) * unit(rng);
    state.set(q);
    scene.set_qpos(*full, q);
    mj_kinematics(&m, full.get());
    expect_same_poses(m, state.data(), *full, scene.source() + " sample " + std::to_string(k));
  }
}

TEST_F(KinematicsTest, PartialKinematicsIsMujocosOnEveryBundledCell) {
  for (const char* cell : {"dallara", "baltico", "dlr", "example", "press_shop", "rail_hall", "shelf_bay"}) {
    const Scene scene = Scene::load(workcell(cell));
    // The moving part is the robot's links, not the cell: the obstacles stay out of it.
    for (int g : scene.obstacle_geoms())
      EXPECT_EQ(std::count(scene.moving_geoms().begin(), scene.moving_geoms().end(), g), 0) << cell;
    for (int g : scene.link_geoms())
      EXPECT_EQ(std::count(scene.moving_geoms().begin(), scene.moving_geoms().end(), g), 1) << cell;
    EXPECT_EQ(std::count(scene.moving_sites().begin(), scene.moving_sites().end(), scene.tool_site()), 1)
        << cell;
    expect_partial_kinematics_exact(scene, 50);
  }
}

TEST_F(KinematicsTest, PartialKinematicsCoversSlidesOffsetAnchorsAndFixedChildren) {
  // A slide carrying a tilted body with two hinges on one body (the second off-centre), a
  // joint-less child with a geom, a site and an off-centre inertia; a static body beside the robot
  // with its own geoms and site; a mocap body. What moves is exactly the robot's subtree.
  const std::string xml = R"(<mujoco model="partial">
  <compiler angle="radian" autolimits="true"/>
  <worldbody>
    <geom name="wall" type="box" size="0.1 1 1" pos="3 0 1"/>
    <body name="shelf" pos="-2 1 0" euler="0 0 0.3">
      <geom name="board" type="box" size="0.5 0.2 0.02" pos="0 0 1"/>
      <site name="goal" pos="0 0 1.1"/>
    </body>
    <body name="marker" mocap="true" pos="0 -2 1"><geom name="m" type="sphere" size="0.1"/></body>
    <body name="carriage" pos="0 0 0.2" euler="0.1 0 0">
      <joint name="rail" type="slide" axis="1 0.2 0" range="-1 2"/>
      <geom name="cart" type="box" size="0.3 0.3 0.1"/>
      <body name="arm" pos="0.1 0.2 0.3" quat="0.9 0.1 0.3 0.2">
        <joint name="a" type="hinge" axis="0 0 1" pos="0.05 0 0" range="-3 3"/>
        <joint name="b" type="hinge" axis="0 1 1" pos="0.2 -0.1 0.3" range="-2 2"/>
        <inertial pos="0.3 0.1 0" quat="0.8 0.2 0.1 0.3" mass="2" diaginertia="0.1 0.2 0.3"/>
        <geom name="upper" type="box" size="0.4 0.05 0.05" pos="0.4 0 0" euler="0.2 0.1 0"/>
        <body name="flange" pos="0.8 0 0" euler="0 1.2 0">
          <geom name="tool" type="capsule" size="0.03 0.1" pos="0 0 0.1"/>
          <site name="tool0" pos="0 0 0.2" euler="0.3 0 0"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
)";
  test::TempDir dir;
  const Scene scene = Scene::load(dir.write("cell.xml", xml));
  const mjModel& m = scene.model();
  std::vector<std::string> bodies;
  for (int b : scene.moving_bodies()) bodies.push_back(object_name(m, mjOBJ_BODY, b));
  EXPECT_EQ(bodies, (std::vector<std::string>{"carriage", "arm", "flange"}));
  EXPECT_EQ(scene.moving_geoms().size(), 3u);  // cart, upper, tool
  EXPECT_EQ(scene.moving_sites(), std::vector<int>{mj_name2id(&m, mjOBJ_SITE, "tool0")});
  expect_partial_kinematics_exact(scene, 200);
}

// A configuration inside the Baltico patch-mould bounds of before self-collision was certified, found
// by an independent checker (its own kinematics and separating-axis test): the wrist swings the
// carried patch into the forearm, where MuJoCo's box-box function reports contacts 4.4 cm deep.
// MuJoCo 2.2.2's box-box dist is half the face penetration (src/core/check.cpp), so the exact
// separating-axis depth that leeway reports is twice that. The patch also reaches the wrist housing.
TEST_F(KinematicsTest, TheCarriedPatchHitsTheForearmWhereAnIndependentCheckerFoundIt) {
  const Scene scene = Scene::load(workcell("baltico"));
  RobotState state(scene);
  Eigen::VectorXd q(6);
  q << 2.5954, -0.4684, -1.7424, 0.0074, -2.0930, -0.7205;
  EXPECT_FALSE(state.obstacle_contact(q));
  EXPECT_GE(state.self_contact(), 0);
  EXPECT_TRUE(state.in_collision(q));
  const auto self = state.self_contacts(q);
  ASSERT_EQ(self.size(), 2u);
  EXPECT_EQ(scene.geom_label(self[0].geom1), "link_4_tube_box");
  EXPECT_EQ(scene.geom_label(self[0].geom2), "patch_box");
  EXPECT_NEAR(self[0].depth, 2 * 0.044, 0.002);
  EXPECT_EQ(scene.geom_label(self[1].geom1), "link_4_wrist_box");
  EXPECT_EQ(scene.geom_label(self[1].geom2), "patch_box");
}

}  // namespace
}  // namespace leeway
