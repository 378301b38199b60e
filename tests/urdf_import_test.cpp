// The URDF importer: the IRB 6700 written as URDF against leeway's hand-written MJCF of it, the
// boxes of each collision shape, package:// resolution, a 7-joint arm end to end, and bad URDFs
// (exit 2, one message naming file, element and value, no file written).
#include "leeway/io/urdf_import.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

#include "leeway/core/box.hpp"
#include "leeway/core/check.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/scene.hpp"
#include "stl_util.hpp"
#include "test_util.hpp"

#ifdef LEEWAY_TEST_ASAN
#include <sanitizer/lsan_interface.h>
#endif

namespace leeway {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;

const std::string kUrdfDir = std::string(LEEWAY_TEST_DATA_DIR) + "/urdf";
const std::string kIrbUrdf = kUrdfDir + "/irb6700_205_280.urdf";
const std::string kArm7Urdf = kUrdfDir + "/arm7.urdf";
const std::string kIrbPackage = "leeway_test_irb6700";

// Today's one-box-per-element import (LinkGeometry::kBox), which the tests written for it keep.
UrdfImportOptions box_options() {
  UrdfImportOptions o;
  o.link_geometry = LinkGeometry::kBox;
  return o;
}

// A path in single quotes, for the shell.
std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

// The meshes of irb6700_205_280.urdf: cuboids spanning the hand-written link_3 and link_5 boxes
// (centre +- half-size, mjcf/robots/irb6700_body.xml), link_3 as ASCII STL in metres, link_5 as
// binary STL in millimetres (integers, exact in 32-bit floats; the URDF scales them by 0.001).
// The package is the folder root/folder (by default named as the package).
void write_irb_package(const fs::path& root, const std::string& folder = kIrbPackage) {
  const fs::path meshes = root / folder / "meshes";
  fs::create_directories(meshes);
  test::write_ascii_stl((meshes / "link_3.stl").string(),
                        test::cuboid({-0.027 - 0.261, 0.032 - 0.317, 0.119 - 0.278},
                                     {-0.027 + 0.261, 0.032 + 0.317, 0.119 + 0.278}));
  test::write_binary_stl((meshes / "link_5.stl").string(), test::cuboid({-168, -100, -109}, {164, 100, 95}));
}

// Writes `fragment` as dir/robots/NAME.xml and a standalone cell dir/cells/NAME.xml around it
// (visual floor, the robot, keyframe home at zero); returns the cell's path.
std::string cell_around(const test::TempDir& dir, const std::string& name, const std::string& fragment,
                        int dof) {
  fs::create_directories(dir.path() / "robots");
  fs::create_directories(dir.path() / "cells");
  dir.write("robots/" + name + ".xml", fragment);
  std::string zeros;
  for (int i = 0; i < dof; ++i) zeros += i ? " 0" : "0";
  return dir.write(
      "cells/" + name + ".xml",
      "<mujoco model=\"" + name +
          "\"><compiler angle=\"radian\" autolimits=\"true\"/><worldbody>"
          "<geom name=\"floor\" type=\"plane\" size=\"6 6 0.1\" contype=\"0\" conaffinity=\"0\"/>"
          "<include file=\"../robots/" +
          name + ".xml\"/></worldbody><keyframe><key name=\"home\" qpos=\"" + zeros +
          "\"/></keyframe></mujoco>\n");
}

std::uint64_t env_or(const char* name, std::uint64_t fallback) {
  const char* v = std::getenv(name);
  return v ? std::strtoull(v, nullptr, 10) : fallback;
}

// World-frame axis-aligned half-extents of a geom's box.
Eigen::Vector3d world_half(const Box& b) { return b.rotation.cwiseAbs() * b.half_size; }

class UrdfImportTest : public test::MujocoTest {};

TEST_F(UrdfImportTest, Irb6700MatchesTheHandWrittenModel) {
  test::TempDir dir;
  write_irb_package(dir.path() / "pkgs");
  UrdfImportOptions options = box_options();
  options.package_paths = {(dir.path() / "pkgs").string()};
  const UrdfImport robot = import_urdf(kIrbUrdf, options);
  EXPECT_EQ(robot.robot_name, "abb_irb6700_205_280");
  EXPECT_EQ(robot.joints,
            (std::vector<std::string>{"joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6"}));
  EXPECT_EQ(robot.boxes, 10);
  EXPECT_TRUE(robot.notes.empty());
  // What each shape became is said in a comment.
  EXPECT_THAT(robot.mjcf, HasSubstr("(12 triangles, ASCII STL) as its axis-aligned bounding box"));
  EXPECT_THAT(robot.mjcf, HasSubstr("(12 triangles, binary STL, scale 0.001 0.001 0.001)"));
  EXPECT_THAT(robot.mjcf, HasSubstr("cylinder radius 0.1 m, length 0.036 m as its tight box"));
  EXPECT_THAT(robot.mjcf, HasSubstr("link 'patch' (merged through fixed joint 'gripper-patch')"));

  const Scene imported = Scene::load(cell_around(dir, "irb_urdf", robot.mjcf, 6));
  const Scene hand = Scene::load(std::string(LEEWAY_MJCF_DIR) + "/robots/irb6700.xml");
  ASSERT_EQ(imported.dof(), 6);
  for (int i = 0; i < 6; ++i) {
    const auto &a = imported.joints()[static_cast<size_t>(i)], &b = hand.joints()[static_cast<size_t>(i)];
    EXPECT_EQ(a.lower, b.lower) << a.name;
    EXPECT_EQ(a.upper, b.upper) << a.name;
    EXPECT_EQ(a.max_speed, b.max_speed) << a.name;
    EXPECT_EQ(a.prismatic, b.prismatic) << a.name;
  }
  EXPECT_EQ(imported.link_geoms().size(), hand.link_geoms().size());
  EXPECT_EQ(imported.base_geoms().size(), 1u);

  // Hand-worked values (the chain's offsets in mjcf/robots/irb6700_body.xml): home puts tool0 at (1.7025,
  // 0, 2.26) m, tool z along +x; the thesis's Dallara patch pose puts it at (943, -1910, 800) mm.
  RobotState a(imported), b(hand);
  const Pose home = a.fk(Eigen::VectorXd::Zero(6));
  EXPECT_NEAR((home.position - Eigen::Vector3d(1.7025, 0, 2.26)).norm(), 0, 1e-12);
  EXPECT_NEAR((home.rotation.col(2) - Eigen::Vector3d::UnitX()).norm(), 0, 1e-12);
  Eigen::VectorXd patch(6);
  patch << -1.11219, 0.734922, 0.0866255, -3.14159, -0.749248, -1.11219;
  EXPECT_NEAR((a.fk(patch).position - Eigen::Vector3d(0.943, -1.910, 0.800)).norm(), 0, 1e-3);

  // Random configurations within the limits: every link frame, the tool pose and every collision box
  // agree with the hand-written model to 1e-9 m.
  const std::uint64_t seed = env_or("LEEWAY_URDF_SEED", 7), count = env_or("LEEWAY_URDF_COUNT", 200);
  std::mt19937_64 rng(seed);
  const Eigen::VectorXd lo = hand.lower_limits(), hi = hand.upper_limits();
  const mjModel &ma = imported.model(), &mb = hand.model();
  for (std::uint64_t n = 0; n < count; ++n) {
    Eigen::VectorXd q(6);
    for (int i = 0; i < 6; ++i) q[i] = std::uniform_real_distribution<double>(lo[i], hi[i])(rng);
    const Pose pa = a.fk(q), pb = b.fk(q);
    SCOPED_TRACE("seed " + std::to_string(seed) + ", configuration " + std::to_string(n));
    EXPECT_LT((pa.position - pb.position).norm(), 1e-9);
    EXPECT_LT((pa.rotation - pb.rotation).norm(), 1e-9);
    for (const char* link : {"link_1", "link_2", "link_3", "link_4", "link_5", "link_6"}) {
      const int ia = mj_name2id(&ma, mjOBJ_BODY, link), ib = mj_name2id(&mb, mjOBJ_BODY, link);
      ASSERT_GE(ia, 0) << link;
      const Eigen::Map<const Eigen::Vector3d> xa(a.data().xpos + 3 * ia), xb(b.data().xpos + 3 * ib);
      EXPECT_LT((xa - xb).norm(), 1e-9) << link;
    }
    for (int gb : hand.link_geoms()) {
      const std::string name = object_name(mb, mjOBJ_GEOM, gb);
      const int ga = mj_name2id(&ma, mjOBJ_GEOM, name.c_str());
      ASSERT_GE(ga, 0) << name;
      const Box ba = geom_box(ma, a.data(), ga), bb = geom_box(mb, b.data(), gb);
      EXPECT_LT((ba.center - bb.center).norm(), 1e-9) << name;
      EXPECT_LT((world_half(ba) - world_half(bb)).norm(), 1e-9) << name;
    }
  }
}

TEST_F(UrdfImportTest, PrimitiveShapesBecomeTheirBoxes) {
  test::TempDir dir;
  const std::string urdf = dir.write("shapes.urdf", R"(<robot name="shapes">
  <link name="base_link"><collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
  <link name="link_1">
    <collision><origin xyz="0.25 0 0" rpy="1.5707963267948966 0 0"/>
      <geometry><cylinder radius="0.05" length="0.4"/></geometry></collision>
    <collision><origin xyz="0.5 0 0"/><geometry><sphere radius="0.03"/></geometry></collision>
    <collision><origin xyz="0 0 0.1" rpy="0 0 0.5"/><geometry><box size="0.2 0.1 0.05"/></geometry></collision>
  </link>
  <link name="tool0"/>
  <joint name="j1" type="prismatic"><origin xyz="0 0 1"/><parent link="base_link"/><child link="link_1"/>
    <axis xyz="0 0 2"/><limit lower="-0.5" upper="0.25" effort="1" velocity="0.75"/></joint>
  <joint name="j1-tool0" type="fixed"><origin xyz="0.5 0 0"/><parent link="link_1"/><child link="tool0"/></joint>
</robot>)");
  const UrdfImport robot = import_urdf(urdf, box_options());
  EXPECT_THAT(
      robot.mjcf,
      HasSubstr("<joint name=\"j1\" type=\"slide\" axis=\"0 0 1\" range=\"-0.5 0.25\" user=\"0.75\"/>"));
  const Scene s = Scene::load(cell_around(dir, "shapes", robot.mjcf, 1));
  RobotState state(s);
  Eigen::VectorXd q(1);
  q << 0.25;
  state.set(q);
  const mjModel& m = s.model();
  auto box_of = [&](const char* name) { return geom_box(m, state.data(), mj_name2id(&m, mjOBJ_GEOM, name)); };
  // Several unnamed elements: numbered in document order. The link frame is at (0, 0, 1.25).
  const Box cyl = box_of("link_1_box_1"), sphere = box_of("link_1_box_2"), box = box_of("link_1_box_3");
  EXPECT_LT((cyl.center - Eigen::Vector3d(0.25, 0, 1.25)).norm(), 1e-12);
  EXPECT_LT((world_half(cyl) - Eigen::Vector3d(0.05, 0.2, 0.05)).norm(), 1e-12);  // axis along y
  EXPECT_LT((sphere.center - Eigen::Vector3d(0.5, 0, 1.25)).norm(), 1e-12);
  EXPECT_LT((sphere.half_size - Eigen::Vector3d::Constant(0.03)).norm(), 1e-12);
  EXPECT_LT((box.half_size - Eigen::Vector3d(0.1, 0.05, 0.025)).norm(), 1e-12);
  EXPECT_NEAR(box.rotation(1, 0), std::sin(0.5), 1e-12);  // yawed by 0.5 rad
  EXPECT_LT((state.tool_pose().position - Eigen::Vector3d(0.5, 0, 1.25)).norm(), 1e-12);
}

TEST_F(UrdfImportTest, MeshPathsFileUriRelativeAndScaledRotated) {
  test::TempDir dir;
  fs::create_directories(dir.path() / "desc" / "meshes");
  test::write_ascii_stl((dir.path() / "desc/meshes/a.stl").string(), test::cuboid({0, 0, 0}, {1, 2, 3}));
  const std::string abs = (dir.path() / "desc/meshes/a.stl").string();
  const std::string urdf = dir.write("desc/robot.urdf", R"(<robot name="meshes">
  <link name="base_link"/>
  <link name="link_1">
    <collision><geometry><mesh filename="meshes/a.stl" scale="0.1 0.1 0.1"/></geometry></collision>
    <collision><origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/>
      <geometry><mesh filename="file://)" + abs + R"(" scale="0.5 0.5 -0.5"/></geometry></collision>
  </link>
  <link name="tool0"/>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="link_1"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="t" type="fixed"><parent link="link_1"/><child link="tool0"/></joint>
</robot>)");
  const Scene s = Scene::load(cell_around(dir, "meshes", import_urdf(urdf, box_options()).mjcf, 1));
  RobotState state(s);
  state.set(Eigen::VectorXd::Zero(1));
  const mjModel& m = s.model();
  const Box rel = geom_box(m, state.data(), mj_name2id(&m, mjOBJ_GEOM, "link_1_box_1"));
  const Box uri = geom_box(m, state.data(), mj_name2id(&m, mjOBJ_GEOM, "link_1_box_2"));
  // Relative path, scale 0.1: the cuboid [0, 0.1] x [0, 0.2] x [0, 0.3].
  EXPECT_LT((rel.center - Eigen::Vector3d(0.05, 0.1, 0.15)).norm(), 1e-12);
  EXPECT_LT((rel.half_size - Eigen::Vector3d(0.05, 0.1, 0.15)).norm(), 1e-12);
  // file:// URI, scale (0.5, 0.5, -0.5): [0, 0.5] x [0, 1] x [-1.5, 0] in the mesh frame, which is
  // turned by +90 deg about z and moved to x = 1: x in [0, 1], y in [0, 0.5], z in [-1.5, 0].
  EXPECT_LT((uri.center - Eigen::Vector3d(0.5, 0.25, -0.75)).norm(), 1e-12);
  EXPECT_LT((world_half(uri) - Eigen::Vector3d(0.5, 0.25, 0.75)).norm(), 1e-12);
}

TEST_F(UrdfImportTest, FlatMeshesAreThickenedWithANote) {
  test::TempDir dir;
  test::write_binary_stl((dir.path() / "plate.stl").string(),
                         {{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0)}});
  const std::string urdf = dir.write("plate.urdf", R"(<robot name="plate">
  <link name="base_link"/>
  <link name="link_1"><collision><geometry><mesh filename="plate.stl"/></geometry></collision></link>
  <link name="tool0"/>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="link_1"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="t" type="fixed"><parent link="link_1"/><child link="tool0"/></joint>
</robot>)");
  const UrdfImport robot = import_urdf(urdf, box_options());
  ASSERT_EQ(robot.notes.size(), 1u);
  EXPECT_THAT(robot.notes[0],
              AllOf(HasSubstr("link 'link_1' <collision> 1"), HasSubstr("half-size 0 m along box axis z"),
                    HasSubstr("thickened to 0.0005 m")));
  EXPECT_THAT(robot.mjcf, HasSubstr("pos=\"0.5 0.5 0\" size=\"0.5 0.5 0.0005\""));
}

