// The bounds as a controller reads them: BoundsTrajectory's interpolation in s and t against values
// worked out by hand, the bounds file's format 2 (times in the file, format 1 still read), and the
// exports of `leeway sample` (CSV, JSON, .npz read back by an independent zip/npy reader here, Drake
// YAML).
#include "leeway/core/bounds_trajectory.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "leeway/core/cell_defaults.hpp"
#include "leeway/core/confidence.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/core/volume_world.hpp"
#include "leeway/io/bounds_export.hpp"
#include "leeway/io/bounds_file.hpp"
#include "leeway/path/nominal_path.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using ::testing::HasSubstr;

WaypointBounds box2(double q0, double l0, double u0, double q1, double l1, double u1) {
  return WaypointBounds((Eigen::VectorXd(2) << q0, q1).finished(), (Eigen::VectorXd(2) << l0, l1).finished(),
                        (Eigen::VectorXd(2) << u0, u1).finished());
}

// Four waypoints of two joints at t = 0, 2, 2 (waypoint 1 given twice) and 5 s.
BoundsTrajectory four_waypoints() {
  return BoundsTrajectory({box2(0, -0.1, 0.2, 1, 0.5, 1.5), box2(1, 0.8, 1.4, 0, -0.4, 0.2),
                           box2(1, 0.8, 1.4, 0, -0.4, 0.2), box2(4, 3.0, 4.5, -1, -1.5, -0.5)},
                          {0, 2, 2, 5}, true);
}

using test::error_of;

TEST(BoundsTrajectory, AtWaypointsItIsTheWaypointValueForValue) {
  const BoundsTrajectory tr = four_waypoints();
  EXPECT_EQ(tr.duration(), 5.0);
  EXPECT_EQ(tr.s_end(), 3.0);
  for (int i = 0; i < 4; ++i) {
    const BoundsStage b = tr.at_s(i);
    EXPECT_EQ(b.nominal, tr.waypoints()[static_cast<size_t>(i)].q) << i;
    EXPECT_EQ(b.lower, tr.waypoints()[static_cast<size_t>(i)].lower) << i;
    EXPECT_EQ(b.upper, tr.waypoints()[static_cast<size_t>(i)].upper) << i;
    EXPECT_EQ(b.t, tr.times()[static_cast<size_t>(i)]);
  }
}

TEST(BoundsTrajectory, BetweenWaypointsItIsLinearInS) {
  const BoundsTrajectory tr = four_waypoints();
  // s = 0.25: a quarter of the way from waypoint 0 to 1. Joint 0: nominal 0 + 0.25 (1 - 0) = 0.25,
  // lower -0.1 + 0.25 (0.8 + 0.1) = 0.125, upper 0.2 + 0.25 (1.4 - 0.2) = 0.5. Joint 1: nominal
  // 1 - 0.25 = 0.75, lower 0.5 + 0.25 (-0.9) = 0.275, upper 1.5 + 0.25 (-1.3) = 1.175. t = 0.5 s.
  const BoundsStage b = tr.at_s(0.25);
  EXPECT_NEAR(b.nominal[0], 0.25, 1e-15);
  EXPECT_NEAR(b.lower[0], 0.125, 1e-15);
  EXPECT_NEAR(b.upper[0], 0.5, 1e-15);
  EXPECT_NEAR(b.nominal[1], 0.75, 1e-15);
  EXPECT_NEAR(b.lower[1], 0.275, 1e-15);
  EXPECT_NEAR(b.upper[1], 1.175, 1e-15);
  EXPECT_NEAR(b.t, 0.5, 1e-15);
  // s = 2.5: halfway through the last segment (2 s to 5 s): t = 3.5 s; joint 0 lower (0.8 + 3) / 2.
  const BoundsStage c = tr.at_s(2.5);
  EXPECT_NEAR(c.t, 3.5, 1e-15);
  EXPECT_NEAR(c.lower[0], 1.9, 1e-15);
  EXPECT_NEAR(c.upper[1], -0.15, 1e-15);
  EXPECT_TRUE(tr.contains(0.25, (Eigen::VectorXd(2) << 0.3, 1.0).finished()));
  EXPECT_FALSE(tr.contains(0.25, (Eigen::VectorXd(2) << 0.1, 1.0).finished()));  // below 0.125
  EXPECT_FALSE(tr.contains(0.25, (Eigen::VectorXd(2) << 0.3, 1.2).finished()));  // above 1.175
}

