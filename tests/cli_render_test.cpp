// The picture subcommands as a user runs them: leeway render, leeway plot, sweep --plot
// and bounds --export-mjcf/--export-mjb; their files, and their bad input (exit 2, nothing written).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "leeway/core/error.hpp"
#include "leeway/core/scene.hpp"
#include "leeway/viz/export_mjcf.hpp"
#include "leeway/viz/plot.hpp"
#include "leeway/viz/render.hpp"
#include "png_util.hpp"
#include "test_util.hpp"

namespace leeway {
namespace {

using test::run_cli;
using test::workcell;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

// Counts, with python3's XML parser, the elements of an SVG file matching each XPath (ElementTree's
// subset, SVG namespace as "s:"); "error" when the file does not parse.
std::string svg_counts(const std::string& file, const std::vector<std::string>& paths) {
  std::string list;
  for (const auto& p : paths) list += (list.empty() ? "" : ",") + ("\"" + p + "\"");
  const std::string script =
      "import sys, xml.etree.ElementTree as E\n"
      "ns = {'s': 'http://www.w3.org/2000/svg'}\n"
      "try:\n"
      "    r = E.parse(sys.argv[1]).getroot()\n"
      "except E.ParseError as e:\n"
      "    print('error', e); sys.exit(0)\n"
      "print(' '.join(str(len(r.findall(p, ns))) for p in [" +
      list + "]))\n";
  test::TempDir dir;
  const std::string py = dir.write("count.py", script);
  return test::run_program("python3", py + " " + file).out;
}

class CliRenderTest : public test::MujocoTest {
 protected:
  //! Bounds home -> patch on the Dallara cell with the thesis's parameters at MAX_cells 2000.
  std::string bounds_file(const std::string& extra = "") {
    const std::string out = path("b.json");
    if (!fs::exists(out)) {
      const auto r =
          run_cli("bounds " + workcell("dallara") +
                  " --from home --to patch --preset thesis --max-cells 2000 --out " + out + " " + extra);
      EXPECT_EQ(r.exit_code, 0) << r.out;
    }
    return out;
  }
  std::string path(const std::string& name) const { return (dir_.path() / name).string(); }
  test::TempDir dir_;
};

TEST_F(CliRenderTest, VolumeColourWhereAVolumeBoxProjectsAndNotWithVolumeOff) {
  const std::string b = bounds_file();
  const std::string camera = " --size 320x240 --camera 0,-1.5,14 --lookat 0,0,0 --legend off";
  const auto on = run_cli("render " + workcell("dallara") + " --bounds " + b + " --out " + path("on.png") +
                          camera + " --volume on");
  ASSERT_EQ(on.exit_code, 0) << on.out;
  EXPECT_THAT(on.out, HasSubstr("320x240 pixels"));
  const auto off = run_cli("render " + workcell("dallara") + " --bounds " + b + " --out " + path("off.png") +
                           camera + " --volume off");
  ASSERT_EQ(off.exit_code, 0) << off.out;
  EXPECT_EQ(png_size(path("on.png")), (std::array<int, 2>{320, 240}));
  const Image img_on = test::read_png(path("on.png")), img_off = test::read_png(path("off.png"));

  // The volume the render drew, regenerated from the bounds file; its highest box is the yellow end
  // of the colour scale. Check the boxes from the highest down whose top centre falls on bare floor
  // in the render without the volume (grey: the robot and tables are orange and brown).
  const Scene scene = Scene::load(workcell("dallara"));
  const BoundsFileVolume v = read_bounds_volume(b, scene);
  ASSERT_EQ(static_cast<int>(v.volume.boxes.size()), v.recorded_boxes);
  std::vector<Box> boxes = v.volume.boxes;
  double max_top = 0;
  for (const Box& box : boxes) max_top = std::max(max_top, box.center.z() + box.half_size.z());
  std::sort(boxes.begin(), boxes.end(), [](const Box& p, const Box& q) {
    return p.center.z() + p.half_size.z() > q.center.z() + q.half_size.z();
  });
  RenderCamera cam;
  cam.azimuth = 0;
  cam.elevation = -1.5;
  cam.distance = 14;
  cam.lookat = Eigen::Vector3d::Zero();
  const double fovy = scene.model().vis.global.fovy * kPi / 180;
  int checked = 0;
  for (const Box& box : boxes) {
    Eigen::Vector2d px;
    const Eigen::Vector3d top = box.center + Eigen::Vector3d(0, 0, box.half_size.z());
    if (!project_point(cam, fovy, 320, 240, top, px)) continue;
    const int x = static_cast<int>(px.x()), y = static_cast<int>(px.y());
    if (x < 2 || x >= 318 || y < 2 || y >= 238) continue;
    const auto floor = img_off.at(x, y);
    if (std::max({floor[0], floor[1], floor[2]}) - std::min({floor[0], floor[1], floor[2]}) > 12) continue;
    // Volume on: the pixel moves from the floor's grey towards the box's colour.
    const auto c = height_colour(top.z(), max_top);
    const auto p = img_on.at(x, y);
    double d_on = 0, d_off = 0;
    for (size_t k = 0; k < 3; ++k) {
      d_on += std::pow(p[k] - 255.0 * c[k], 2);
      d_off += std::pow(floor[k] - 255.0 * c[k], 2);
    }
    EXPECT_LT(std::sqrt(d_on), std::sqrt(d_off) - 25)
        << "box at (" << box.center.transpose() << ") pixel " << x << "," << y << ": on " << int{p[0]} << " "
        << int{p[1]} << " " << int{p[2]} << ", off " << int{floor[0]} << " " << int{floor[1]} << " "
        << int{floor[2]};
    if (++checked == 5) break;
  }
  EXPECT_EQ(checked, 5);
}

TEST_F(CliRenderTest, FromToComputesTheBoundsAndBareCellRenders) {
  const auto r =
      run_cli("render " + workcell("dallara") +
              " --from home --to patch --preset thesis --max-cells 500 --waypoint 0 --size 64x48 --out " +
              path("ft.png"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("waypoint 0 of home -> patch"));
  EXPECT_EQ(png_size(path("ft.png")), (std::array<int, 2>{64, 48}));
  const auto bare =
      run_cli("render " + workcell("dallara") + " --key patch --size 80x60 --out " + path("bare.png"));
  ASSERT_EQ(bare.exit_code, 0) << bare.out;
  EXPECT_THAT(bare.out, HasSubstr("0 volume boxes"));
  EXPECT_EQ(png_size(path("bare.png")), (std::array<int, 2>{80, 60}));
}

// --strip K: K frames at evenly spaced nominal times side by side. The first is at t = 0, the
// first waypoint's box value for value, and the last at the end, the last waypoint's: with the same
// camera they are the pictures of --waypoint 0 and --waypoint 1, pixel for pixel.
TEST_F(CliRenderTest, StripFramesAreThePathsWaypointsAtItsEnds) {
  const std::string b = bounds_file();
  const std::string cell = workcell("dallara");
  const std::string camera = " --camera -2.4,-0.9,9 --lookat 0.5,-0.5,1.5";
  const auto strip = run_cli("render " + cell + " --bounds " + b + " --strip 3 --size 240x80 --out " +
                             path("strip.png") + camera);
  ASSERT_EQ(strip.exit_code, 0) << strip.out;
  EXPECT_THAT(strip.out, HasSubstr("3 frames along"));
  EXPECT_EQ(png_size(path("strip.png")), (std::array<int, 2>{240, 80}));
  const Image s = test::read_png(path("strip.png"));
  for (int w : {0, 1}) {
    const std::string out = path("w" + std::to_string(w) + ".png");
    const auto one = run_cli("render " + cell + " --bounds " + b + " --waypoint " + std::to_string(w) +
                             " --size 80x80 --out " + out + camera);
    ASSERT_EQ(one.exit_code, 0) << one.out;
    const Image single = test::read_png(out);
    const int x0 = w == 0 ? 0 : 160;
    int differ = 0;
    for (int y = 0; y < 80; ++y)
      for (int x = 0; x < 80; ++x) differ += s.at(x0 + x, y) != single.at(x, y) ? 1 : 0;
    EXPECT_EQ(differ, 0) << "waypoint " << w;
  }
  // The middle frame is neither end: the arm is half way.
  int middle = 0;
  for (int y = 0; y < 80; ++y)
    for (int x = 0; x < 80; ++x) middle += s.at(80 + x, y) != s.at(160 + x, y) ? 1 : 0;
  EXPECT_GT(middle, 0);
}

// The legend band (on by default from 320 x 176 pixels) fills the image's last 56 rows: the colour
// scale starts at the lowest height's colour at (11, 240 + 14) of a 400 x 300 picture.
TEST_F(CliRenderTest, LegendBandUnderThePicture) {
  const std::string b = bounds_file();
  const auto r =
      run_cli("render " + workcell("dallara") + " --bounds " + b + " --size 400x300 --out " + path("l.png"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const Image img = test::read_png(path("l.png"));
  ASSERT_EQ(img.height, 300);
  const BoundsFileVolume v = read_bounds_volume(b, Scene::load(workcell("dallara")));
  double top = 0;
  for (const Box& box : v.volume.boxes) top = std::max(top, box.center.z() + box.half_size.z());
  const auto c = height_colour(0.5 / 64 * top, top);
  const auto px = img.at(11, 300 - kLegendHeight + 14);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(px[static_cast<size_t>(k)], 255 * c[static_cast<size_t>(k)], 3) << k;
  // Without it the picture reaches the last row: no white band there.
  const auto off = run_cli("render " + workcell("dallara") + " --bounds " + b +
                           " --size 400x300 --legend off --out " + path("n.png"));
  ASSERT_EQ(off.exit_code, 0) << off.out;
  const Image none = test::read_png(path("n.png"));
  EXPECT_NE(none.at(11, 300 - kLegendHeight + 14), img.at(11, 300 - kLegendHeight + 14));
}

// --video: an MP4 beside the picture, a frame every 1/30 s of nominal time from 0 and one at the
// path's end (the bounds file's last waypoint time).
TEST_F(CliRenderTest, VideoAlongThePathAtThirtyFramesPerSecond) {
  if (std::system("command -v ffmpeg > /dev/null 2>&1") != 0) GTEST_SKIP() << "ffmpeg is not installed";
  const std::string b = bounds_file();
  const auto r = run_cli("render " + workcell("dallara") + " --bounds " + b + " --size 160x120 --video " +
                         path("v.mp4") + " --out " + path("v.png"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const double duration = test::read_json(b).at("waypoints").back().at("t").get<double>();
  int frames = 1;  // the end
  for (int j = 0; j / 30.0 < duration - 1e-9; ++j) ++frames;
  EXPECT_THAT(r.out, HasSubstr("(" + std::to_string(frames) + " frames at 30 fps"));
  const std::string bytes = test::read_text(path("v.mp4"));
  ASSERT_GT(bytes.size(), 1000u);
  EXPECT_EQ(bytes.substr(4, 4), "ftyp");
  EXPECT_EQ(png_size(path("v.png")), (std::array<int, 2>{160, 120}));
}

TEST(TileTest, SideBySideRowByRow) {
  Image a, b;
  a.width = 1;
  a.height = 2;
  a.rgb = {1, 1, 1, 2, 2, 2};
  b.width = 2;
  b.height = 2;
  b.rgb = {3, 3, 3, 4, 4, 4, 5, 5, 5, 6, 6, 6};
  const Image t = tile_horizontally({a, b});
  EXPECT_EQ(t.width, 3);
  EXPECT_EQ(t.height, 2);
  EXPECT_EQ(t.rgb, (std::vector<unsigned char>{1, 1, 1, 3, 3, 3, 4, 4, 4, 2, 2, 2, 5, 5, 5, 6, 6, 6}));
  b.height = 1;
  b.rgb.resize(6);
  EXPECT_THROW(tile_horizontally({a, b}), InputError);
  EXPECT_THROW(tile_horizontally({}), InputError);
}

// The same picture whatever the thread count and whether the bounds come from a file: the boxes
// added to MuJoCo's scene once kept what the heap held in the sorter's fields, and the thesis
// preset's translucent volume came out other with --threads 1 than with 2.
TEST_F(CliRenderTest, SamePictureForOneAndTwoThreadsAndFromTheFile) {
  const std::string cell = workcell("example");
  const std::string common = " --preset thesis --size 320x240 --out ";
  const auto one = run_cli("render " + cell + " --from home --to pick --threads 1" + common + path("t1.png"));
  ASSERT_EQ(one.exit_code, 0) << one.out;
  const auto two = run_cli("render " + cell + " --from home --to pick --threads 2" + common + path("t2.png"));
  ASSERT_EQ(two.exit_code, 0) << two.out;
  const auto b = run_cli("bounds " + cell + " --from home --to pick --preset thesis --out " + path("b.json"));
  ASSERT_EQ(b.exit_code, 0) << b.out;
  const auto file = run_cli("render " + cell + " --bounds " + path("b.json") + common + path("f.png"));
  ASSERT_EQ(file.exit_code, 0) << file.out;
  const std::string t1 = test::read_text(path("t1.png"));
  EXPECT_FALSE(t1.empty());
  EXPECT_TRUE(t1 == test::read_text(path("t2.png"))) << "--threads 1 and 2 give other PNGs";
  EXPECT_TRUE(t1 == test::read_text(path("f.png"))) << "--from/--to and --bounds give other PNGs";
}

TEST_F(CliRenderTest, BadInputExitsTwoAndWritesNothing) {
  const std::string b = bounds_file();
  const std::string out = path("bad.png");
  const std::string cell = workcell("dallara") + " --bounds " + b;
  struct Case {
    std::string args, message;
  };
  const std::vector<Case> cases = {
      {cell + " --out /nonexistent-folder/x.png", "cannot write there"},
      {cell + " --out " + path("x.jpg"), "must end in .png"},
      {cell + " --out " + out + " --waypoint 7", "--waypoint 7: " + b + " has 2 waypoints (0 .. 1)"},
      {cell + " --out " + out + " --waypoint -2", "--waypoint: '-2' must be a waypoint index, 0 or more"},
      {workcell("baltico") + " --bounds " + b + " --out " + out, "computed for another cell"},
      {cell + " --out " + out + " --size 12x", "--size '12x' must be WIDTHxHEIGHT"},
      {cell + " --out " + out + " --size 8x8", "from 16 to 8192"},
      {cell + " --out " + out + " --camera 1,nan,3", "--camera"},
      {cell + " --out " + out + " --camera 1,2", "must be three numbers"},
      {cell + " --out " + out + " --camera 1,-2,3", "elevation -2 rad"},
      {cell + " --out " + out + " --camera 1,-1,0", "distance 0 m must be > 0"},
      {cell + " --out " + out + " --lookat 0,0,inf", "--lookat"},
      {cell + " --out " + out + " --volume maybe", "--volume 'maybe' must be fade, on or off"},
      {cell + " --out " + out + " --frame nowhere", "--frame 'nowhere' must be robot or volume"},
      {cell + " --out " + out + " --legend maybe", "--legend 'maybe' must be on or off"},
      {cell + " --out " + out + " --video " + path("v.avi"), "must end in .mp4"},
      {cell + " --out " + out + " --video " + path("v.mp4") + " --size 161x120", "must be even"},
      {workcell("dallara") + " --out " + out + " --video " + path("v.mp4"), "there is no path"},
      {workcell("dallara") + " --out " + out + " --strip 3",
       "--strip 3: there is no path without --bounds or --from/--to"},
      {cell + " --out " + out + " --strip 1", "--strip 1 must be within 2 .. 64"},
      {cell + " --out " + out + " --strip 3 --waypoint 0", "not with --waypoint 0"},
      {cell + " --out " + out + " --strip 3 --size 40x40", "frames 13 pixels wide"},
      {cell + " --out " + out + " --ghosts all", "--ghosts 'all'"},
      {workcell("dallara") + " --from home --to nowhere --out " + out, "nowhere"},
      {workcell("dallara") + " --from home --to patch --waypoint 2 --out " + out,
       "--waypoint 2: the path has 2"},
  };
  for (const auto& c : cases) {
    const auto r = run_cli("render " + c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.out;
    EXPECT_THAT(r.out, HasSubstr(c.message)) << c.args;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
}

TEST_F(CliRenderTest, PlotSvgParsesWithOneCurveSetPerJointAndPngHasItsSize) {
  const std::string b = bounds_file();
  const auto r = run_cli("plot " + b + " --out " + path("p.svg"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  // Six joint panels; each has one lower, one nominal and one upper curve.
  EXPECT_EQ(svg_counts(path("p.svg"),
                       {".//s:g[@class='joint']", ".//s:g[@class='joint']/s:polyline[@class='lower']",
                        ".//s:g[@class='joint']/s:polyline[@class='nominal']",
                        ".//s:g[@class='joint']/s:polyline[@class='upper']"}),
            "6 6 6 6\n");
  const auto png = run_cli("plot " + b + " --out " + path("p.png"));
  ASSERT_EQ(png.exit_code, 0) << png.out;
  EXPECT_EQ(png_size(path("p.png")), (std::array<int, 2>{1000, 60 + 3 * 240}));
  const auto sized = run_cli("plot " + b + " --out " + path("q.png") + " --size 640x560");
  ASSERT_EQ(sized.exit_code, 0) << sized.out;
  EXPECT_EQ(png_size(path("q.png")), (std::array<int, 2>{640, 560}));
}

TEST_F(CliRenderTest, PlotMarksShrunkAndCollapsedIntervals) {
  // A hand-made two-joint file: joint a shrunk by the safety stage at waypoint 1, joint b collapsed
  // at waypoint 0.
  const std::string b =
      dir_.write("h.json", R"({"joints": ["a", "b"], "joint_bounding": ["bisected", "linear_axis"],
    "waypoints": [
      {"q": [0, 0], "lower": [-1, -0.01], "upper": [1, 0.01], "collapsed": ["b"]},
      {"q": [0.5, 0.1], "lower": [0.2, 0], "upper": [0.9, 0.2], "guide_lower": [0, 0], "guide_upper": [1, 0.2]}]})");
  const auto r = run_cli("plot " + b + " --out " + path("h.svg"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(
      svg_counts(path("h.svg"), {".//s:g[@class='joint']", ".//s:polyline[@class='guide-lower']",
                                 ".//s:circle[@class='collapsed']", ".//s:g[@data-joint='b']/s:polyline"}),
      "2 1 1 3\n");
  const std::string text = test::run_program("cat", path("h.svg")).out;
  EXPECT_THAT(text, HasSubstr("b [m], linear_axis"));
  EXPECT_THAT(text, HasSubstr("a [rad], bisected"));
}

TEST_F(CliRenderTest, PlotBadInput) {
  const std::string b = bounds_file();
  const std::string bad =
      dir_.write("bad.json", R"({"joints": ["a"], "waypoints": [{"q": [0], "lower": [0.5], "upper": [1]}]})");
  const std::string short_file = dir_.write(
      "short.json", R"({"joints": ["a", "b"], "waypoints": [{"q": [0], "lower": [0], "upper": [1]}]})");
  const std::string nan_file =
      dir_.write("nan.json", R"({"joints": ["a"], "waypoints": [{"q": [NaN], "lower": [0], "upper": [1]}]})");
  const std::string back_in_time = dir_.write("back.json", R"({"joints": ["a"], "waypoints": [
      {"t": 0, "q": [0], "lower": [0], "upper": [1]}, {"t": 0.5, "q": [0], "lower": [0], "upper": [1]},
      {"t": 0.2, "q": [0], "lower": [0], "upper": [1]}]})");
  struct Case {
    std::string args, message;
  };
  const std::vector<Case> cases = {
      {b + " --out " + path("p.txt"), "must end in .svg or .png"},
      {back_in_time + " --out " + path("p.svg"),
       "back.json: waypoint 2 't' 0.2 s: times are finite, from 0 and never decrease"},
      {b + " --out /nonexistent-folder/p.svg", "cannot write there"},
      {b + " --out " + path("p.svg") + " --size 0x100", "--size '0x100'"},
      {bad + " --out " + path("p.svg"), "nominal 0 is not within [0.5, 1]"},
      {short_file + " --out " + path("p.svg"), "waypoint 0 'q' has 1 values, 'joints' names 2"},
      {nan_file + " --out " + path("p.svg"), "malformed JSON"},
      // Six panels in three rows need 58 + 3 * 160 pixels.
      {b + " --out " + path("p.svg") + " --size 1400x500",
       "plot size 1400x500 is too small for 6 joint panels in 3 row(s) of 2: at least 400x538 pixels"},
      {b + " --out " + path("p.png") + " --size 1400x500", "plot size 1400x500 is too small"},
      {b + " --out " + path("p.svg") + " --x u", "--x: u not in {t,s}"},
  };
  for (const auto& c : cases) {
    const auto r = run_cli("plot " + c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.out;
    EXPECT_THAT(r.out, HasSubstr(c.message)) << c.args;
    EXPECT_FALSE(fs::exists(path("p.svg")));
    EXPECT_FALSE(fs::exists(path("p.png")));
  }
}

// A via point 0.036 s into a 0.55 s path is drawn at 0.036 / 0.55 of the axis (x = t by default),
// at the middle with --x s; a file without times falls back to s with a note.
TEST_F(CliRenderTest, PlotXAxisIsTimeBySecondsOrThePathParameter) {
  const std::string b = dir_.write("t.json", R"({"joints": ["a"], "waypoints": [
      {"t": 0, "q": [0], "lower": [-1], "upper": [1]},
      {"t": 0.036, "q": [0], "lower": [-1], "upper": [1]},
      {"t": 0.55, "q": [0], "lower": [-1], "upper": [1]}]})");
  // One panel of 400x300: plot area from x 64, 316 wide; y = 1 at row 82 + 182 * 0.1 / 2.2 = 90.27.
  auto r = run_cli("plot " + b + " --out " + path("t.svg") + " --size 400x300");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::string svg = test::run_program("cat", path("t.svg")).out;
  EXPECT_THAT(svg,
              HasSubstr("class=\"upper\" fill=\"none\" points=\"64.00,90.27 84.68,90.27 380.00,90.27\""));
  EXPECT_THAT(svg, HasSubstr(">time t [s]; lines join the waypoints</text>"));
  r = run_cli("plot " + b + " --out " + path("s.svg") + " --size 400x300 --x s");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  svg = test::run_program("cat", path("s.svg")).out;
  EXPECT_THAT(svg,
              HasSubstr("class=\"upper\" fill=\"none\" points=\"64.00,90.27 222.00,90.27 380.00,90.27\""));
  const std::string old = dir_.write("old.json", R"({"joints": ["a"], "waypoints": [
      {"q": [0], "lower": [-1], "upper": [1]}, {"q": [0], "lower": [-1], "upper": [1]}]})");
  r = run_cli("plot " + old + " --out " + path("o.svg") + " --size 400x300");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_THAT(r.out,
              HasSubstr("has no waypoint times 't' (or lasts 0 s): the x axis is the path parameter s"));
}

TEST_F(CliRenderTest, SweepPlotHasTheThesisSeriesForOneOfTheNineCases) {
  const std::string common = " --preset thesis --max-cells 100,300 --samples 50 --windows 2 --threads 2";
  auto r = run_cli("sweep " + workcell("dallara") + " --from home --to patch" + common + " --plot " +
                   path("s.svg"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  // Three panels (boxes, time, CF), each with leeway's series (2 points) and table 4.1's.
  EXPECT_EQ(svg_counts(path("s.svg"), {".//s:g[@class='panel']", ".//s:polyline[@data-series='leeway']",
                                       ".//s:polyline[@class='series']"}),
            "3 3 6\n");
  EXPECT_THAT(test::run_program("cat", path("s.svg")).out, HasSubstr("thesis, table 4.1"));
  // patch -> home is not one of the nine: leeway's series only.
  r = run_cli("sweep " + workcell("dallara") + " --from patch --to home" + common + " --plot " +
              path("t.svg"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(svg_counts(path("t.svg"), {".//s:g[@class='panel']", ".//s:polyline[@class='series']"}), "3 3\n");
  r = run_cli("sweep " + workcell("dallara") + " --from home --to patch" + common + " --plot " +
              path("s.pdf"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.out, HasSubstr("must end in .svg or .png"));
}

// A sweep CSV saved again by a spreadsheet: a byte order mark, quoted header fields and numbers,
// spaces after the commas and CRLF line ends read as the file leeway wrote.
TEST(SweepCsvTest, ReadsASpreadsheetsCsvWithBomQuotesAndCrlf) {
  test::TempDir dir;
  const std::string file =
      dir.write("s.csv",
                "\xEF\xBB\xBF\"max_cells\", \"boxes\",\"time_ms\" ,\"cf\",\"note, with comma\"\r\n"
                "100,60,18.3,0.9,\"say \"\"hi\"\"\"\r\n"
                "\"1000\", 600 ,80,\"0.99\",\r\n\r\n");
  const SweepSeries s = read_sweep_csv(file);
  ASSERT_EQ(s.points.size(), 2u);
  EXPECT_EQ(s.points[0].max_cells, 100);
  EXPECT_DOUBLE_EQ(s.points[0].boxes, 60);
  EXPECT_DOUBLE_EQ(s.points[0].time_ms, 18.3);
  EXPECT_DOUBLE_EQ(s.points[0].cf_percent, 90);
  EXPECT_EQ(s.points[1].max_cells, 1000);
  EXPECT_DOUBLE_EQ(s.points[1].boxes, 600);
  EXPECT_DOUBLE_EQ(s.points[1].time_ms, 80);
  EXPECT_DOUBLE_EQ(s.points[1].cf_percent, 99);
  const std::string open_quote = dir.write("q.csv", "max_cells,boxes,time_ms,cf\n\"100,60,18.3,0.9\n");
  EXPECT_EQ(test::error_of([&] { read_sweep_csv(open_quote); }),
            open_quote + ": line 2: a quoted field is not closed");
}

TEST_F(CliRenderTest, PlotOfSweepCsvFilesBesideTheThesisTable) {
  const std::string a =
      dir_.write("a.csv", "max_cells,boxes,time_ms,cf\n100,60,18.3,0.9\n1000,600,80,0.99\n");
  const std::string b = dir_.write("b.csv", "max_cells,boxes,time_ms,cf,extra\n100,50,10,0.95,x\n");
  auto r = run_cli("plot " + a + " " + b + " --thesis dlr/mould-home --out " + path("s.svg"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  // Three panels with three series each: a, b and table 4.9.
  EXPECT_EQ(svg_counts(path("s.svg"), {".//s:g[@class='panel']", ".//s:polyline[@data-series='a']",
                                       ".//s:polyline[@data-series='thesis, table 4.9 (i5-8250U)']"}),
            "3 3 3\n");
  // CF 0.9 and 0.99 are plotted as 90 and 99 %: padded by 5 % to [89.55, 99.45], ticks every 2 %.
  r = run_cli("plot " + a + " --out " + path("a.svg"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string svg = test::run_program("cat", path("a.svg")).out;
  EXPECT_THAT(svg, HasSubstr(">90</text>"));
  EXPECT_THAT(svg, HasSubstr(">98</text>"));
  const std::string bad = dir_.write("bad.csv", "max_cells,boxes,cf\n100,60,0.9\n");
  const std::string nan = dir_.write("nan.csv", "max_cells,boxes,time_ms,cf\n100,60,nan,0.9\n");
  struct Case {
    std::string args, message;
  };
  const std::vector<Case> cases = {
      {bad + " --out " + path("t.svg"), "bad.csv: line 1 has no column 'time_ms'"},
      {nan + " --out " + path("t.svg"), "nan.csv: line 2 column 'time_ms': 'nan' is not a finite number"},
      {a + " --thesis dallara/home-mould --out " + path("t.svg"), "--thesis 'dallara/home-mould'"},
      {a + " " + bounds_file() + " --out " + path("t.svg"), "not both"},
  };
  for (const auto& c : cases) {
    r = run_cli("plot " + c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.out;
    EXPECT_THAT(r.out, HasSubstr(c.message)) << c.args;
    EXPECT_FALSE(fs::exists(path("t.svg")));
  }
}

TEST_F(CliRenderTest, ExportedMjcfAndMjbCompileWithTheFilesBoxes) {
  fs::create_directories(dir_.path() / "elsewhere");
  const std::string xml = path("elsewhere/volume.xml"), mjb = path("volume.mjb");
  bounds_file("--export-mjcf " + xml + " --export-mjb " + mjb);
  const int boxes = test::read_json(path("b.json")).at("boxes").get<int>();
  ASSERT_GT(boxes, 100);
  for (const std::string& file : {xml, mjb}) {
    SCOPED_TRACE(file);
    const ModelPtr m = load_model_file(file);  // the fixture fails the test on any MuJoCo warning
    const int body = mj_name2id(m.get(), mjOBJ_BODY, kExportBodyName);
    ASSERT_GE(body, 0);
    EXPECT_EQ(m->body_geomnum[body], boxes);
    const int g = m->body_geomadr[body];
    EXPECT_EQ(object_name(*m, mjOBJ_GEOM, g), "leeway_volume_box_0");
    EXPECT_EQ(object_name(*m, mjOBJ_GEOM, g + boxes - 1), "leeway_volume_box_" + std::to_string(boxes - 1));
    for (int k = g; k < g + boxes; ++k) {
      ASSERT_EQ(m->geom_type[k], mjGEOM_BOX);
      ASSERT_EQ(m->geom_contype[k], 0);
      ASSERT_EQ(m->geom_conaffinity[k], 0);
    }
    // The cell itself is still there: the robot and the tables.
    EXPECT_GE(mj_name2id(m.get(), mjOBJ_GEOM, "patch_table"), 0);
    EXPECT_GE(mj_name2id(m.get(), mjOBJ_JOINT, "j1"), 0);
  }
}

TEST_F(CliRenderTest, ExportOfACellWithNestedIncludesCompilesInAnotherFolder) {
  // DLR's cell includes the rail robot, which includes the arm: MuJoCo resolves both against the
  // main file's folder, so the export inlines them.
  const std::string xml = path("dlr-volume.xml");
  const auto r =
      run_cli("bounds " + workcell("dlr") + " --from home --to patch --preset thesis --max-cells 300 --json" +
              " --export-mjcf " + xml);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const ModelPtr m = load_model_file(xml);
  EXPECT_GE(mj_name2id(m.get(), mjOBJ_BODY, kExportBodyName), 0);
  EXPECT_GE(mj_name2id(m.get(), mjOBJ_JOINT, "rail_x"), 0);
}

TEST_F(CliRenderTest, ExportBadPathWritesNothing) {
  const auto r =
      run_cli("bounds " + workcell("dallara") + " --from home --to patch --preset thesis --max-cells 300" +
              " --out " + path("b.json") + " --export-mjcf /nonexistent-folder/v.xml");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_THAT(r.out, HasSubstr("--export-mjcf /nonexistent-folder/v.xml: cannot write there"));
  EXPECT_FALSE(fs::exists(path("b.json")));
  const auto ext =
      run_cli("bounds " + workcell("dallara") + " --from home --to patch --preset thesis --max-cells 300" +
              " --export-mjb " + path("v.xml"));
  EXPECT_EQ(ext.exit_code, 2) << ext.out;
  EXPECT_THAT(ext.out, HasSubstr("must end in .mjb"));
}

}  // namespace
}  // namespace leeway