TEST_F(UrdfImportTest, OffChainJointsAreFrozenAndNoted) {
  test::TempDir dir;
  const std::string urdf = dir.write("finger.urdf", R"(<robot name="finger">
  <link name="base_link"/>
  <link name="link_1"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="tool0"/>
  <link name="finger"><collision><geometry><box size="0.02 0.02 0.02"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="link_1"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="t" type="fixed"><origin xyz="0 0 0.1"/><parent link="link_1"/><child link="tool0"/></joint>
  <joint name="grip" type="prismatic"><parent link="tool0"/><child link="finger"/><axis xyz="1 0 0"/>
    <limit lower="0.01" upper="0.04" effort="1" velocity="1"/></joint>
</robot>)");
  const UrdfImport robot = import_urdf(urdf, box_options());
  EXPECT_EQ(robot.joints, std::vector<std::string>{"j1"});
  ASSERT_EQ(robot.notes.size(), 1u);
  EXPECT_THAT(robot.notes[0], AllOf(HasSubstr("'grip'"), HasSubstr("frozen at 0.01 m")));
  EXPECT_THAT(robot.mjcf, HasSubstr("<geom name=\"finger_box\" type=\"box\" pos=\"0.01 0 0.1\""));
}

TEST_F(UrdfImportTest, PackagesFromPathsEnvironmentAndPackageXml) {
  test::TempDir dir;
  fs::create_directories(dir.path() / "a" / "pkg_one");
  fs::create_directories(dir.path() / "b" / "src" / "checkout");
  std::ofstream(dir.path() / "b/src/checkout/package.xml")
      << "<package format=\"2\">\n  <name> pkg_two </name>\n</package>\n";
  UrdfImportOptions o;
  o.package_paths = {(dir.path() / "a").string()};
  EXPECT_EQ(resolve_urdf_resource("package://pkg_one/m/x.stl", "/u", o, "w"),
            (dir.path() / "a/pkg_one/m/x.stl").string());
  // Found through ROS_PACKAGE_PATH's second entry, by the name in package.xml two folders down.
  o.ros_package_path = "/nonexistent:" + (dir.path() / "b").string();
  EXPECT_EQ(resolve_urdf_resource("package://pkg_two/x.stl", "/u", o, "w"),
            (dir.path() / "b/src/checkout/x.stl").string());
  EXPECT_EQ(resolve_urdf_resource("file:///abs/x.stl", "/u", o, "w"), "/abs/x.stl");
  EXPECT_EQ(resolve_urdf_resource("file://rel/x.stl", "/u", o, "w"), "/u/rel/x.stl");
  EXPECT_EQ(resolve_urdf_resource("rel/x.stl", "/u", o, "w"), "/u/rel/x.stl");
  try {
    resolve_urdf_resource("package://pkg_three/x.stl", "/u", o, "link 'l' <mesh>");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(std::string(e.what()),
                AllOf(HasSubstr("link 'l' <mesh>"), HasSubstr("no ROS package 'pkg_three'"),
                      HasSubstr("/nonexistent")));
  }
  EXPECT_THROW(resolve_urdf_resource("http://example.com/x.stl", "/u", o, "w"), InputError);
}