TEST(BoundsTrajectory, TimeMapsToTheParameterSegmentBySegment) {
  const BoundsTrajectory tr = four_waypoints();
  EXPECT_EQ(tr.s_at_t(0), 0.0);
  EXPECT_EQ(tr.s_at_t(1), 0.5);
  // At t = 2 s two waypoints are reached at once (a segment of zero duration): the later one.
  EXPECT_EQ(tr.s_at_t(2), 2.0);
  EXPECT_EQ(tr.s_at_t(3.5), 2.5);
  EXPECT_EQ(tr.s_at_t(5), 3.0);
  const BoundsStage b = tr.at_t(1);
  EXPECT_NEAR(b.lower[0], 0.35, 1e-15);  // -0.1 + 0.5 (0.9)
  EXPECT_EQ(b.t, 1.0);
  EXPECT_EQ(b.s, 0.5);
  EXPECT_EQ(tr.t_at_s(2.5), 3.5);
  EXPECT_EQ(tr.t_at_s(1.5), 2.0);  // inside the zero-duration segment
}

TEST(BoundsTrajectory, OutsideThePathItHoldsTheEndsAndNanIsRefused) {
  const BoundsTrajectory tr = four_waypoints();
  EXPECT_EQ(tr.at_t(-1).lower, tr.waypoints().front().lower);
  EXPECT_EQ(tr.at_t(-1).t, 0.0);
  EXPECT_EQ(tr.at_t(7).upper, tr.waypoints().back().upper);
  EXPECT_EQ(tr.at_t(7).t, 5.0);
  EXPECT_EQ(tr.at_s(-0.5).s, 0.0);
  EXPECT_EQ(tr.at_s(9).nominal, tr.waypoints().back().q);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(error_of([&] { tr.at_t(nan); }), HasSubstr("the time t is NaN"));
  EXPECT_THAT(error_of([&] { tr.at_s(nan); }), HasSubstr("the path parameter s is NaN"));
  EXPECT_THAT(error_of([&] { tr.contains(0, Eigen::VectorXd::Zero(3)); }), HasSubstr("3 values"));
}

TEST(BoundsTrajectory, SampleCoversZeroToTheDurationInclusive) {
  const BoundsTrajectory tr = four_waypoints();
  // dt 2: t = 0, 2, 4 and the end 5.
  std::vector<double> t;
  for (const auto& b : tr.sample(2)) t.push_back(b.t);
  EXPECT_EQ(t, (std::vector<double>{0, 2, 4, 5}));
  // dt 2.5: the end is a multiple of the step and appears once.
  t.clear();
  for (const auto& b : tr.sample(2.5)) t.push_back(b.t);
  EXPECT_EQ(t, (std::vector<double>{0, 2.5, 5}));
  EXPECT_EQ(tr.sample_count(0.001), 5001);
  EXPECT_EQ(tr.sample(0.001).back().upper, tr.waypoints().back().upper);
  // One waypoint: one row.
  const BoundsTrajectory one({box2(0, -1, 1, 0, -1, 1)}, {0}, false);
  EXPECT_EQ(one.sample(0.1).size(), 1u);
  EXPECT_THAT(error_of([&] { tr.sample(0); }), HasSubstr("must be a positive number"));
  EXPECT_THAT(error_of([&] { tr.sample(-0.1); }), HasSubstr("must be a positive number"));
  EXPECT_THAT(error_of([&] { tr.sample(std::numeric_limits<double>::infinity()); }),
              HasSubstr("must be a positive number"));
  EXPECT_THAT(error_of([&] { tr.sample_count(1e-7); }), HasSubstr("more than 10000000 rows"));
}

TEST(BoundsTrajectory, RefusesBadTimesAndBoxes) {
  const std::vector<WaypointBounds> two = {box2(0, -1, 1, 0, -1, 1), box2(1, 0, 2, 1, 0, 2)};
  EXPECT_THAT(error_of([&] { BoundsTrajectory(two, {0, -1}, true); }), HasSubstr("comes before"));
  EXPECT_THAT(error_of([&] { BoundsTrajectory(two, {0.5, 1}, true); }), HasSubstr("is not 0"));
  EXPECT_THAT(error_of([&] { BoundsTrajectory(two, {0}, true); }), HasSubstr("1 times for 2 waypoints"));
  std::vector<WaypointBounds> bad = two;
  bad[1].lower[0] = 1.5;  // above the nominal 1
  EXPECT_THAT(error_of([&] { BoundsTrajectory(bad, {0, 1}, true); }), HasSubstr("is not within"));
}

