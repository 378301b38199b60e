#include "leeway/core/scene.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <set>

#include "leeway/core/error.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using test::one_link_cell;
using test::TempDir;
using ::testing::HasSubstr;

class SceneTest : public test::MujocoTest {
 protected:
  TempDir dir_;
  // Loads `xml` and expects an InputError whose message contains every fragment.
  void expect_error(const std::string& xml, std::initializer_list<const char*> fragments) {
    const std::string path = dir_.write("cell.xml", xml);
    try {
      Scene::load(path);
      ADD_FAILURE() << "no error for:\n" << xml;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(path));
      for (const char* f : fragments) EXPECT_THAT(e.what(), HasSubstr(f));
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "message spans lines: " << e.what();
    }
  }
};

TEST_F(SceneTest, RecognisesRobotObstaclesSitesAndKeyframes) {
  const std::string path =
      dir_.write("cell.xml", one_link_cell(R"(<geom name="wall" type="box" size="0.05 1 1" pos="0 1.2 1"/>
    <geom name="deco" type="sphere" size="0.1" pos="3 3 3" contype="0" conaffinity="0"/>
    <site name="goal" pos="1 0 0.6"/>)",
                                           R"(<key name="home" qpos="0"/><key name="left" qpos="1.5"/>)"));
  const Scene s = Scene::load(path);
  ASSERT_EQ(s.dof(), 1);
  EXPECT_EQ(s.joints()[0].name, "j1");
  EXPECT_DOUBLE_EQ(s.joints()[0].lower, -3);
  EXPECT_DOUBLE_EQ(s.joints()[0].upper, 3);
  EXPECT_DOUBLE_EQ(s.joints()[0].max_speed, 1.5);
  EXPECT_FALSE(s.joints()[0].prismatic);
  const mjModel& m = s.model();
  ASSERT_EQ(s.link_geoms().size(), 1u);
  EXPECT_EQ(s.geom_label(s.link_geoms()[0]), "link_box");
  ASSERT_EQ(s.base_geoms().size(), 1u);
  EXPECT_EQ(s.geom_label(s.base_geoms()[0]), "base_box");
  ASSERT_EQ(s.obstacle_geoms().size(), 1u);  // the floor and "deco" are visual only
  EXPECT_EQ(s.geom_label(s.obstacle_geoms()[0]), "wall");
  // Normalised bitmasks: links collide with obstacles only; the fixed base with nothing.
  const int link = s.link_geoms()[0], wall = s.obstacle_geoms()[0], base = s.base_geoms()[0];
  EXPECT_EQ(m.geom_contype[link], 1);
  EXPECT_EQ(m.geom_conaffinity[link], 0);
  EXPECT_EQ(m.geom_contype[wall], 0);
  EXPECT_EQ(m.geom_conaffinity[wall], 1);
  EXPECT_EQ(m.geom_contype[base] | m.geom_conaffinity[base], 0);
  ASSERT_EQ(s.goal_sites().size(), 1u);
  EXPECT_EQ(s.goal_site("goal"), s.goal_sites()[0]);
  ASSERT_EQ(s.keyframes().size(), 2u);
  EXPECT_DOUBLE_EQ(s.keyframe("left").q[0], 1.5);
}

TEST_F(SceneTest, UnknownKeyframeAndSiteListTheKnownOnes) {
  const std::string path = dir_.write(
      "cell.xml", one_link_cell(R"(<site name="goal" pos="1 0 0.6"/>)", R"(<key name="home" qpos="0"/>)"));
  const Scene s = Scene::load(path);
  try {
    s.keyframe("patch");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("no keyframe 'patch'"));
    EXPECT_THAT(e.what(), HasSubstr("'home'"));
  }
  try {
    s.goal_site("mould");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("no goal site 'mould'"));
    EXPECT_THAT(e.what(), HasSubstr("'goal'"));
  }
}

TEST_F(SceneTest, MissingFile) {
  try {
    Scene::load(dir_.path().string() + "/absent.xml");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("absent.xml: cannot open the file"));
  }
}