TEST(UrdfImportCliTest, PackagePathFlagAndEnvironmentGiveTheSameRobot) {
  test::TempDir dir;
  write_irb_package(dir.path() / "flag");
  // In the environment's path the package is a folder of another name holding its package.xml.
  write_irb_package(dir.path() / "env" / "src", "abb_checkout");
  std::ofstream(dir.path() / "env/src/abb_checkout/package.xml")
      << "<package><name>" << kIrbPackage << "</name></package>\n";
  const fs::path by_flag = dir.path() / "by_flag.xml", by_env = dir.path() / "by_env.xml";
  const std::string no_env = "env -u ROS_PACKAGE_PATH " + std::string(LEEWAY_CLI);
  const auto r1 =
      test::run_program(no_env, "import-urdf " + kIrbUrdf + " --link-geometry box --out " + quoted(by_flag) +
                                    " --package-path " + quoted(dir.path() / "flag"));
  ASSERT_EQ(r1.exit_code, 0) << r1.out;
  EXPECT_THAT(
      r1.out,
      HasSubstr("6 joints (joint_1, joint_2, joint_3, joint_4, joint_5, joint_6), 10 collision boxes"));
  const auto r2 =
      test::run_program("ROS_PACKAGE_PATH=/nonexistent:" + quoted(dir.path() / "env") + " " + LEEWAY_CLI,
                        "import-urdf " + kIrbUrdf + " --link-geometry box --out " + quoted(by_env));
  ASSERT_EQ(r2.exit_code, 0) << r2.out;
  std::ifstream f1(by_flag), f2(by_env);
  const std::string t1((std::istreambuf_iterator<char>(f1)), {}),
      t2((std::istreambuf_iterator<char>(f2)), {});
  EXPECT_EQ(t1, t2);
  // Neither: the package is not found.
  const auto r3 =
      test::run_program(no_env, "import-urdf " + kIrbUrdf + " --out " + quoted(dir.path() / "none.xml"));
  EXPECT_EQ(r3.exit_code, 2);
  EXPECT_THAT(r3.out, AllOf(HasSubstr("irb6700_205_280.urdf: link 'link_3' <collision> 1 <mesh> filename "
                                      "'package://leeway_test_irb6700/meshes/link_3.stl'"),
                            HasSubstr("no ROS package 'leeway_test_irb6700'")));
  EXPECT_FALSE(fs::exists(dir.path() / "none.xml"));
}

// A valid two-joint URDF; the bad cases below edit it.
const std::string kTwoJoints = R"(<robot name="two">
  <link name="base_link"><collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
  <link name="link_1"><collision><origin xyz="0 0 0.25"/><geometry><box size="0.1 0.1 0.5"/></geometry></collision></link>
  <link name="link_2"><collision><origin xyz="0.25 0 0"/><geometry><box size="0.5 0.1 0.1"/></geometry></collision></link>
  <link name="tool0"/>
  <joint name="j1" type="revolute"><origin xyz="0 0 0.5"/><parent link="base_link"/><child link="link_1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="2"/></joint>
  <joint name="j2" type="revolute"><origin xyz="0 0 0.5"/><parent link="link_1"/><child link="link_2"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="2.5"/></joint>
  <joint name="j2-tool0" type="fixed"><origin xyz="0.5 0 0"/><parent link="link_2"/><child link="tool0"/></joint>
</robot>
)";

std::string edited(std::string text, const std::string& from, const std::string& to) {
  const size_t p = text.find(from);
  if (p == std::string::npos)
    ADD_FAILURE() << "'" << from << "' not in the URDF";
  else
    text.replace(p, from.size(), to);
  return text;
}