// The scene's timing: the IRB 6700's j6 (3.6652 rad/s, docs/mjcf-conventions.md) moving 1 rad sets
// the segment's duration, 1 / 3.6652 s (j1's 0.5 rad at 1.9199 rad/s takes less).
TEST(BoundsTrajectory, TimedByTheSceneJointSpeeds) {
  install_mujoco_error_handlers();
  const Scene dallara = Scene::load(test::workcell("dallara"));
  Eigen::VectorXd q1 = Eigen::VectorXd::Zero(6);
  q1[0] = 0.5;
  q1[5] = 1.0;
  const BoundsTrajectory tr(dallara,
                            {WaypointBounds(Eigen::VectorXd::Zero(6), Eigen::VectorXd::Constant(6, -0.1),
                                            Eigen::VectorXd::Constant(6, 0.1)),
                             WaypointBounds(q1, q1, q1)});
  EXPECT_TRUE(tr.timed());
  EXPECT_NEAR(tr.duration(), 1.0 / 3.6652, 1e-12);
  EXPECT_NEAR(tr.at_t(tr.duration() / 2).nominal[5], 0.5, 1e-12);
}

class BoundsFormatTest : public test::MujocoTest {
 protected:
  void SetUp() override {
    test::MujocoTest::SetUp();
    scene_ = std::make_unique<Scene>(Scene::load(test::workcell("dallara")));
    apply_cell_defaults(*scene_, params_);
    params_.height_map.max_cells = 300;
    VolumeModel world(*scene_, 300 + static_cast<int>(scene_->obstacle_geoms().size()));
    const BoundsRun run =
        compute_bounds(*scene_, world, keyframe_path(*scene_, "home", "patch", 2), params_, 2);
    file_ = std::make_unique<nlohmann::json>(bounds_json(*scene_, run, params_));
  }
  std::string write(const std::string& name, const nlohmann::json& j) const {
    return dir_.write(name, j.dump(1));
  }
  std::unique_ptr<Scene> scene_;
  Params params_;
  std::unique_ptr<nlohmann::json> file_;
  test::TempDir dir_;
};

TEST_F(BoundsFormatTest, FormatTwoCarriesTimesAndTheContract) {
  const nlohmann::json& j = *file_;
  EXPECT_EQ(j.at("format"), "leeway-bounds-2");
  const auto& w = j.at("waypoints");
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[0].at("t"), 0.0);
  EXPECT_EQ(w[1].at("s"), 1.0);
  // The nominal timing: the slowest joint at its speed (time_path, checked by hand above).
  std::vector<WaypointBounds> b = read_bounds(write("b.json", j), *scene_);
  EXPECT_EQ(w[1].at("t").get<double>(), time_path(*scene_, b).total);
  EXPECT_EQ(j.at("timing").at("joint_speeds").size(), 6u);
  EXPECT_EQ(j.at("timing").at("joint_speeds")[5], scene_->joints()[5].max_speed);
  EXPECT_EQ(j.at("interpolation").at("parameter"), "s");
  // The default safety stage certifies: the region states what was proven.
  EXPECT_EQ(j.at("certified_region").at("mode"), "certified");
  EXPECT_EQ(j.at("certified_region").at("proven"), j.at("safety").at("certified"));
  EXPECT_EQ(j.at("certified_region").at("margin"), params_.safety.margin);
}

TEST_F(BoundsFormatTest, FormatTwoRoundTripsAndFormatOneStillLoads) {
  const BoundsTrajectory two = read_bounds_trajectory(write("two.json", *file_), *scene_);
  EXPECT_EQ(two.times()[1], (*file_)["waypoints"][1]["t"].get<double>());
  EXPECT_EQ(two.waypoints()[1].lower,
            Eigen::Map<const Eigen::VectorXd>(
                (*file_)["waypoints"][1]["lower"].get<std::vector<double>>().data(), 6));
  nlohmann::json one = *file_;
  one["format"] = "leeway-bounds-1";
  for (auto& w : one["waypoints"]) {
    w.erase("t");
    w.erase("s");
  }
  const BoundsTrajectory old = read_bounds_trajectory(write("one.json", one), *scene_);
  EXPECT_EQ(old.times(), two.times());  // timed by the cell, the same numbers
  // Read without the cell: format 2 only.
  const BoundsFile f = read_bounds_file(write("two.json", *file_));
  EXPECT_EQ(f.joints, scene_->joint_names());
  EXPECT_EQ(f.trajectory.times(), two.times());
  EXPECT_THAT(error_of([&] { read_bounds_file(write("one.json", one)); }), HasSubstr("without times"));
}