TEST_F(SceneTest, MalformedXml) { expect_error("<mujoco><worldbody>", {"MJCF does not compile", "XML"}); }

TEST_F(SceneTest, NoRobotJoints) {
  expect_error(R"(<mujoco><worldbody><geom name="t" type="box" size="1 1 1"/></worldbody></mujoco>)",
               {"no robot joints"});
}

TEST_F(SceneTest, FreeJointIsRejected) {
  expect_error(R"(<mujoco><worldbody><body name="b"><freejoint name="f"/><geom type="box" size="1 1 1"/>
      </body></worldbody></mujoco>)",
               {"joint 'f'", "free joint"});
}

TEST_F(SceneTest, TwoRobotsAreRejected) {
  expect_error(one_link_cell(R"(<body name="other"><joint name="k" type="hinge" range="-1 1"/>
      <geom type="box" size="0.1 0.1 0.1"/></body>)"),
               {"joint 'k'", "'other'", "outside the robot subtree 'base'"});
}

TEST_F(SceneTest, UnlimitedJointIsRejected) {
  expect_error(
      R"(<mujoco><worldbody><body name="b"><joint name="j" type="hinge"/><geom type="box" size="1 1 1"/>
      <site name="tool0"/></body></worldbody></mujoco>)",
      {"joint 'j'", "no range"});
}

TEST_F(SceneTest, MissingToolSite) {
  std::string xml = one_link_cell("");
  xml.replace(xml.find("tool0"), 5, "flange");
  expect_error(xml, {"no site named 'tool0'", "tool_site"});
  try {
    Scene::load(dir_.write("cell.xml", xml));
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).find("--"), std::string::npos) << "names a program flag: " << e.what();
  }
}

TEST_F(SceneTest, KeyframeOfWrongLength) {
  expect_error(one_link_cell("", R"(<key name="bad" qpos="0 1"/>)"), {"qpos size", "bad"});
}

TEST_F(SceneTest, NanAndInfInKeyframe) {
  expect_error(one_link_cell("", R"(<key name="bad" qpos="nan"/>)"), {"key 'bad' qpos 'nan' is not finite"});
  expect_error(one_link_cell("", R"(<key name="huge" qpos="inf"/>)"),
               {"key 'huge' qpos 'inf' is not finite"});
  // Refused before MuJoCo parses the file: no warning of MuJoCo's about the NaN.
  EXPECT_TRUE(take_mujoco_warnings().empty());
}

TEST_F(SceneTest, NegativeMaxSpeed) {
  std::string xml = one_link_cell("");
  xml.replace(xml.find("user=\"1.5\""), 10, "user=\"-2\"");
  expect_error(xml, {"joint 'j1'", "max speed", "'-2'"});
}

TEST(ParseVectorTest, AcceptsSpacesAndCommas) {
  const Eigen::VectorXd v = parse_vector(" 1, -2.5 3e-1 ", "--q");
  ASSERT_EQ(v.size(), 3);
  EXPECT_DOUBLE_EQ(v[0], 1);
  EXPECT_DOUBLE_EQ(v[1], -2.5);
  EXPECT_DOUBLE_EQ(v[2], 0.3);
}

TEST(ParseVectorTest, RejectsNonNumbersNanAndInf) {
  for (const char* bad : {"1 x", "1 nan", "inf 2", "1 2abc"}) {
    try {
      parse_vector(bad, "--q");
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("--q: value"));
    }
  }
}

// The self pairs of a Scene by geom name, each "a|b" with a on the part nearer the root.
template <typename Pairs>
std::set<std::string> pair_names(const Scene& s, const Pairs& pairs) {
  std::set<std::string> out;
  for (const auto& p : pairs) out.insert(s.geom_label(p.geom1) + "|" + s.geom_label(p.geom2));
  return out;
}