TEST(UrdfImportCliTest, BadUrdfsExitTwoWithOneMessageAndNoFile) {
  test::TempDir dir;
  fs::create_directories(dir.path() / "meshes");
  std::ofstream(dir.path() / "meshes/link_2.dae") << "<COLLADA/>\n";
  std::ofstream(dir.path() / "meshes/text.stl") << "this is no mesh\n";
  const std::string box2 = R"(<box size="0.5 0.1 0.1"/>)";
  struct Case {
    std::string name, urdf, flags;
    std::vector<std::string> fragments;
  };
  const std::vector<Case> cases = {
      {"parent",
       edited(kTwoJoints, R"(<parent link="link_1"/>)", R"(<parent link="link_9"/>)"),
       "",
       {"not a valid URDF", "parent link [link_9] of joint [j2] not found"}},
      {"loop",
       edited(
           kTwoJoints, "</robot>",
           R"(<joint name="back" type="fixed"><parent link="link_2"/><child link="link_1"/></joint></robot>)"),
       "",
       {"link 'link_1' is the child of joints 'back', 'j1'", "joint loop"}},
      {"cycle",
       edited(
           kTwoJoints, "</robot>",
           R"(<link name="ring_a"/><link name="ring_b"><collision><geometry><sphere radius="1"/></geometry>)"
           R"(</collision></link><joint name="r1" type="fixed"><parent link="ring_a"/><child link="ring_b"/></joint>)"
           R"(<joint name="r2" type="fixed"><parent link="ring_b"/><child link="ring_a"/></joint></robot>)"),
       "--tool ring_b",
       {"joint loop above the tool link 'ring_b'"}},
      {"missing",
       edited(kTwoJoints, box2, R"(<mesh filename="meshes/absent.stl"/>)"),
       "",
       {"link 'link_2' <collision> 1 <mesh> filename 'meshes/absent.stl'",
        "/meshes/absent.stl' does not exist"}},
      {"collada",
       edited(kTwoJoints, box2, R"(<mesh filename="meshes/link_2.dae"/>)"),
       "",
       {"link 'link_2' <collision> 1 <mesh> filename 'meshes/link_2.dae'", "not an STL file ('.dae')"}},
      {"text",
       edited(kTwoJoints, box2, R"(<mesh filename="meshes/text.stl"/>)"),
       "",
       {"link 'link_2' <collision> 1 <mesh> filename 'meshes/text.stl'", "text.stl: not an STL file"}},
      {"nan",
       edited(kTwoJoints, R"(<origin xyz="0.25 0 0"/>)", R"(<origin xyz="0.25 nan 0"/>)"),
       "",
       {"not a valid URDF", "[nan]", "collision element for Link [link_2]"}},
      {"nanjoint",
       edited(kTwoJoints, R"(<origin xyz="0 0 0.5"/><parent link="link_1"/>)",
              R"(<origin xyz="0 0 0.5" rpy="0 nan 0"/><parent link="link_1"/>)"),
       "",
       {"[nan]", "origin element for joint [j2]"}},
      {"notool",
       edited(edited(kTwoJoints, R"(<link name="tool0"/>)", R"(<link name="flange"/>)"),
              R"(<child link="tool0"/>)", R"(<child link="flange"/>)"),
       "",
       {"no tool link: the URDF has no link 'tool0'", "'flange'", "(see --tool LINK)"}},
      {"unknowntool", kTwoJoints, "--tool hand", {"no link 'hand'", "(see --tool LINK)"}},
      {"unknownbase",
       kTwoJoints,
       "--base-link socket",
       {"no link 'socket' for the base", "(see --base-link LINK)"}},
      {"continuous",
       edited(kTwoJoints, R"(name="j2" type="revolute")", R"(name="j2" type="continuous")"),
       "",
       {"joint 'j2' is continuous", "-2 pi .. 2 pi rad", "(see --continuous-full-turn)"}},
      {"emptyrange",
       edited(kTwoJoints, R"(lower="-2" upper="2")", R"(lower="2" upper="1")"),
       "",
       {"joint 'j2' <limit> lower '2' upper '1'", "not a finite, non-empty range"}},
      {"malformed", "<robot name=\"x\"><link name=\"a\">", "", {"not a valid URDF"}},
      {"nocollision",
       edited(
           edited(
               kTwoJoints,
               R"(<link name="link_1"><collision><origin xyz="0 0 0.25"/><geometry><box size="0.1 0.1 0.5"/></geometry></collision></link>)",
               R"(<link name="link_1"/>)"),
           R"(<link name="link_2"><collision><origin xyz="0.25 0 0"/><geometry><box size="0.5 0.1 0.1"/></geometry></collision></link>)",
           R"(<link name="link_2"/>)"),
       "",
       {"no <collision> element on the links that move"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string urdf = dir.write(c.name + ".urdf", c.urdf);
    const fs::path out = dir.path() / (c.name + ".xml");
    const auto r = test::run_cli("import-urdf " + urdf + " --out " + quoted(out) + " " + c.flags);
    EXPECT_EQ(r.exit_code, 2) << r.out;
    EXPECT_THAT(r.out, HasSubstr("leeway: error: " + urdf + ": "));
    for (const auto& f : c.fragments) EXPECT_THAT(r.out, HasSubstr(f));
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
    EXPECT_FALSE(fs::exists(out));
  }
  // Nothing but the inputs is left in the folder (no temporary files).
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) files += e.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, static_cast<int>(cases.size()));
  const auto absent = test::run_cli("import-urdf " + (dir.path() / "absent.urdf").string() + " --out " +
                                    quoted(dir.path() / "x.xml"));
  EXPECT_EQ(absent.exit_code, 2);
  EXPECT_THAT(absent.out, HasSubstr("absent.urdf: cannot open the URDF file"));
}

TEST(UrdfImportCliTest, ContinuousJointsOnRequest) {
  test::TempDir dir;
  const std::string urdf = dir.write(
      "c.urdf", edited(kTwoJoints, R"(name="j2" type="revolute")", R"(name="j2" type="continuous")"));
  const fs::path out = dir.path() / "c.xml";
  const auto r = test::run_cli("import-urdf " + urdf + " --out " + quoted(out) + " --continuous-full-turn");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::ifstream in(out);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  const Scene s = Scene::load(cell_around(dir, "c", text, 2));
  EXPECT_EQ(s.joints()[1].lower, -2 * M_PI);
  EXPECT_EQ(s.joints()[1].upper, 2 * M_PI);
  EXPECT_EQ(s.joints()[1].max_speed, 2.5);
}

TEST(UrdfImportCliTest, SevenJointArmEndToEnd) {
  test::TempDir dir;
  fs::create_directories(dir.path() / "robots");
  fs::create_directories(dir.path() / "cells");
  const fs::path robot = dir.path() / "robots/arm7.xml", cell = dir.path() / "cells/arm7.xml";
  const auto imp = test::run_cli("import-urdf " + kArm7Urdf + " --link-geometry box --out " + quoted(robot));
  ASSERT_EQ(imp.exit_code, 0) << imp.out;
  EXPECT_THAT(imp.out, HasSubstr("7 joints (a1, a2, a3, a4, a5, a6, a7), 8 collision boxes"));
  EXPECT_THAT(imp.out,
              HasSubstr("note: the root link 'world' and its fixed joint 'world-base' are left out"));
  // The boxes of the upper arm and the forearm meet face to face at the elbow (a3 and a4 share their
  // origin), those of the forearm and link_6 at the wrist: both pairs are excluded, and said so.
  EXPECT_THAT(imp.out, HasSubstr("wrote " + (dir.path() / "robots/arm7_excludes.xml").string() +
                                 ": 2 box pair(s) excluded from self-collision, 19 checked"));
  EXPECT_THAT(imp.out, HasSubstr("excluded: 'link_2_box' and 'link_4_box': the boxes touch (within 1e-06 m) "
                                 "at the reference configuration"));
  EXPECT_THAT(imp.out, HasSubstr("excluded: 'link_4_box' and 'link_6_box': the boxes touch"));
  const auto nc = test::run_cli("new-cell --robot " + quoted(robot) + " --out " + quoted(cell));
  ASSERT_EQ(nc.exit_code, 0) << nc.out;
  EXPECT_THAT(nc.out, HasSubstr("includes ../robots/arm7.xml and ../robots/arm7_excludes.xml, 7 joints, "
                                "keyframe home = [0 0 0 0 0 0 0]"));
  ASSERT_EQ(test::run_cli("check " + quoted(cell)).exit_code, 0);

  // Obstacles and a second keyframe, as a user would add them: a table in front of the arm and a
  // pose leaning over it: the y-axis joints a2, a4, a6 at 0.6, 1.0, 1.0 rad put tool0 at
  // (0.4 sin 0.6 + 0.4 sin 1.6 + 0.25 sin 2.6, 0, 0.5 + 0.4 cos 0.6 + 0.4 cos 1.6 + 0.25 cos 2.6)
  // = (0.755, 0, 0.604) m, 0.1 m above the table top.
  std::ifstream in(cell);
  std::string xml((std::istreambuf_iterator<char>(in)), {});
  xml = edited(
      xml, "  </worldbody>",
      "    <geom name=\"table\" type=\"box\" pos=\"0.8 0 0.25\" size=\"0.3 0.4 0.25\" contype=\"0\" "
      "conaffinity=\"1\"/>\n    <geom name=\"post\" type=\"box\" pos=\"-0.6 0.4 0.6\" size=\"0.1 0.1 0.6\" "
      "contype=\"0\" conaffinity=\"1\"/>\n  </worldbody>");
  xml = edited(xml, "  </keyframe>", "    <key name=\"lean\" qpos=\"0 0.6 0 1.0 0 1.0 0\"/>\n  </keyframe>");
  std::ofstream(cell) << xml;
  const auto check = test::run_cli("check --json " + quoted(cell));
  ASSERT_EQ(check.exit_code, 0) << check.out;
  const auto report = nlohmann::json::parse(check.out);
  EXPECT_EQ(report.at("robot").at("joints").size(), 7u);
  const auto tool = report.at("keyframes").at(1).at("tool_position");
  EXPECT_NEAR(tool.at(0).get<double>(), 0.754562, 1e-6);
  EXPECT_NEAR(tool.at(2).get<double>(), 0.604232, 1e-6);

  const fs::path bounds = dir.path() / "b.json";
  const auto b = test::run_cli("bounds " + quoted(cell) +
                               " --from home --to lean --waypoints 3 --threads 1 --out " + quoted(bounds));
  ASSERT_EQ(b.exit_code, 0) << b.out;
  const auto file = test::read_json(bounds);
  EXPECT_EQ(file.at("joint_bounding"),
            nlohmann::json({"bisected", "bisected", "bisected", "fixed", "fixed", "fixed", "fixed"}));
  ASSERT_EQ(file.at("waypoints").size(), 3u);
  for (const auto& w : file.at("waypoints")) EXPECT_EQ(w.at("lower").size(), 7u);
  const auto cf =
      test::run_cli("cf " + quoted(cell) + " " + quoted(bounds) + " --samples 2000 --threads 1 --json");
  ASSERT_EQ(cf.exit_code, 0) << cf.out;
  EXPECT_EQ(nlohmann::json::parse(cf.out).at("cf").get<double>(),
            1.0);  // certified bounds: no sample collides

  // The elbow a4 bisected instead of the upper-arm roll a3 (docs/robots.md), the roll kept tight.
  const fs::path elbow = dir.path() / "elbow.json";
  const auto e =
      test::run_cli("bounds " + quoted(cell) +
                    " --from home --to lean --waypoints 3 --threads 1 --bisect a1,a2,a4 --half-width "
                    "a3=0.1 --out " +
                    quoted(elbow));
  ASSERT_EQ(e.exit_code, 0) << e.out;
  const auto elbow_file = test::read_json(elbow);
  EXPECT_EQ(elbow_file.at("joint_bounding"),
            nlohmann::json({"bisected", "bisected", "fixed", "bisected", "fixed", "fixed", "fixed"}));
  for (const auto& w : elbow_file.at("waypoints"))
    EXPECT_LE(w.at("upper")[2].get<double>(), w.at("q")[2].get<double>() + 0.1);
  const auto elbow_cf =
      test::run_cli("cf " + quoted(cell) + " " + quoted(elbow) + " --samples 2000 --threads 1 --json");
  ASSERT_EQ(elbow_cf.exit_code, 0) << elbow_cf.out;
  EXPECT_EQ(nlohmann::json::parse(elbow_cf.out).at("cf").get<double>(), 1.0);
}