TEST_F(BoundsFormatTest, BadTimesNameTheFileAndWaypoint) {
  nlohmann::json j = *file_;
  j["waypoints"][1]["t"] = -1.0;
  const std::string back = write("back.json", j);
  EXPECT_THAT(error_of([&] { read_bounds_trajectory(back, *scene_); }),
              HasSubstr(back + ": waypoint 1 't' -1 s: times start at 0 and never decrease"));
  j = *file_;
  j["waypoints"][1].erase("t");
  EXPECT_THAT(error_of([&] { read_bounds_trajectory(write("no_t.json", j), *scene_); }),
              HasSubstr("has no 't'"));
  j = *file_;
  j["waypoints"][1]["s"] = 3.0;
  EXPECT_THAT(error_of([&] { read_bounds_trajectory(write("s.json", j), *scene_); }),
              HasSubstr("'s' 3 is not its index 1"));
}

TEST_F(BoundsFormatTest, CfThroughTheFileIsTheCfOfTheBounds) {
  const std::string path = write("b.json", *file_);
  CfParams p;
  p.windows = 4;
  p.samples = 50;
  const CfResult a = confidence_factor(*scene_, read_bounds(path, *scene_), p, 2);
  const CfResult b = confidence_factor(*scene_, read_bounds_trajectory(path, *scene_), p, 2);
  EXPECT_EQ(a.window_cf, b.window_cf);
  EXPECT_EQ(a.obstacle_collisions, b.obstacle_collisions);
  EXPECT_EQ(a.duration, b.duration);
}

// --- Exports ---

using test::read_text;

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

TEST(StagesExport, CsvHasUnitsColumnsAndOneRowPerStage) {
  test::TempDir dir;
  const std::string out = (dir.path() / "s.csv").string();
  write_stages(four_waypoints(), {"a", "b"}, 2, StagesFormat::kCsv, out, "in.json");
  const auto lines = lines_of(read_text(out));
  ASSERT_EQ(lines.size(), 2u + 4u);  // units, header, t = 0, 2, 4, 5
  EXPECT_THAT(lines[0], HasSubstr("# leeway sample of in.json: t [s]"));
  EXPECT_EQ(lines[1], "t,s,nominal_a,lower_a,upper_a,nominal_b,lower_b,upper_b");
  EXPECT_EQ(lines[2], "0,0,0,-0.1,0.2,1,0.5,1.5");
  // t = 2 s: waypoint 2 (the later of the two reached at 2 s), s = 2.
  EXPECT_EQ(lines[3], "2,2,1,0.8,1.4,0,-0.4,0.2");
  EXPECT_EQ(lines[5], "5,3,4,3,4.5,-1,-1.5,-0.5");
}

TEST(StagesExport, JsonHasEveryStage) {
  test::TempDir dir;
  const std::string out = (dir.path() / "s.json").string();
  write_stages(four_waypoints(), {"a", "b"}, 2.5, StagesFormat::kJson, out, "in.json");
  const auto j = nlohmann::json::parse(read_text(out));
  EXPECT_EQ(j.at("format"), "leeway-stages-1");
  ASSERT_EQ(j.at("stages").size(), 3u);
  EXPECT_EQ(j["stages"][1]["t"], 2.5);
  EXPECT_EQ(j["stages"][1]["s"], 2.0 + 0.5 / 3.0);
  EXPECT_EQ(j["stages"][2]["upper"], (std::vector<double>{4.5, -0.5}));
}

// An independent reader of what numpy.load needs: zip local headers (stored), CRC-32 (bitwise, the
// zip polynomial) and .npy version 1.0 headers.
struct NpyArray {
  std::string descr, shape;
  std::string data;
};

std::uint32_t le32(const std::string& s, size_t at) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(s[at])) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(s[at + 1])) << 8 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(s[at + 2])) << 16 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(s[at + 3])) << 24;
}
unsigned le16(const std::string& s, size_t at) {
  return static_cast<unsigned>(static_cast<unsigned char>(s[at])) |
         static_cast<unsigned>(static_cast<unsigned char>(s[at + 1])) << 8;
}
std::uint32_t crc32_bitwise(const std::string& s) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (unsigned char b : s) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return ~c;
}