TEST_F(SceneTest, SelfPairsAreTheRigidPartsNeitherTheSameNorParentAndChild) {
  // Parts (MuJoCo's weld bodies): the world with base_box, link1, link2, and link3 with the tool
  // welded to it. Of the 10 pairs of the 5 robot geoms, l3_box|tool_box share a part and
  // base_box|l1_box, l1_box|l2_box, l2_box|l3_box, l2_box|tool_box are parent and child: 5 remain.
  const Scene s = Scene::load(dir_.write("cell.xml", test::three_link_cell()));
  EXPECT_EQ(pair_names(s, s.self_pairs()),
            (std::set<std::string>{"base_box|l2_box", "base_box|l3_box", "base_box|tool_box", "l1_box|l3_box",
                                   "l1_box|tool_box"}));
  EXPECT_TRUE(s.excluded_pairs().empty());
  // The base touches links only through self pairs: it is no link and no obstacle.
  EXPECT_EQ(s.base_geoms().size(), 1u);
  EXPECT_EQ(s.link_geoms().size(), 4u);
}

TEST_F(SceneTest, ABodyExcludeRemovesThatBodysPairsAndAGeomExcludeOnePair) {
  // MuJoCo's body exclude between base and link3: base_box|l3_box only (the tool is another body,
  // though welded to link3); the geom exclude drops l1_box|tool_box only.
  const Scene s = Scene::load(
      dir_.write("cell.xml", test::three_link_cell(R"(<contact><exclude body1="base" body2="link3"/></contact>
  <custom><text name="leeway_exclude_tool" data="tool_box l1_box"/></custom>)")));
  EXPECT_EQ(pair_names(s, s.self_pairs()),
            (std::set<std::string>{"base_box|l2_box", "base_box|tool_box", "l1_box|l3_box"}));
  ASSERT_EQ(s.excluded_pairs().size(), 2u);
  for (const ExcludedPair& e : s.excluded_pairs()) {
    const std::string name = s.geom_label(e.geom1) + "|" + s.geom_label(e.geom2);
    if (name == "base_box|l3_box")
      EXPECT_TRUE(e.by_body);
    else if (name == "l1_box|tool_box")
      EXPECT_FALSE(e.by_body);
    else
      ADD_FAILURE() << "excluded " << name;
  }
  // Excluding a pair the rule never checks (parent and child) changes nothing.
  const Scene t = Scene::load(dir_.write(
      "adjacent.xml", test::three_link_cell(R"(<contact><exclude body1="link1" body2="link2"/></contact>)")));
  EXPECT_EQ(t.self_pairs().size(), 5u);
  EXPECT_TRUE(t.excluded_pairs().empty());
}

TEST_F(SceneTest, ExcludesThatCannotBeUsedAreRefused) {
  expect_error(test::three_link_cell(R"(<contact><exclude body1="link3" body2="stand"/></contact>)"),
               {"<exclude body1='link3' body2='stand'> pairs a robot body with a body of the cell"});
  expect_error(
      test::three_link_cell(R"(<custom><text name="leeway_exclude_x" data="l1_box l9_box"/></custom>)"),
      {"custom text 'leeway_exclude_x' names geom 'l9_box', which does not exist"});
  expect_error(
      test::three_link_cell(R"(<custom><text name="leeway_exclude_x" data="l1_box block"/></custom>)"),
      {"names geom 'block', which is not a collidable robot geom"});
  expect_error(test::three_link_cell(R"(<custom><text name="leeway_exclude_x" data="l1_box"/></custom>)"),
               {"custom text 'leeway_exclude_x' must name two robot geoms, not 1 words"});
  expect_error(test::three_link_cell(R"(<contact><exclude body1="link1" body2="ghost"/></contact>)"),
               {"MJCF does not compile", "body 'ghost' not found"});
}

TEST_F(SceneTest, ValidateConfigurationNamesJointAndValue) {
  const Scene s = Scene::load(dir_.write("cell.xml", one_link_cell("")));
  EXPECT_THROW(s.validate_configuration(Eigen::VectorXd::Zero(2), "--q"), InputError);
  Eigen::VectorXd q(1);
  q << std::nan("");
  try {
    s.validate_configuration(q, "--q");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("joint 'j1' value 'nan'"));
  }
}

}  // namespace
}  // namespace leeway