TEST(UrdfImportCliTest, FourJointArmPlansAndBounds) {
  // arm7.urdf with a5, a6 and a7 fixed: four joints, three of them the bisected hinges.
  test::TempDir dir;
  std::ifstream in(kArm7Urdf);
  std::string urdf((std::istreambuf_iterator<char>(in)), {});
  for (const char* j : {"a5", "a6", "a7"})
    urdf = edited(urdf, std::string("name=\"") + j + "\" type=\"revolute\"",
                  std::string("name=\"") + j + "\" type=\"fixed\"");
  const std::string source = dir.write("arm4.urdf", urdf);
  const fs::path robot = dir.path() / "arm4.xml", cell = dir.path() / "cell.xml",
                 path = dir.path() / "p.json", bounds = dir.path() / "b.json";
  const auto imp = test::run_cli("import-urdf " + source + " --link-geometry box --out " + quoted(robot));
  ASSERT_EQ(imp.exit_code, 0) << imp.out;
  EXPECT_THAT(imp.out, HasSubstr("4 joints (a1, a2, a3, a4)"));
  ASSERT_EQ(test::run_cli("new-cell --robot " + quoted(robot) + " --out " + quoted(cell)).exit_code, 0);
  std::ifstream cin(cell);
  std::string xml((std::istreambuf_iterator<char>(cin)), {});
  xml = edited(xml, "  </worldbody>",
               "    <geom name=\"table\" type=\"box\" pos=\"0.8 0 0.25\" size=\"0.3 0.4 0.25\" contype=\"0\" "
               "conaffinity=\"1\"/>\n  </worldbody>");
  xml = edited(xml, "  </keyframe>", "    <key name=\"over\" qpos=\"0.3 0.6 0 1.2\"/>\n  </keyframe>");
  std::ofstream(cell) << xml;
  const auto check = test::run_cli("check " + quoted(cell));
  ASSERT_EQ(check.exit_code, 0) << check.out;
  const auto ik = test::run_cli("ik " + quoted(cell) + " --xyz 0.8 0.2 0.65 --free-orientation --json");
  ASSERT_EQ(ik.exit_code, 0) << ik.out;
  const auto plan = test::run_cli("plan " + quoted(cell) + " --from home --to over --out " + quoted(path));
  ASSERT_EQ(plan.exit_code, 0) << plan.out;
  const auto b = test::run_cli("bounds " + quoted(cell) + " --path " + quoted(path) + " --threads 1 --out " +
                               quoted(bounds));
  ASSERT_EQ(b.exit_code, 0) << b.out;
  EXPECT_EQ(test::read_json(bounds).at("joint_bounding"),
            nlohmann::json({"bisected", "bisected", "bisected", "fixed"}));
  const auto cf =
      test::run_cli("cf " + quoted(cell) + " " + quoted(bounds) + " --samples 2000 --threads 1 --json");
  ASSERT_EQ(cf.exit_code, 0) << cf.out;
  EXPECT_EQ(nlohmann::json::parse(cf.out).at("cf").get<double>(), 1.0);
}

// Three joints whose reference configuration (j1 at its lower limit 0.5 rad, j2 and j3 at 0) has
// link_3's box, which reaches back from the elbow over the column, 0.05 m deep in link_1's box.
const std::string kOverlapping = R"(<robot name="overlap">
  <link name="base_link"><collision><origin xyz="0 0 0.1"/><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
  <link name="link_1"><collision><origin xyz="0 0 0.25"/><geometry><box size="0.1 0.1 0.5"/></geometry></collision></link>
  <link name="link_2"><collision><origin xyz="0.1 0 0"/><geometry><box size="0.2 0.1 0.1"/></geometry></collision></link>
  <link name="link_3"><collision><origin xyz="-0.1 0 0"/><geometry><box size="0.3 0.1 0.1"/></geometry></collision></link>
  <link name="tool0"/>
  <joint name="j1" type="revolute"><origin xyz="0 0 0.2"/><parent link="base_link"/><child link="link_1"/>
    <axis xyz="0 0 1"/><limit lower="0.5" upper="3" effort="1" velocity="2"/></joint>
  <joint name="j2" type="revolute"><origin xyz="0 0 0.5"/><parent link="link_1"/><child link="link_2"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="2"/></joint>
  <joint name="j3" type="revolute"><origin xyz="0.2 0 0"/><parent link="link_2"/><child link="link_3"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="2"/></joint>
  <joint name="j3-tool0" type="fixed"><origin xyz="0.05 0 0"/><parent link="link_3"/><child link="tool0"/></joint>
</robot>
)";

// `fragment` and `excludes` as dir/robots/NAME.xml and NAME_excludes.xml, and a cell dir/cells/NAME.xml
// including both (the excludes at the top level), with keyframe home at the reference configuration;
// returns the cell.
std::string cell_with_excludes(const test::TempDir& dir, const std::string& name, const UrdfImport& robot) {
  fs::create_directories(dir.path() / "robots");
  fs::create_directories(dir.path() / "cells");
  dir.write("robots/" + name + ".xml", robot.mjcf);
  dir.write("robots/" + name + "_excludes.xml", robot.excludes_mjcf);
  const std::string robots = "../robots/" + name;
  std::string xml = "<mujoco model=\"" + name + "\"><compiler angle=\"radian\" autolimits=\"true\"/>";
  xml += "<include file=\"" + robots + "_excludes.xml\"/>";
  xml += "<worldbody><include file=\"" + robots + ".xml\"/></worldbody>";
  xml += "<keyframe><key name=\"home\" qpos=\"" + robot.reference + "\"/></keyframe></mujoco>\n";
  return dir.write("cells/" + name + ".xml", xml);
}

