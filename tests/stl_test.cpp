// STL reading: binary and ASCII files written here, their vertices and bounding boxes by hand.
#include "leeway/io/stl.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "leeway/core/error.hpp"
#include "stl_util.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

// A tetrahedron with float-exact coordinates (binary STL stores 32-bit floats).
std::vector<test::Triangle> tetrahedron() {
  const Eigen::Vector3d a(0, 0, 0), b(1.5, 0, 0), c(0, -2.25, 0), d(0.5, 0.25, 3);
  return {{a, c, b}, {a, b, d}, {b, c, d}, {c, a, d}};
}

std::string message_of(const std::string& path) {
  try {
    read_stl(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(StlTest, BinaryAndAsciiGiveTheSameTriangles) {
  test::TempDir dir;
  const std::string bin = (dir.path() / "t.stl").string(), text = (dir.path() / "a.stl").string();
  test::write_binary_stl(bin, tetrahedron());
  test::write_ascii_stl(text, tetrahedron());
  const StlMesh b = read_stl(bin), a = read_stl(text);
  EXPECT_TRUE(b.binary);
  EXPECT_FALSE(a.binary);
  ASSERT_EQ(b.triangles(), 4);
  ASSERT_EQ(a.triangles(), 4);
  EXPECT_EQ(b.vertices[1], Eigen::Vector3d(0, -2.25, 0));  // first triangle a, c, b
  EXPECT_EQ(a.vertices[11], Eigen::Vector3d(0.5, 0.25, 3));
  for (size_t i = 0; i < 12; ++i) EXPECT_EQ(a.vertices[i], b.vertices[i]) << i;
  const auto [lo, hi] = bounding_box(b.vertices);
  EXPECT_EQ(lo, Eigen::Vector3d(0, -2.25, 0));
  EXPECT_EQ(hi, Eigen::Vector3d(1.5, 0.25, 3));
}

TEST(StlTest, BinaryWhoseHeaderSaysSolidIsStillBinary) {
  // Many exporters start the binary header with "solid"; the size decides.
  test::TempDir dir;
  const std::string p = (dir.path() / "s.stl").string();
  test::write_binary_stl(p, test::cuboid({-1, -2, -3}, {1, 2, 3}), "solid exported by a CAD tool");
  const StlMesh m = read_stl(p);
  EXPECT_TRUE(m.binary);
  EXPECT_EQ(m.triangles(), 12);
  EXPECT_EQ(bounding_box(m.vertices).second, Eigen::Vector3d(1, 2, 3));
}

TEST(StlTest, BadFilesNameFileAndPlace) {
  test::TempDir dir;
  EXPECT_THAT(message_of((dir.path() / "absent.stl").string()),
              AllOf(HasSubstr("absent.stl"), HasSubstr("cannot open")));
  EXPECT_THAT(message_of(dir.write("hello.stl", "hello, world\n")),
              AllOf(HasSubstr("hello.stl"), HasSubstr("not an STL")));
  EXPECT_THAT(message_of(dir.write("nan.stl",
                                   "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 nan 0\n"
                                   "vertex 0 1 0\nendloop\nendfacet\nendsolid x\n")),
              AllOf(HasSubstr("nan.stl"), HasSubstr("line 5"), HasSubstr("'nan'")));
  EXPECT_THAT(message_of(dir.write("empty.stl", "solid x\nendsolid x\n")),
              AllOf(HasSubstr("empty.stl"), HasSubstr("no triangle")));
  // A binary file cut short: its size no longer matches its triangle count.
  const std::string cut = (dir.path() / "cut.stl").string();
  test::write_binary_stl(cut, tetrahedron());
  std::filesystem::resize_file(cut, 84 + 50 * 4 - 10);
  EXPECT_THAT(message_of(cut), AllOf(HasSubstr("cut.stl"), HasSubstr("not an STL"), HasSubstr("(4)")));
}

}  // namespace
}  // namespace leeway
