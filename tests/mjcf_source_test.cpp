// The MJCF text before MuJoCo sees it (mjcf_source.hpp): every numeric attribute finite, in the
// model file and the files it includes, and the list of files MuJoCo 2.2.2 reads for a model.
#include "leeway/core/mjcf_source.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/scene.hpp"
#include "stl_util.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

using test::error_of;

class MjcfSourceTest : public test::MujocoTest {
 protected:
  // The one-link cell with `world` in its world body, read by read_mjcf_source.
  std::string refusal(const std::string& world, const std::string& keys = "") {
    const std::string cell = dir_.write("cell.xml", test::one_link_cell(world, keys));
    return error_of([&] { read_mjcf_source(cell); });
  }
  std::string path(const std::string& name) const { return (dir_.path() / name).string(); }
  test::TempDir dir_;
};

TEST_F(MjcfSourceTest, TheMessageNamesFileElementAttributeValueAndLine) {
  EXPECT_EQ(
      refusal(R"(<body name="shelf" pos="nan -0.6 0.5"><geom name="b" type="box" size="1 1 1"/></body>)"),
      path("cell.xml") +
          ": body 'shelf' pos 'nan -0.6 0.5' is not finite (value 1 'nan', line 13); MJCF numbers must be "
          "finite");
  EXPECT_EQ(
      refusal(R"(<geom name="b" type="box" size="1 1 1" pos="0 0 0" euler="0 0 inf"/>)"),
      path("cell.xml") +
          ": geom 'b' euler '0 0 inf' is not finite (value 3 'inf', line 13); MJCF numbers must be finite");
}

TEST_F(MjcfSourceTest, EveryFrameAndSizeAttributeIsChecked) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"(<geom name="g" type="box" size="1 1 1" zaxis="nan 0 1"/>)", "geom 'g' zaxis 'nan 0 1'"},
      {R"(<geom name="g" type="box" size="1 1 1" axisangle="0 0 1 nan"/>)", "geom 'g' axisangle '0 0 1 nan'"},
      {R"(<geom name="g" type="box" size="1 1 1" xyaxes="1 0 0 0 1 -inf"/>)",
       "geom 'g' xyaxes '1 0 0 0 1 -inf'"},
      {R"(<geom name="g" type="box" size="1 NaN 1"/>)", "geom 'g' size '1 NaN 1'"},
      {R"(<geom name="g" type="capsule" fromto="0 0 0 1 1 -nan" size="0.1"/>)",
       "geom 'g' fromto '0 0 0 1 1 -nan'"},
      {R"(<geom name="g" type="box" size="1 1 1" margin="Infinity"/>)", "geom 'g' margin 'Infinity'"},
      {R"(<geom name="g" type="box" size="1 1 1" pos="1e999 0 0"/>)", "geom 'g' pos '1e999 0 0'"},
      {R"(<site name="s" pos="0 0 1" size="nan"/>)", "site 's' size 'nan'"},
      {R"(<camera name="c" pos="0 0 1" fovy="nan"/>)", "camera 'c' fovy 'nan'"},
      {R"(<light name="l" pos="0 0 3" dir="0 0 nan"/>)", "light 'l' dir '0 0 nan'"},
      {R"(<body name="b" quat="nan 0 0 1"><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body>)",
       "body 'b' quat 'nan 0 0 1'"},
      {R"(<body name="b"><inertial pos="0 0 0" mass="nan" diaginertia="1 1 1"/></body>)",
       "inertial in body 'b' mass 'nan'"},
      // Entities are decoded as MuJoCo's XML parser decodes them.
      {R"(<geom name="g" type="box" size="1 1 1" pos="&#110;an 0 0"/>)", "geom 'g' pos 'nan 0 0'"},
  };
  for (const auto& [world, fragment] : cases)
    EXPECT_THAT(refusal(world), HasSubstr(fragment + " is not finite")) << world;
}

TEST_F(MjcfSourceTest, JointsKeyframesCustomNumbersAndVisualAreChecked) {
  std::string cell = test::one_link_cell("");
  cell.replace(cell.find(R"(range="-3 3")"), 12, R"(range="-3 inf")");
  EXPECT_THAT(error_of([&] { read_mjcf_source(dir_.write("r.xml", cell)); }),
              HasSubstr("r.xml: joint 'j1' range '-3 inf' is not finite (value 2 'inf', line 8)"));
  EXPECT_THAT(refusal("", R"(<key name="k" qpos="nan"/>)"), HasSubstr("key 'k' qpos 'nan' is not finite"));
  cell = test::one_link_cell("");
  cell.replace(cell.find("<worldbody>"), 0,
               R"(<custom><numeric name="leeway_reach_radius" data="nan"/></custom>
  <visual><global fovy="inf"/></visual>
  )");
  EXPECT_THAT(error_of([&] { read_mjcf_source(dir_.write("c.xml", cell)); }),
              HasSubstr("numeric 'leeway_reach_radius' data 'nan' is not finite"));
  cell.replace(cell.find(R"(data="nan")"), 10, R"(data="2")");
  EXPECT_THAT(error_of([&] { read_mjcf_source(dir_.write("v.xml", cell)); }),
              HasSubstr("visual global fovy 'inf' is not finite"));
}

TEST_F(MjcfSourceTest, NamesAndTextThatReadNanAreNotNumbers) {
  std::string cell = test::one_link_cell(
      R"(<geom name="nan" type="box" size="0.1 0.1 0.1" pos="0 -0.8 0.1" material="inf"/>)");
  cell.replace(cell.find("<worldbody>"), 0, R"(<custom><text name="t" data="nan"/></custom>
  <asset><material name="inf" rgba="1 0 0 1"/></asset>
  )");
  const std::string file = dir_.write("names.xml", cell);
  EXPECT_NO_THROW(read_mjcf_source(file));
  EXPECT_NO_THROW(Scene::load(file));
}