TEST_F(UrdfImportTest, ExcludesTheBoxesThatOverlapAtTheReferenceConfiguration) {
  test::TempDir dir;
  const UrdfImport robot = import_urdf(dir.write("overlap.urdf", kOverlapping), box_options());
  EXPECT_EQ(robot.reference, "0.5 0 0");
  // Four boxes on a chain of four parts: 6 pairs, 3 of them parent and child; 1 excluded.
  ASSERT_EQ(robot.excludes.size(), 1u);
  const UrdfExclude& e = robot.excludes[0];
  EXPECT_EQ(e.geom1, "link_1_box");
  EXPECT_EQ(e.geom2, "link_3_box");
  EXPECT_NEAR(e.depth, 0.05, 1e-9);
  EXPECT_THAT(e.reason, AllOf(HasSubstr("the boxes overlap by 0.05 m at the reference configuration"),
                              HasSubstr("an artefact of the box approximation; check it")));
  EXPECT_EQ(robot.self_pairs, 2);
  EXPECT_THAT(
      robot.excludes_mjcf,
      AllOf(HasSubstr("<!-- link_1_box and link_3_box: the boxes overlap by 0.05 m"),
            HasSubstr("<text name=\"leeway_exclude_link_1_box_link_3_box\" data=\"link_1_box link_3_box\"/>"),
            HasSubstr("at the top level of the cell")));
  // Included at a cell's top level, the exclude is leeway's: the reference configuration passes.
  const Scene s = Scene::load(cell_with_excludes(dir, "overlap", robot));
  EXPECT_EQ(s.self_pairs().size(), 2u);
  ASSERT_EQ(s.excluded_pairs().size(), 1u);
  EXPECT_FALSE(s.excluded_pairs()[0].by_body);
  EXPECT_EQ(s.geom_label(s.excluded_pairs()[0].geom1), "link_1_box");
  EXPECT_TRUE(check_scene(s).ok());

  // Nothing to exclude: the fragment still compiles as an include (MuJoCo refuses an empty one).
  const UrdfImport clean = import_urdf(dir.write("two.urdf", kTwoJoints), box_options());
  EXPECT_TRUE(clean.excludes.empty());
  EXPECT_THAT(clean.excludes_mjcf, HasSubstr("Nothing excluded"));
  EXPECT_EQ(Scene::load(cell_with_excludes(dir, "two", clean)).excluded_pairs().size(), 0u);
}

TEST_F(UrdfImportTest, SrdfDisabledPairsAreExcludedWithTheirReason) {
  test::TempDir dir;
  const std::string urdf = dir.write("overlap.urdf", kOverlapping);
  UrdfImportOptions options = box_options();
  options.srdf = dir.write("overlap.srdf", R"(<?xml version="1.0"?>
<robot name="overlap">
  <group name="arm"><chain base_link="base_link" tip_link="tool0"/></group>
  <disable_collisions link1="base_link" link2="link_1" reason="Adjacent"/>
  <disable_collisions link1="base_link" link2="link_2" reason="Never"/>
  <disable_collisions link1="link_3" link2="link_1" reason="Never"/>
</robot>
)");
  const UrdfImport robot = import_urdf(urdf, options);
  ASSERT_EQ(robot.excludes.size(), 2u);
  EXPECT_EQ(robot.excludes[0].geom1, "base_link_box");
  EXPECT_EQ(robot.excludes[0].geom2, "link_2_box");
  EXPECT_EQ(robot.excludes[0].depth, 0);
  EXPECT_EQ(
      robot.excludes[0].reason,
      "the SRDF 'overlap.srdf' disables collisions between links 'base_link' and 'link_2' (reason 'Never')");
  // Overlapping and disabled: both reasons.
  EXPECT_EQ(robot.excludes[1].geom1, "link_1_box");
  EXPECT_THAT(robot.excludes[1].reason,
              AllOf(HasSubstr("the boxes overlap by 0.05 m"),
                    HasSubstr("; and the SRDF 'overlap.srdf' disables collisions between links 'link_3' and "
                              "'link_1' (reason 'Never')")));
  EXPECT_EQ(robot.self_pairs, 1);
  ASSERT_EQ(robot.notes.size(), 1u);
  EXPECT_EQ(robot.notes[0],
            "the SRDF 'overlap.srdf' disables 3 link pair(s); 1 of them have no box pair leeway checks "
            "(one rigid part, parent and child, or no boxes)");

  // An SRDF naming a link the URDF lacks, a malformed one and a missing one are refused.
  const std::pair<std::string, std::string> bad[] = {
      {"<robot><disable_collisions link1=\"link_1\" link2=\"hand\" reason=\"Never\"/></robot>",
       "<disable_collisions> on line 1 names link 'hand', which the URDF '" + urdf + "' does not have"},
      {"<robot><disable_collisions link1=\"link_1\"/></robot>", "needs both link1 and link2"},
      {"<robot><disable_collisions", "not a valid SRDF"},
      {"<srdf/>", "not a valid SRDF: the root element is not <robot>"},
  };
  for (const auto& [text, message] : bad) {
    options.srdf = dir.write("bad.srdf", text);
    try {
      import_urdf(urdf, options);
      ADD_FAILURE() << text;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), AllOf(HasSubstr(options.srdf + ": "), HasSubstr(message)));
    }
  }
  options.srdf = (dir.path() / "absent.srdf").string();
  EXPECT_THROW(import_urdf(urdf, options), InputError);
}

TEST(UrdfImportCliTest, ImportAndNewCellWriteAndPrintTheExcludes) {
  test::TempDir dir;
  const std::string urdf = dir.write("overlap.urdf", kOverlapping);
  const std::string srdf = dir.write(
      "overlap.srdf",
      R"(<robot name="overlap"><disable_collisions link1="base_link" link2="link_2" reason="Never"/></robot>)");
  fs::create_directories(dir.path() / "robots");
  fs::create_directories(dir.path() / "cells");
  const fs::path robot = dir.path() / "robots/overlap.xml", cell = dir.path() / "cells/overlap.xml";
  const auto imp = test::run_cli("import-urdf " + urdf + " --link-geometry box --out " + quoted(robot) +
                                 " --srdf " + srdf);
  ASSERT_EQ(imp.exit_code, 0) << imp.out;
  EXPECT_THAT(imp.out,
              AllOf(HasSubstr("wrote " + (dir.path() / "robots/overlap_excludes.xml").string() +
                              ": 2 box pair(s) excluded from self-collision, 1 checked"),
                    HasSubstr("excluded: 'base_link_box' and 'link_2_box': the SRDF 'overlap.srdf' disables"),
                    HasSubstr("excluded: 'link_1_box' and 'link_3_box': the boxes overlap by 0.05 m")));
  const auto nc = test::run_cli("new-cell --robot " + quoted(robot) + " --out " + quoted(cell));
  ASSERT_EQ(nc.exit_code, 0) << nc.out;
  EXPECT_THAT(nc.out,
              AllOf(HasSubstr("includes ../robots/overlap.xml and ../robots/overlap_excludes.xml, 3 joints, "
                              "keyframe home = [0.5 0 0]"),
                    HasSubstr("self-collision: 1 robot geom pairs checked, 2 excluded (2 by "
                              "../robots/overlap_excludes.xml, 0 in the cell)")));
  const auto check = test::run_cli("check --json " + quoted(cell));
  ASSERT_EQ(check.exit_code, 0) << check.out;
  EXPECT_EQ(nlohmann::json::parse(check.out).at("robot").at("excluded_pairs").size(), 2u);
}

