// export_mjcf.hpp: the cell with its volume as MJCF written in another folder (includes inlined,
// asset paths rewritten) and as MJB, compiled by MuJoCo without warnings.
#include "leeway/viz/export_mjcf.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "leeway/core/error.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// A binary STL tetrahedron (MuJoCo computes the normals).
void write_tetrahedron(const fs::path& file) {
  const float v[4][3] = {{0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}, {0, 0, 0.1f}};
  const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::ofstream out(file, std::ios::binary);
  const std::string header(80, ' ');
  out.write(header.data(), 80);
  const std::uint32_t n = 4;
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (const auto& f : faces) {
    const float normal[3] = {0, 0, 0};
    out.write(reinterpret_cast<const char*>(normal), sizeof(normal));
    for (int k : f) out.write(reinterpret_cast<const char*>(v[k]), sizeof(v[k]));
    const std::uint16_t attr = 0;
    out.write(reinterpret_cast<const char*>(&attr), 2);
  }
}

class ExportMjcfTest : public test::MujocoTest {
 protected:
  // cell/main.xml includes parts/arm.xml, which includes parts/link.xml (relative to the main file's
  // folder, as MuJoCo resolves nested includes); a mesh in cell/meshes; a commented-out include.
  std::string cell() {
    fs::create_directories(dir_.path() / "cell/parts");
    fs::create_directories(dir_.path() / "cell/meshes");
    write_tetrahedron(dir_.path() / "cell/meshes/tet.stl");
    dir_.write("cell/parts/link.xml",
               R"(<mujoco><geom name="link_box" type="box" size="0.1 0.1 0.1"/></mujoco>)");
    dir_.write("cell/parts/arm.xml", R"(<?xml version="1.0"?>
<!-- the arm -->
<mujoco model="arm">
  <body name="arm" pos="0 0 1"><joint name="j1" type="hinge" axis="0 0 1"/>
    <include file="parts/link.xml"/>
  </body>
</mujoco>)");
    return dir_.write("cell/main.xml", R"(<mujoco model="cell">
  <asset><mesh name="tet" file="meshes/tet.stl"/></asset>
  <worldbody>
    <!-- <include file="parts/missing.xml"/> stays a comment, as </worldbody> here does -->
    <include file="parts/arm.xml"/>
    <geom name="table" type="box" pos="1 0 0.3" size="0.5 0.5 0.3"/>
    <geom name="ornament" type="mesh" mesh="tet" pos="-1 0 0" contype="0" conaffinity="0"/>
  </worldbody>
</mujoco>
)");
  }
  std::vector<Box> boxes() const {
    Box a, b;
    a.center = {2, 0, 0.5};
    a.half_size = {0.1, 0.1, 0.5};
    b.center = {2, 1, 0.25};
    b.half_size = {0.1, 0.2, 0.25};
    b.rotation << 0, -1, 0, 1, 0, 0, 0, 0, 1;  // 90 degrees about z
    return {a, b};
  }
  test::TempDir dir_;
};

TEST_F(ExportMjcfTest, WrittenElsewhereItCompilesWithTheBoxes) {
  const std::string c = cell();
  fs::create_directories(dir_.path() / "out/deeper");
  const std::string out = (dir_.path() / "out/deeper/v.xml").string();
  const std::string xml = volume_mjcf(c, boxes(), out);
  EXPECT_THAT(xml, HasSubstr("<!-- leeway: begin parts/arm.xml -->"));
  EXPECT_THAT(xml, HasSubstr("file=\"../../cell/meshes/tet.stl\""));
  EXPECT_THAT(xml, HasSubstr("<!-- <include file=\"parts/missing.xml\"/>"));
  std::ofstream(out) << xml;
  const ModelPtr m = load_model_file(out);
  const int body = mj_name2id(m.get(), mjOBJ_BODY, kExportBodyName);
  ASSERT_GE(body, 0);
  ASSERT_EQ(m->body_geomnum[body], 2);
  const int g = m->body_geomadr[body];
  EXPECT_EQ(object_name(*m, mjOBJ_GEOM, g + 1), "leeway_volume_box_1");
  EXPECT_DOUBLE_EQ(m->geom_pos[3 * (g + 1) + 1], 1.0);
  EXPECT_DOUBLE_EQ(m->geom_size[3 * (g + 1) + 1], 0.2);
  // 90 degrees about z: quaternion (cos 45, 0, 0, sin 45).
  EXPECT_NEAR(m->geom_quat[4 * (g + 1)], std::sqrt(0.5), 1e-9);
  EXPECT_NEAR(m->geom_quat[4 * (g + 1) + 3], std::sqrt(0.5), 1e-9);
  EXPECT_EQ(m->geom_contype[g], 0);
  EXPECT_EQ(m->geom_conaffinity[g], 0);
  // The top of box 0 is the highest (1 m): the yellow end of the colour scale.
  EXPECT_NEAR(m->geom_rgba[4 * g], 0.993, 1e-6);
  EXPECT_GE(mj_name2id(m.get(), mjOBJ_GEOM, "link_box"), 0);
  EXPECT_GE(mj_name2id(m.get(), mjOBJ_MESH, "tet"), 0);
}

TEST_F(ExportMjcfTest, MjbHoldsTheSameModel) {
  const std::string c = cell();
  const std::string out = (dir_.path() / "v.mjb").string();
  const std::string bytes = volume_mjb(c, boxes(), out);
  std::ofstream(out, std::ios::binary) << bytes;
  const ModelPtr m = load_model_file(out);
  const int body = mj_name2id(m.get(), mjOBJ_BODY, kExportBodyName);
  ASSERT_GE(body, 0);
  EXPECT_EQ(m->body_geomnum[body], 2);
}

TEST_F(ExportMjcfTest, MissingIncludeOrWorldbodyIsBadInput) {
  const std::string c = cell();
  fs::remove(dir_.path() / "cell/parts/link.xml");
  try {
    volume_mjcf(c, boxes(), (dir_.path() / "v.xml").string());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("link.xml: cannot read the included file"));
  }
  const std::string bare = dir_.write("bare.xml", "<mujoco/>");
  EXPECT_THROW(volume_mjcf(bare, boxes(), (dir_.path() / "v.xml").string()), InputError);
  Box bad;
  bad.half_size = {0.1, std::nan(""), 0.1};
  EXPECT_THROW(volume_mjcf(c, {bad}, (dir_.path() / "v.xml").string()), InputError);
}

}  // namespace
}  // namespace leeway
