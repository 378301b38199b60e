// Wavefront OBJ reading: quads, negative indices and v/vt/vn corners read back as triangles.
#include "leeway/io/obj.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_util.hpp"

namespace leeway {
namespace {

using Eigen::Vector3d;
using ::testing::HasSubstr;

TEST(ObjReaderTest, QuadsNegativeIndicesAndTextureNormalCorners) {
  test::TempDir dir;
  const std::string path = dir.write("part.obj", R"(# a unit square and a triangle
mtllib part.mtl
o square
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0 1.0
vt 0 0
vn 0 0 1
usemtl steel
s off
f 1/1/1 2/1/1 3/1/1 4/1/1
v 0 0 2
v 1 0 2
v 0 1 2
f -3//1 -2//1 -1//1
f 5/1 6 7
)");
  const std::vector<Vector3d> t = read_obj(path);
  ASSERT_EQ(t.size(), 12u);  // the quad fanned into two triangles, then two triangles
  const std::vector<Vector3d> expected = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                          {0, 0, 2}, {1, 0, 2}, {0, 1, 2}, {0, 0, 2}, {1, 0, 2}, {0, 1, 2}};
  for (size_t i = 0; i < t.size(); ++i) EXPECT_EQ(t[i], expected[i]) << "vertex " << i;
}

TEST(ObjReaderTest, MalformedLinesNameTheFileAndLine) {
  test::TempDir dir;
  EXPECT_THAT(test::error_of([&] { read_obj(dir.write("a.obj", "v 0 0 0\nv 1 0\n")); }),
              HasSubstr("a.obj: OBJ line 2: vertex 'v' has fewer than 3 values"));
  EXPECT_THAT(test::error_of([&] { read_obj(dir.write("b.obj", "v 0 0 nan\n")); }),
              HasSubstr("b.obj: OBJ line 1: vertex value 'nan' is not a finite number"));
  EXPECT_THAT(test::error_of([&] { read_obj(dir.write("c.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")); }),
              HasSubstr("c.obj: OBJ line 4: face corner '4' names vertex 4, but 3 vertices"));
  EXPECT_THAT(test::error_of([&] { read_obj(dir.write("d.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x/1\n")); }),
              HasSubstr("d.obj: OBJ line 4: face corner 'x/1' is not a vertex index"));
  EXPECT_THAT(test::error_of([&] { read_obj(dir.write("e.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n")); }),
              HasSubstr("e.obj: OBJ line 3: face 'f' has 2 corners"));
  EXPECT_THAT(test::error_of([&] { read_obj(dir.write("f.obj", "v 0 0 0\nf 0 1 1\n")); }),
              HasSubstr("names vertex 0"));
  EXPECT_THAT(test::error_of([&] { read_obj(dir.write("g.obj", "# nothing\nv 0 0 0\n")); }),
              HasSubstr("g.obj: the OBJ file holds no face"));
  EXPECT_THAT(test::error_of([&] { read_obj((dir.path() / "missing.obj").string()); }),
              HasSubstr("missing.obj: cannot open the OBJ file"));
}

}  // namespace
}  // namespace leeway