// The bundled robot mjcf/robots/wide_elbow.xml (and its excludes) is what import-urdf writes from
// tests/data/urdf/wide_elbow.urdf; its cell passes the check (workcells_test.cpp).
TEST_F(UrdfImportTest, TheBundledWideElbowRobotIsTheImportOfItsUrdf) {
  const UrdfImport robot = import_urdf(kUrdfDir + "/wide_elbow.urdf", box_options());
  auto read = [](const std::string& path) {
    std::ifstream in(path);
    return std::string((std::istreambuf_iterator<char>(in)), {});
  };
  EXPECT_EQ(robot.mjcf, read(std::string(LEEWAY_MJCF_DIR) + "/robots/wide_elbow.xml"));
  EXPECT_EQ(robot.excludes_mjcf, read(std::string(LEEWAY_MJCF_DIR) + "/robots/wide_elbow_excludes.xml"));
  EXPECT_EQ(robot.joints.size(), 6u);
  EXPECT_EQ(robot.boxes, 9);
  // 9 boxes on 7 parts (the forearm's two, link_6's flange and gripper): 36 pairs, 2 within one
  // part and 9 parent and child; none touches at zero.
  EXPECT_TRUE(robot.excludes.empty());
  EXPECT_EQ(robot.self_pairs, 25);
  const Scene s = Scene::load(test::workcell("wide_elbow"));
  EXPECT_DOUBLE_EQ(s.joints()[2].lower, -3.14);
  EXPECT_DOUBLE_EQ(s.joints()[2].upper, 4.61);
}

// A joint loop is refused, and the refused model does not leak: urdfdom's links own their children
// (shared_ptr), so the loop was a cycle of owners that outlived the import (found by
// fuzz/fuzz_urdf.cpp; fuzz/regressions/urdf/joint_loop_leak.urdf). Needs LeakSanitizer
// (LEEWAY_SANITIZE=address).
// ---- mesh geoms (LinkGeometry::kMesh, the default) ----

// The triangles of the cuboid [lo, hi] turned about z by `yaw` [rad] and moved by `shift`.
std::vector<test::Triangle> turned_cuboid(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double yaw,
                                          const Eigen::Vector3d& shift = Eigen::Vector3d::Zero()) {
  const Eigen::Matrix3d r = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::vector<test::Triangle> out = test::cuboid(lo, hi);
  for (auto& t : out)
    for (auto& v : t) v = r * v + shift;
  return out;
}

// Writes an import as import-urdf does (fragment, excludes fragment, mesh copies) into dir/robots
// and a cell dir/cells/NAME.xml around it with <compiler meshdir="../robots">; returns the cell.
std::string cell_with_meshes(const test::TempDir& dir, const std::string& name, const UrdfImport& robot) {
  const std::string cell = cell_with_excludes(dir, name, robot);
  for (const UrdfMeshFile& m : robot.meshes) {
    fs::create_directories((dir.path() / "robots" / m.file).parent_path());
    std::ofstream(dir.path() / "robots" / m.file, std::ios::binary) << m.bytes;
  }
  std::ifstream in(cell);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  text.replace(text.find("autolimits=\"true\""), 17, "autolimits=\"true\" meshdir=\"../robots\"");
  return dir.write("cells/" + name + ".xml", text);
}

// One hinge; link_1's collision is an ASCII STL cuboid (8 corners), placed with an origin and scaled.
const std::string kOneMeshLink = R"(<robot name="one_mesh">
  <link name="base_link"/>
  <link name="link_1"><collision><origin xyz="0.1 0.2 0.3" rpy="0.3 -0.2 0.5"/>
    <geometry><mesh filename="part.stl" scale="2 1 0.5"/></geometry></collision></link>
  <link name="tool0"/>
  <joint name="j1" type="revolute"><origin xyz="0 0 0.4"/><parent link="base_link"/><child link="link_1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="2"/></joint>
  <joint name="j1-tool0" type="fixed"><origin xyz="0.5 0 0"/><parent link="link_1"/><child link="tool0"/></joint>
</robot>
)";

TEST_F(UrdfImportTest, MeshGeomHullIsTheStlsVerticesScaledWhereTheUrdfPutsThem) {
  test::TempDir dir;
  const Eigen::Vector3d lo(-0.1, 0.02, 0.0), hi(0.15, 0.12, 0.4);
  test::write_ascii_stl((dir.path() / "part.stl").string(), test::cuboid(lo, hi));
  const UrdfImport robot = import_urdf(dir.write("one_mesh.urdf", kOneMeshLink));
  EXPECT_EQ(robot.boxes, 1);
  ASSERT_EQ(robot.meshes.size(), 1u);
  EXPECT_EQ(robot.meshes[0].file, "meshes/link_1_mesh.stl");
  EXPECT_EQ(robot.meshes[0].bytes.size(), 84u + 50u * 12u);  // binary STL, 12 triangles
  EXPECT_THAT(robot.mjcf, AllOf(HasSubstr("<geom name=\"link_1_mesh\" type=\"mesh\" mesh=\"link_1_mesh\""),
                                HasSubstr("as a mesh geom on its binary STL copy")));
  EXPECT_THAT(robot.excludes_mjcf,
              HasSubstr("<mesh name=\"link_1_mesh\" file=\"meshes/link_1_mesh.stl\" scale=\"2 1 0.5\"/>"));

  const Scene s = Scene::load(cell_with_meshes(dir, "one_mesh", robot));
  const mjModel& m = s.model();
  const int g = mj_name2id(&m, mjOBJ_GEOM, "link_1_mesh");
  ASSERT_GE(g, 0);
  ASSERT_EQ(m.geom_type[g], mjGEOM_MESH);
  const int mesh = m.geom_dataid[g];
  ASSERT_EQ(m.mesh_vertnum[mesh], 8);
  // At j1 = 0.7 rad, each compiled vertex in the world is a corner of the scaled cuboid placed by
  // the joint, the collision origin and the scale (MuJoCo's re-centring undone by the geom's pose).
  RobotState state(s);
  Eigen::VectorXd q(1);
  q << 0.7;
  state.set(q);
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
  origin.translation() << 0.1, 0.2, 0.3;
  origin.linear() =
      (Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  Eigen::Isometry3d body = Eigen::Isometry3d::Identity();
  body.translation() << 0, 0, 0.4;
  body.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d scale(2, 1, 0.5);
  const Eigen::Map<const Eigen::Vector3d> xpos(state.data().geom_xpos + 3 * g);
  const Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>> xmat(state.data().geom_xmat + 9 * g);
  std::vector<Eigen::Vector3d> compiled;
  for (int v = 0; v < 8; ++v) {
    const float* p = m.mesh_vert + 3 * (m.mesh_vertadr[mesh] + v);
    compiled.push_back(xpos + xmat * Eigen::Vector3d(p[0], p[1], p[2]));
  }
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d corner(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
    const Eigen::Vector3d expected = body * origin * Eigen::Vector3d(corner.cwiseProduct(scale));
    double nearest = 1e9;
    for (const auto& c : compiled) nearest = std::min(nearest, (c - expected).norm());
    EXPECT_LT(nearest, 1e-6) << "corner " << i;
  }
}

// Three hinges about one axis with coincident frames: link_1 and link_3 each carry a thin rod
// running diagonally (45 degrees) in the xy-plane, link_3's 0.3 m further along x: the rods are
// 0.3 / sqrt(2) = 0.21 m apart, but their boxes in the mesh frames overlap.
const std::string kDiagonalRods = R"(<robot name="rods">
  <link name="base_link"/>
  <link name="link_1"><collision><geometry><mesh filename="rod_a.stl"/></geometry></collision></link>
  <link name="link_2"/>
  <link name="link_3"><collision><geometry><mesh filename="rod_b.stl"/></geometry></collision></link>
  <link name="tool0"/>
  <joint name="j1" type="revolute"><origin xyz="0 0 0.1"/><parent link="base_link"/><child link="link_1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="2"/></joint>
  <joint name="j2" type="revolute"><parent link="link_1"/><child link="link_2"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="2"/></joint>
  <joint name="j3" type="revolute"><parent link="link_2"/><child link="link_3"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="2"/></joint>
  <joint name="j3-tool0" type="fixed"><origin xyz="0.5 0 0"/><parent link="link_3"/><child link="tool0"/></joint>
</robot>
)";