std::map<std::string, NpyArray> read_npz(const std::string& bytes) {
  std::map<std::string, NpyArray> out;
  size_t at = 0;
  while (at + 30 <= bytes.size() && le32(bytes, at) == 0x04034b50) {
    const std::uint32_t crc = le32(bytes, at + 14), size = le32(bytes, at + 18);
    const unsigned name_len = le16(bytes, at + 26), extra = le16(bytes, at + 28);
    EXPECT_EQ(le16(bytes, at + 8), 0u) << "stored";
    const std::string name = bytes.substr(at + 30, name_len);
    const std::string npy = bytes.substr(at + 30 + name_len + extra, size);
    EXPECT_EQ(crc32_bitwise(npy), crc) << name;
    EXPECT_EQ(npy.substr(0, 8), std::string("\x93NUMPY\x01\x00", 8)) << name;
    const unsigned header_len = le16(npy, 8);
    EXPECT_EQ((10 + header_len) % 64, 0u) << name;
    const std::string header = npy.substr(10, header_len);
    NpyArray a;
    a.descr = header.substr(header.find("'descr': '") + 10);
    a.descr = a.descr.substr(0, a.descr.find('\''));
    a.shape = header.substr(header.find("'shape': ") + 9);
    a.shape = a.shape.substr(0, a.shape.find(')') + 1);
    a.data = npy.substr(10 + header_len);
    out[name] = a;
    at += 30 + name_len + extra + size;
  }
  EXPECT_EQ(le32(bytes, at), 0x02014b50u) << "the central directory follows the entries";
  return out;
}

double double_at(const std::string& data, size_t i) {
  double v;
  std::memcpy(&v, data.data() + 8 * i, 8);
  return v;
}

TEST(StagesExport, NpzIsAZipOfNpyArraysNumpyReads) {
  test::TempDir dir;
  const std::string out = (dir.path() / "s.npz").string();
  write_stages(four_waypoints(), {"a", "b"}, 2, StagesFormat::kNpz, out, "in.json");
  const auto arrays = read_npz(read_text(out));
  ASSERT_EQ(arrays.size(), 6u);
  EXPECT_EQ(arrays.at("t.npy").shape, "(4,)");
  EXPECT_EQ(arrays.at("lower.npy").shape, "(4, 2)");
  EXPECT_EQ(arrays.at("lower.npy").descr, "<f8");
  EXPECT_EQ(double_at(arrays.at("t.npy").data, 3), 5.0);
  EXPECT_EQ(double_at(arrays.at("s.npy").data, 1), 2.0);
  // Row 0, joint 1 of upper; row 3, joint 0 of lower (row-major).
  EXPECT_EQ(double_at(arrays.at("upper.npy").data, 1), 1.5);
  EXPECT_EQ(double_at(arrays.at("lower.npy").data, 6), 3.0);
  EXPECT_EQ(arrays.at("joints.npy").descr, "<U1");
  EXPECT_EQ(arrays.at("joints.npy").data, std::string("a\0\0\0b\0\0\0", 8));
}

TEST(StagesExport, DrakeYamlBoxesAndSegments) {
  const std::string y = drake_yaml(four_waypoints(), {"a", "b"}, true, "in.json");
  // Waypoint 0: A = [I; -I], b = [upper; -lower].
  EXPECT_THAT(y,
              HasSubstr("waypoint_000:\n  ambient_dimension: 2\n  A:\n  - [1, 0]\n  - [0, 1]\n  - [-1, 0]\n"
                        "  - [0, -1]\n  b: [0.2, 1.5, 0.1, -0.5]\n"));
  // Segment 2 (waypoint 2 to 3) over (q_a, q_b, f): q_a - (4.5 - 1.4) f <= 1.4, -q_a + (3 - 0.8) f <=
  // -0.8, then f <= 1 and -f <= 0.
  EXPECT_THAT(y, HasSubstr("segment_002:\n  ambient_dimension: 3\n  A:\n  - [1, 0, -3.1]\n"));
  EXPECT_THAT(y, HasSubstr("  - [-1, 0, 2.2]\n"));
  EXPECT_THAT(y, HasSubstr("  - [0, 0, 1]\n  - [0, 0, -1]\n  b: [1.4, 0.2, -0.8, 0.4, 1, 0]\n"));
  EXPECT_THAT(y, ::testing::Not(HasSubstr("segment_003")));
}

TEST(StagesExport, RefusesABadStepAndWritesNothing) {
  test::TempDir dir;
  const std::string out = (dir.path() / "s.csv").string();
  EXPECT_THAT(error_of([&] {
                write_stages(four_waypoints(), {"a", "b"}, 0, StagesFormat::kCsv, out, "x");
              }),
              HasSubstr("must be a positive number"));
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_THAT(error_of([&] { write_stages(four_waypoints(), {"a"}, 1, StagesFormat::kCsv, out, "x"); }),
              HasSubstr("1 joint names for bounds of 2 joints"));
  EXPECT_THAT(error_of([&] { stages_format_of("x.txt"); }), HasSubstr("must end in .csv"));
}

}  // namespace
}  // namespace leeway
