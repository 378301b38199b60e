// The whole method on one path: keyframe paths, cell defaults, the bounds file and atomic writes.
#include "leeway/core/pipeline.hpp"
#include "leeway/core/cell_defaults.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/io/bounds_file.hpp"
#include "leeway/path/nominal_path.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>
#include <string>

#include "leeway/core/error.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using nlohmann::json;
using test::one_link_cell;
using test::workcell;
using ::testing::HasSubstr;
using ::testing::Not;

//! The message of the InputError that f throws, or "" (and a test failure) when it does not throw.
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError thrown";
  return "";
}

std::vector<std::string> folder_entries(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

class PipelineTest : public test::MujocoTest {};

TEST_F(PipelineTest, KeyframePathIsJointLinear) {
  // Dallara home = 0; patch = (-1.11219, 0.734922, 0.0866255, -3.14159, -0.749248, -1.11219).
  const Scene scene = Scene::load(workcell("dallara"));
  const auto path = keyframe_path(scene, "home", "patch", 3);
  ASSERT_EQ(path.size(), 3u);
  Eigen::VectorXd patch(6), mid(6);
  patch << -1.11219, 0.734922, 0.0866255, -3.14159, -0.749248, -1.11219;
  mid << -0.556095, 0.367461, 0.04331275, -1.570795, -0.374624, -0.556095;  // patch / 2
  EXPECT_EQ(path[0], Eigen::VectorXd::Zero(6));
  EXPECT_LT((path[1] - mid).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((path[2] - patch).cwiseAbs().maxCoeff(), 1e-12);
  // Two waypoints: the thesis's paths, just the end points.
  const auto ends = keyframe_path(scene, "patch", "home", 2);
  ASSERT_EQ(ends.size(), 2u);
  EXPECT_LT((ends[0] - patch).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(ends[1], Eigen::VectorXd::Zero(6));
}

TEST_F(PipelineTest, KeyframePathRejectsUnknownNamesAndTooFewWaypoints) {
  const Scene scene = Scene::load(workcell("dallara"));
  std::string msg = error_of([&] { keyframe_path(scene, "home", "nowhere", 3); });
  EXPECT_THAT(msg, HasSubstr("'nowhere'"));
  EXPECT_THAT(msg, HasSubstr("'home', 'patch', 'mould'"));
  msg = error_of([&] { keyframe_path(scene, "elsewhere", "home", 3); });
  EXPECT_THAT(msg, HasSubstr("'elsewhere'"));
  msg = error_of([&] { keyframe_path(scene, "home", "patch", 1); });
  EXPECT_THAT(msg, HasSubstr("1"));
  EXPECT_THAT(msg, HasSubstr(">= 2"));
  EXPECT_THAT(msg, HasSubstr("waypoint count 1"));
  EXPECT_THAT(msg, Not(HasSubstr("--")));  // the library names values, the programs their flags
  EXPECT_THROW(keyframe_path(scene, "home", "patch", 0), InputError);
  EXPECT_THROW(keyframe_path(scene, "home", "patch", -3), InputError);
}

TEST_F(PipelineTest, CellDefaultsComeFromTheCustomBlock) {
  // dlr.xml: leeway_reach_radius 3.0, leeway_add_obstacle_boxes 1; dallara.xml: reach 2.8 only.
  Params p;
  p.volume.reach_radius = 1.0;
  apply_cell_defaults(Scene::load(workcell("dlr")), p);
  EXPECT_EQ(p.volume.reach_radius, 3.0);
  EXPECT_TRUE(p.volume.add_obstacle_boxes);

  Params q;
  q.volume.reach_radius = 1.0;
  apply_cell_defaults(Scene::load(workcell("dallara")), q);
  EXPECT_EQ(q.volume.reach_radius, 2.8);
  EXPECT_FALSE(q.volume.add_obstacle_boxes);
  // A numeric the cell does not have leaves the value as it was.
  Params r;
  r.volume.add_obstacle_boxes = true;
  apply_cell_defaults(Scene::load(workcell("dallara")), r);
  EXPECT_TRUE(r.volume.add_obstacle_boxes);
}

TEST_F(PipelineTest, CellDefaultsRejectBadNumerics) {
  test::TempDir dir;
  auto cell = [&](const std::string& custom) {
    std::string xml = one_link_cell("");
    xml.insert(xml.find("<worldbody>"), "<custom>" + custom + "</custom>\n  ");
    return Scene::load(dir.write("cell.xml", xml));
  };
  Params p;
  EXPECT_THAT(
      error_of([&] { apply_cell_defaults(cell(R"(<numeric name="leeway_reach_radius" data="-1"/>)"), p); }),
      HasSubstr("leeway_reach_radius' = -1"));
  EXPECT_THAT(error_of([&] {
                apply_cell_defaults(cell(R"(<numeric name="leeway_add_obstacle_boxes" data="2"/>)"), p);
              }),
              HasSubstr("leeway_add_obstacle_boxes' = 2"));
  apply_cell_defaults(cell(R"(<numeric name="leeway_reach_radius" data="1.25"/>)"), p);
  EXPECT_EQ(p.volume.reach_radius, 1.25);
}

class BoundsFileTest : public test::MujocoTest {
 protected:
  void SetUp() override {
    test::MujocoTest::SetUp();
    scene_ = std::make_unique<Scene>(Scene::load(workcell("dallara")));
    apply_cell_defaults(*scene_, params_);
    params_.height_map.max_cells = 300;
    VolumeModel world(*scene_, 300 + static_cast<int>(scene_->obstacle_geoms().size()));
    run_ = compute_bounds(*scene_, world, keyframe_path(*scene_, "home", "patch", 2), params_, 2);
    file_ = bounds_json(*scene_, run_, params_);
  }
  //! Writes `j` to `name` in the temporary folder and returns its path.
  std::string write(const std::string& name, const json& j) {
    const std::string path = (dir_.path() / name).string();
    write_file_atomic(path, j.dump(2));
    return path;
  }
  std::unique_ptr<Scene> scene_;
  Params params_;
  BoundsRun run_;
  json file_;
  test::TempDir dir_;
};

TEST_F(BoundsFileTest, HasTheDocumentedKeys) {
  EXPECT_EQ(file_.at("joints"), json({"j1", "j2", "j3", "j4", "j5", "j6"}));
  ASSERT_EQ(file_.at("waypoints").size(), 2u);
  for (const auto& w : file_.at("waypoints"))
    for (const char* key : {"q", "lower", "upper"}) EXPECT_EQ(w.at(key).size(), 6u) << key;
  // Values as computed: waypoint 1's nominal is the patch keyframe.
  EXPECT_NEAR(file_.at("waypoints")[1].at("q")[0].get<double>(), -1.11219, 1e-12);
  EXPECT_EQ(file_.at("boxes").get<size_t>(), run_.volume.boxes.size());
  EXPECT_EQ(file_.at("max_cells").get<int>(), 300);
  const auto& t = file_.at("timing_ms");
  for (const char* key : {"volume", "bounds", "total"}) {
    EXPECT_TRUE(t.at(key).is_number()) << key;
    EXPECT_GE(t.at(key).get<double>(), 0.0) << key;
  }
  EXPECT_GE(t.at("total").get<double>(), t.at("volume").get<double>() + t.at("bounds").get<double>());
  EXPECT_EQ(file_.at("joint_bounding"),
            json({"bisected", "bisected", "bisected", "fixed", "fixed", "fixed"}));
}

TEST_F(BoundsFileTest, ReadsBackWhatWasWritten) {
  const std::string path = write("b.json", file_);
  const auto back = read_bounds(path, *scene_);
  ASSERT_EQ(back.size(), run_.bounds.size());
  for (size_t i = 0; i < back.size(); ++i) {
    EXPECT_EQ(back[i].q, run_.bounds[i].q) << i;  // JSON keeps 17 significant digits: exact
    EXPECT_EQ(back[i].lower, run_.bounds[i].lower) << i;
    EXPECT_EQ(back[i].upper, run_.bounds[i].upper) << i;
    EXPECT_EQ(back[i].collapsed.size(), 6u);
  }
}

TEST_F(BoundsFileTest, ReadRejectsFilesThatDoNotFit) {
  const std::string good = write("b.json", file_);
  // Another cell's robot: the DLR arm has rail_x in front of j1..j6.
  const Scene dlr = Scene::load(workcell("dlr"));
  std::string msg = error_of([&] { read_bounds(good, dlr); });
  EXPECT_THAT(msg, HasSubstr(good));
  EXPECT_THAT(msg, HasSubstr("j1 j2 j3 j4 j5 j6"));
  EXPECT_THAT(msg, HasSubstr("dlr.xml"));

  const std::string missing = (dir_.path() / "absent.json").string();
  msg = error_of([&] { read_bounds(missing, *scene_); });
  EXPECT_THAT(msg, HasSubstr(missing));

  const std::string malformed = dir_.write("malformed.json", R"({"joints": ["j1", )");
  msg = error_of([&] { read_bounds(malformed, *scene_); });
  EXPECT_THAT(msg, HasSubstr(malformed));
  EXPECT_THAT(msg, HasSubstr("malformed JSON"));

  json five = file_;
  five["waypoints"][1]["lower"].erase(5);
  const std::string five_path = write("five.json", five);
  msg = error_of([&] { read_bounds(five_path, *scene_); });
  EXPECT_THAT(msg, HasSubstr(five_path));
  EXPECT_THAT(msg, HasSubstr("waypoint 1 'lower' has 5 values"));

  json above = file_;
  const double q0 = above["waypoints"][0]["q"][2].get<double>();
  above["waypoints"][0]["lower"][2] = q0 + 0.1;
  const std::string above_path = write("above.json", above);
  msg = error_of([&] { read_bounds(above_path, *scene_); });
  EXPECT_THAT(msg, HasSubstr(above_path));
  EXPECT_THAT(msg, HasSubstr("waypoint 0 joint 'j3'"));

  json no_waypoints = file_;
  no_waypoints.erase("waypoints");
  const std::string nw_path = write("nowp.json", no_waypoints);
  EXPECT_THAT(error_of([&] { read_bounds(nw_path, *scene_); }), HasSubstr(nw_path));

  json text_value = file_;
  text_value["waypoints"][0]["upper"][0] = "wide";
  const std::string tv_path = write("text.json", text_value);
  EXPECT_THAT(error_of([&] { read_bounds(tv_path, *scene_); }), HasSubstr(tv_path));
}

TEST_F(BoundsFileTest, ReadKeepsTheCollapsedJoints) {
  json marked = file_;
  marked["waypoints"][0]["collapsed"] = {"j2"};
  marked["waypoints"][1]["collapsed"] = json::array({"j1", "j3"});
  const auto back = read_bounds(write("collapsed.json", marked), *scene_);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].collapsed, std::vector<bool>({false, true, false, false, false, false}));
  EXPECT_EQ(back[1].collapsed, std::vector<bool>({true, false, true, false, false, false}));

  // What bounds_json wrote comes back as it was.
  const auto same = read_bounds(write("same.json", file_), *scene_);
  for (size_t i = 0; i < same.size(); ++i) EXPECT_EQ(same[i].collapsed, run_.bounds[i].collapsed) << i;

  json unknown = file_;
  unknown["waypoints"][0]["collapsed"] = {"j9"};
  const std::string path = write("unknown.json", unknown);
  const std::string msg = error_of([&] { read_bounds(path, *scene_); });
  EXPECT_THAT(msg, HasSubstr(path));
  EXPECT_THAT(msg, HasSubstr("'j9'"));
}

TEST_F(BoundsFileTest, ReadChecksTheFormat) {
  EXPECT_EQ(file_.at("format"), kBoundsFormat);
  json other = file_;
  other["format"] = "leeway-path-1";
  const std::string path = write("path.json", other);
  const std::string msg = error_of([&] { read_bounds(path, *scene_); });
  EXPECT_THAT(msg, HasSubstr(path));
  EXPECT_THAT(msg, HasSubstr("\"leeway-path-1\""));
  EXPECT_THAT(msg, HasSubstr("leeway-bounds-1"));
  json number = file_;
  number["format"] = 1;
  EXPECT_THAT(error_of([&] { read_bounds(write("number.json", number), *scene_); }), HasSubstr("format 1"));
  // Files written before the format key existed are still read.
  json old = file_;
  old.erase("format");
  EXPECT_EQ(read_bounds(write("old.json", old), *scene_).size(), 2u);
}

TEST(WriteFileAtomicTest, MissingFolderThrowsAndLeavesNothing) {
  test::TempDir dir;
  const auto target = dir.path() / "no_such_folder" / "out.json";
  const std::string msg = error_of([&] { write_file_atomic(target.string(), "{}"); });
  EXPECT_THAT(msg, HasSubstr(target.string()));
  EXPECT_FALSE(std::filesystem::exists(target));
  EXPECT_TRUE(folder_entries(dir.path()).empty());
}

TEST(WriteFileAtomicTest, SuccessLeavesOnlyTheTarget) {
  test::TempDir dir;
  const auto target = dir.path() / "out.csv";
  write_file_atomic(target.string(), "a,b\n1,2\n");
  EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"out.csv"});
  std::ifstream in(target);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "a,b\n1,2\n");
  // Replacing an existing file.
  write_file_atomic(target.string(), "x\n");
  EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"out.csv"});
  std::ifstream again(target);
  std::string line;
  std::getline(again, line);
  EXPECT_EQ(line, "x");
}

}  // namespace
}  // namespace leeway