TEST_F(UrdfImportTest, MeshGeomsApartAreNotExcludedWhereTheirBoxesOverlap) {
  test::TempDir dir;
  const double yaw = 0.7853981633974483;
  test::write_binary_stl((dir.path() / "rod_a.stl").string(),
                         turned_cuboid({0, -0.01, -0.01}, {1, 0.01, 0.01}, yaw));
  test::write_binary_stl((dir.path() / "rod_b.stl").string(),
                         turned_cuboid({0, -0.01, -0.01}, {1, 0.01, 0.01}, yaw, {0.3, 0, 0}));
  const std::string urdf = dir.write("rods.urdf", kDiagonalRods);
  const UrdfImport boxes = import_urdf(urdf, box_options());
  ASSERT_EQ(boxes.excludes.size(), 1u);
  EXPECT_EQ(boxes.excludes[0].geom1, "link_1_box");
  EXPECT_EQ(boxes.excludes[0].geom2, "link_3_box");
  EXPECT_TRUE(boxes.meshes.empty());

  const UrdfImport meshes = import_urdf(urdf);
  EXPECT_TRUE(meshes.excludes.empty());
  EXPECT_EQ(meshes.self_pairs, 1);
  EXPECT_THAT(meshes.excludes_mjcf, HasSubstr("Nothing excluded: no two geoms checked"));
  // The pair is checked: at the reference the hulls are apart; with j3 turned they meet.
  const Scene s = Scene::load(cell_with_meshes(dir, "rods", meshes));
  EXPECT_TRUE(check_scene(s).ok());
  RobotState state(s);
  EXPECT_FALSE(state.in_collision(Eigen::Vector3d(0, 0, 0)));
  EXPECT_TRUE(state.in_collision(Eigen::Vector3d(0, 0, 0.4)));
}

// The same rods touching at the reference (link_3's rod crossing link_1's): excluded in mesh mode
// too, with the reason naming the geoms.
TEST_F(UrdfImportTest, MeshGeomsTouchingAtTheReferenceAreExcluded) {
  test::TempDir dir;
  test::write_binary_stl((dir.path() / "rod_a.stl").string(),
                         turned_cuboid({0, -0.01, -0.01}, {1, 0.01, 0.01}, 0.78));
  test::write_binary_stl((dir.path() / "rod_b.stl").string(),
                         turned_cuboid({0, -0.01, -0.01}, {1, 0.01, 0.01}, 0.0));
  const UrdfImport robot = import_urdf(dir.write("rods.urdf", kDiagonalRods));
  ASSERT_EQ(robot.excludes.size(), 1u);
  EXPECT_EQ(robot.excludes[0].geom1, "link_1_mesh");
  EXPECT_THAT(robot.excludes[0].reason,
              AllOf(HasSubstr("the geoms overlap by"), HasSubstr("a mesh geom is its convex hull")));
}

TEST(UrdfImportCliTest, MeshImportNewCellAndCheck) {
  test::TempDir dir;
  const double yaw = 0.7853981633974483;
  test::write_binary_stl((dir.path() / "rod_a.stl").string(),
                         turned_cuboid({0, -0.01, -0.01}, {1, 0.01, 0.01}, yaw));
  test::write_ascii_stl((dir.path() / "rod_b.stl").string(),
                        turned_cuboid({0, -0.01, -0.01}, {1, 0.01, 0.01}, yaw, {0.3, 0, 0}));
  const std::string urdf = dir.write("rods.urdf", kDiagonalRods);
  fs::create_directories(dir.path() / "robots");
  fs::create_directories(dir.path() / "cells");
  const fs::path robot = dir.path() / "robots" / "rods.xml", cell = dir.path() / "cells" / "rods.xml";
  const auto imp = test::run_cli("import-urdf " + urdf + " --out " + quoted(robot));
  ASSERT_EQ(imp.exit_code, 0) << imp.out;
  EXPECT_THAT(imp.out, AllOf(HasSubstr("2 collision geoms, 2 of them meshes"),
                             HasSubstr("0 geom pair(s) excluded from self-collision, 1 checked")));
  EXPECT_TRUE(fs::is_regular_file(dir.path() / "robots" / "rods_meshes" / "link_1_mesh.stl"));
  EXPECT_TRUE(fs::is_regular_file(dir.path() / "robots" / "rods_meshes" / "link_3_mesh.stl"));
  const auto nc = test::run_cli("new-cell --robot " + quoted(robot) + " --out " + quoted(cell));
  ASSERT_EQ(nc.exit_code, 0) << nc.out;
  std::ifstream in(cell);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_THAT(text, HasSubstr("meshdir=\"../robots\""));
  const auto check = test::run_cli("check " + quoted(cell));
  EXPECT_EQ(check.exit_code, 0) << check.out;
  // --link-geometry box writes no meshes; an unknown value is refused before anything is written.
  const fs::path boxed = dir.path() / "robots" / "boxed.xml";
  const auto box = test::run_cli("import-urdf " + urdf + " --link-geometry box --out " + quoted(boxed));
  ASSERT_EQ(box.exit_code, 0) << box.out;
  EXPECT_THAT(box.out, HasSubstr("2 collision boxes"));
  EXPECT_FALSE(fs::exists(dir.path() / "robots" / "boxed_meshes"));
  const fs::path other = dir.path() / "robots" / "other.xml";
  const auto bad = test::run_cli("import-urdf " + urdf + " --link-geometry hull --out " + quoted(other));
  EXPECT_EQ(bad.exit_code, 2) << bad.out;
  EXPECT_THAT(bad.out, HasSubstr("--link-geometry"));
  EXPECT_FALSE(fs::exists(other));
  EXPECT_FALSE(fs::exists(dir.path() / "robots" / "other_meshes"));
}

TEST(UrdfImportCliTest, AMeshMuJoCoCannotCompileExitsTwoWithNoFile) {
  test::TempDir dir;
  // A flat mesh: one triangle, no volume.
  test::write_binary_stl(
      (dir.path() / "rod_a.stl").string(),
      {test::Triangle{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0)}});
  test::write_binary_stl((dir.path() / "rod_b.stl").string(), test::cuboid({0.5, 0.5, 0}, {0.6, 0.6, 0.1}));
  const std::string urdf = dir.write("rods.urdf", kDiagonalRods);
  const fs::path out = dir.path() / "flat.xml";
  const auto r = test::run_cli("import-urdf " + urdf + " --out " + quoted(out));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_THAT(r.out,
              AllOf(HasSubstr("link 'link_1' <collision> 1 <mesh> filename 'rod_a.stl'"),
                    HasSubstr("MuJoCo cannot compile it as a mesh geom"), HasSubstr("--link-geometry box")));
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(dir.path() / "flat_excludes.xml"));
  EXPECT_FALSE(fs::exists(dir.path() / "flat_meshes"));
}

TEST(UrdfImportLeakTest, RefusedJointLoopsLeaveNoLeak) {
#ifndef LEEWAY_TEST_ASAN
  GTEST_SKIP() << "needs LeakSanitizer: build with LEEWAY_SANITIZE=address";
#else
  test::TempDir dir;
  const std::string loop = dir.write(
      "loop.urdf",
      edited(
          kTwoJoints, "</robot>",
          R"(<joint name="back" type="fixed"><parent link="link_2"/><child link="link_1"/></joint></robot>)"));
  const std::string cycle = dir.write(
      "cycle.urdf",
      edited(
          kTwoJoints, "</robot>",
          R"(<link name="ring_a"/><link name="ring_b"/><joint name="r1" type="fixed"><parent link="ring_a"/>)"
          R"(<child link="ring_b"/></joint><joint name="r2" type="fixed"><parent link="ring_b"/>)"
          R"(<child link="ring_a"/></joint></robot>)"));
  UrdfImportOptions ring;
  ring.tool_link = "ring_b";
  try {
    import_urdf(loop);
    ADD_FAILURE() << "a joint loop was imported";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("loop.urdf: link 'link_1' is the child of joints 'back', 'j1'"));
  }
  try {
    import_urdf(cycle, ring);
    ADD_FAILURE() << "a joint loop was imported";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("cycle.urdf: link 'ring_b' lies on a joint loop above the tool link"));
  }
  EXPECT_EQ(__lsan_do_recoverable_leak_check(), 0) << "the refused URDF models leaked (report above)";
#endif
}

}  // namespace
}  // namespace leeway