TEST_F(MjcfSourceTest, IncludedFilesAreCheckedAndNamedInTheMessage) {
  fs::create_directories(dir_.path() / "cells");
  fs::create_directories(dir_.path() / "robots");
  dir_.write("robots/part.xml",
             R"(<mujoco><geom name="p" type="box" size="1 1 1" pos="0 0 -inf"/></mujoco>)");
  dir_.write("robots/arm.xml", R"(<mujoco><include file="../robots/part.xml"/></mujoco>)");
  const std::string cell = dir_.write(
      "cells/cell.xml", R"(<mujoco><worldbody><include file="../robots/arm.xml"/></worldbody></mujoco>)");
  // MuJoCo 2.2.2 resolves the nested include from the model file's folder, as the reader does.
  EXPECT_THAT(error_of([&] { read_mjcf_source(cell); }),
              HasSubstr(path("cells") + "/../robots/part.xml: geom 'p' pos '0 0 -inf' is not finite"));
}

// An include that names a folder is refused with the including file, the include and the line: the
// file to mend is the one that includes it.
TEST_F(MjcfSourceTest, AnIncludeNamingAFolderNamesTheIncludingFile) {
  fs::create_directories(dir_.path() / "cells");
  fs::create_directories(dir_.path() / "robots");
  const std::string cell = dir_.write(
      "cells/cell.xml", "<mujoco>\n<worldbody>\n<include file=\"../robots\"/></worldbody></mujoco>");
  EXPECT_EQ(error_of([&] { read_mjcf_source(cell); }),
            cell + ": include '../robots' (line 3): " + path("cells") +
                "/../robots: the included file is a folder, not a regular file");
}

// A deeply nested file is refused (or left to MuJoCo) without exhausting the stack.
TEST_F(MjcfSourceTest, DeepNestingIsASyntaxErrorNotACrash) {
  std::string text = "<mujoco><worldbody>";
  for (int i = 0; i < 100000; ++i) text += "<body>";
  const std::string file = dir_.write("deep.xml", text);
  EXPECT_THROW(read_mjcf_source(file), MjcfSyntaxError);
  EXPECT_THAT(error_of([&] { load_model_file(file); }), HasSubstr("deep.xml"));
}

// The files listed are the ones MuJoCo opens: with any one of the assets removed, MuJoCo no longer
// compiles the model; with all there, it does.
TEST_F(MjcfSourceTest, InputFilesAreTheIncludesAndAssetsMujocoReads) {
  for (const std::string& meshdir : {std::string("meshes"), std::string("meshes/"), path("meshes")}) {
    test::TempDir dir;
    fs::create_directories(dir.path() / "cell" / "meshes");
    fs::create_directories(dir.path() / "robots");
    test::write_binary_stl((dir.path() / "cell/meshes/a.stl").string(), test::cuboid({0, 0, 0}, {1, 1, 1}));
    test::write_binary_stl((dir.path() / "cell/meshes/b.stl").string(), test::cuboid({0, 0, 0}, {1, 2, 1}));
    const std::string dir_meshes = meshdir[0] == '/' ? (dir.path() / "cell/meshes").string() : meshdir;
    std::ofstream(dir.path() / "robots/r.xml")
        << R"(<mujoco><asset><mesh name="b" file="b.stl"/></asset></mujoco>)";
    const fs::path cell = dir.path() / "cell/cell.xml";
    std::ofstream(cell) << R"(<mujoco><compiler meshdir=")" + dir_meshes + R"("/>
  <asset><mesh name="a" file="a.stl"/></asset>
  <include file="../robots/r.xml"/>
  <worldbody><geom name="ra" type="mesh" mesh="a" contype="0" conaffinity="0"/>
  <geom name="rb" type="mesh" mesh="b" contype="0" conaffinity="0"/></worldbody></mujoco>)";
    const std::vector<std::string> files = model_input_files(cell.string());
    ASSERT_EQ(files.size(), 4u) << meshdir;
    EXPECT_EQ(files[0], cell.string());
    EXPECT_TRUE(fs::equivalent(files[1], dir.path() / "robots/r.xml")) << files[1];
    EXPECT_TRUE(fs::equivalent(files[2], dir.path() / "cell/meshes/a.stl")) << files[2];
    EXPECT_TRUE(fs::equivalent(files[3], dir.path() / "cell/meshes/b.stl")) << files[3];
    EXPECT_NO_THROW(load_model_file(cell.string())) << meshdir;
    for (size_t k = 1; k < files.size(); ++k) {
      const fs::path moved = files[k] + ".away";
      fs::rename(files[k], moved);
      EXPECT_THROW(load_model_file(cell.string()), InputError) << files[k];
      fs::rename(moved, files[k]);
    }
  }
}

TEST_F(MjcfSourceTest, StrippathAndTexturedirAreHonoured) {
  const std::string cell = dir_.write("cell.xml", R"(<mujoco>
  <compiler meshdir="m" texturedir="t" strippath="true"/>
  <asset><mesh name="a" file="deep/a.stl"/><texture name="sky" type="skybox" file="/x/sky.png"/></asset>
</mujoco>)");
  EXPECT_THAT(read_mjcf_source(cell).files, ElementsAre(cell, (dir_.path() / "m" / "a.stl").string(),
                                                        (dir_.path() / "t" / "sky.png").string()));
  EXPECT_THAT(model_input_files(path("model.mjb")), ElementsAre(path("model.mjb")));
}

}  // namespace
}  // namespace leeway
