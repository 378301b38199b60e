// plot.hpp: the thesis's tables as embedded, bounds files read for plotting, and bad plot input.
#include "leeway/viz/plot.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <clocale>
#include <cstdlib>
#include <locale>
#include <regex>

#include "leeway/core/error.hpp"
#include "png_util.hpp"
#include "test_util.hpp"
#include "viz/canvas.hpp"

namespace leeway {
namespace {

TEST(ThesisTableTest, EmbeddedRowsOfTable41AndTable49) {
  std::string table;
  const auto rows = thesis_table("dallara", "home-patch", &table);
  EXPECT_EQ(table, "4.1");
  ASSERT_EQ(rows.size(), 20u);
  // docs/data/thesis_tables.csv: 4.1,dallara,home-patch,100,43,82,95.3839
  EXPECT_EQ(rows[0].max_cells, 100);
  EXPECT_DOUBLE_EQ(rows[0].boxes, 43);
  EXPECT_DOUBLE_EQ(rows[0].time_ms, 82);
  EXPECT_DOUBLE_EQ(rows[0].cf_percent, 95.3839);
  EXPECT_EQ(rows.back().max_cells, 100000);
  EXPECT_FALSE(thesis_table("dlr", "mould-home", &table).empty());
  EXPECT_EQ(table, "4.9");
  EXPECT_TRUE(thesis_table("dallara", "patch-home").empty());
  EXPECT_TRUE(thesis_table("example", "home-patch").empty());
}

TEST(BoundsSeriesTest, PathParameterShrunkAndUnits) {
  test::TempDir dir;
  const std::string file =
      dir.write("b.json", R"({"joints": ["j1", "rail"], "joint_bounding": ["bisected", "linear_axis"],
    "waypoints": [{"q": [0, 0], "lower": [-1, 0], "upper": [1, 0]},
                  {"q": [0, 0], "lower": [-0.5, 0], "upper": [1, 0], "guide_lower": [-1, 0], "guide_upper": [1, 0]},
                  {"q": [0, 0], "lower": [0, 0], "upper": [0, 0], "collapsed": ["j1"]}]})");
  const BoundsSeries s = read_bounds_series(file);
  EXPECT_EQ(s.s, (std::vector<double>{0, 0.5, 1}));
  EXPECT_EQ(s.unit(0), "rad");
  EXPECT_EQ(s.unit(1), "m");
  EXPECT_FALSE(s.shrunk(0, 0));
  EXPECT_TRUE(s.shrunk(1, 0));
  EXPECT_FALSE(s.shrunk(1, 1));
  EXPECT_TRUE(s.collapsed[2][0]);
}

TEST(PlotTest, BadSizesAndEmptySweeps) {
  test::TempDir dir;
  const BoundsSeries s = read_bounds_series(
      dir.write("b.json", R"({"joints": ["j1"], "waypoints": [{"q": [0], "lower": [-1], "upper": [1]}]})"));
  EXPECT_THROW(bounds_svg(s, 10, 400), InputError);
  EXPECT_NO_THROW(bounds_svg(s, 400, 300));
  EXPECT_THROW(sweep_svg({{"leeway", {}}}, "t", 800, 400), InputError);
  EXPECT_THROW(sweep_svg({{"leeway", {{100, std::nan(""), 1, 99}}}}, "t", 800, 400), InputError);
  EXPECT_NO_THROW(sweep_svg({{"leeway", {{100, 40, 1, 99}}}}, "t", 800, 400));
}

// Ranges worked out by hand: the step is the 1, 2 or 5 times 10^k nearest above (hi - lo) / n.
TEST(NiceTicksTest, OneTwoFiveStepsWithoutFloatNoise) {
  using detail::nice_ticks;
  // (0.93 + 0.04) / 5 = 0.194 -> 0.2: 0, 0.2, ..., 0.8 (not -0.0396 and 0.926).
  auto t = nice_ticks(-0.04, 0.93, 5);
  EXPECT_EQ(t.labels, (std::vector<std::string>{"0.0", "0.2", "0.4", "0.6", "0.8"}));
  // 1 / 10 = 0.1: the fourth tick is the double nearest 0.3, not 0.30000000000000004.
  t = nice_ticks(0, 1, 10);
  ASSERT_EQ(t.values.size(), 11u);
  EXPECT_EQ(t.values[3], 0.3);
  EXPECT_EQ(t.labels[3], "0.3");
  EXPECT_EQ(t.labels[10], "1.0");
  // 4400 / 4 = 1100 -> 2000.
  EXPECT_EQ(nice_ticks(1200, 5600, 4).labels, (std::vector<std::string>{"2000", "4000"}));
  // 3.1 / 4 = 0.775 -> 1.
  EXPECT_EQ(nice_ticks(-3.2, -0.1, 4).labels, (std::vector<std::string>{"-3", "-2", "-1"}));
  // 0.9 / 3 = 0.3 -> 0.5.
  EXPECT_EQ(nice_ticks(0, 0.9, 3).labels, (std::vector<std::string>{"0.0", "0.5"}));
  // 22 / 5 = 4.4 -> 5.
  EXPECT_EQ(nice_ticks(-11, 11, 5).labels, (std::vector<std::string>{"-10", "-5", "0", "5", "10"}));
  EXPECT_EQ(detail::format_fixed(-0.0001, 2), "0.00");
  EXPECT_EQ(detail::format_fixed(-1.005, 1), "-1.0");
}

// A dashed line 2 pixels wide along y = 10, dashes of 5 and gaps of 3 from x = 0: pixels whose
// centres lie in [0, 5) and [8, 13) are the line's colour, those in [5, 8) and [13, 16) background.
TEST(CanvasTest, DashedLineAndShadedBandPixels) {
  detail::Drawing d;
  d.width = 40;
  d.height = 20;
  d.polyline({{0, 10}, {40, 10}}, {1, 0, 0}, 2, {5, 3});
  d.polygon({{0, 0}, {40, 0}, {40, 5}, {0, 5}}, {0.62, 0.79, 0.88}, 0.5);
  const Image im = detail::to_image(d);
  using Px = std::array<unsigned char, 3>;
  const Px red{255, 0, 0}, white{255, 255, 255};
  EXPECT_EQ(im.at(2, 9), red);
  EXPECT_EQ(im.at(2, 10), red);
  EXPECT_EQ(im.at(9, 10), red);
  EXPECT_EQ(im.at(6, 10), white);  // centre 6.5: in the gap [5, 8)
  EXPECT_EQ(im.at(14, 9), white);  // centre 14.5: in the gap [13, 16)
  EXPECT_EQ(im.at(2, 12), white);  // below the line's rows 9 and 10
  // Half-opaque (0.62, 0.79, 0.88) over white: 0.5 * 255 * c + 0.5 * 255 = 207, 228, 240.
  EXPECT_EQ(im.at(20, 2), (Px{207, 228, 240}));
  // The SVG of the same drawing has the same dash pattern and opacity.
  const std::string svg = detail::to_svg(d);
  EXPECT_THAT(svg, testing::HasSubstr("stroke-dasharray=\"5,3\""));
  EXPECT_THAT(svg, testing::HasSubstr("fill=\"#9ec9e0\" fill-opacity=\"0.5\""));
}

// A numpunct facet writing ',' as the decimal point, as a German C++ locale does.
struct CommaPunct : std::numpunct<char> {
  char do_decimal_point() const override { return ','; }
};

BoundsSeries one_joint(test::TempDir& dir) {
  return read_bounds_series(dir.write("one.json", R"({"joints": ["j1"], "waypoints": [
    {"t": 0, "q": [0], "lower": [-0.04], "upper": [0.93]},
    {"t": 0.55, "q": [0.5], "lower": [0.25], "upper": [0.75]}]})"));
}

void expect_no_decimal_commas(const BoundsSeries& s) {
  const auto d = detail::bounds_drawing(s, 400, 300, PlotX::kTime);
  for (const auto& label : d.texts("tick")) EXPECT_EQ(label.find(','), std::string::npos) << label;
  const std::string svg = bounds_svg(s, 400, 300);
  // Every number in an attribute has a '.' decimal point: no x="12,50".
  EXPECT_FALSE(std::regex_search(svg, std::regex(R"( (x|y|x1|y1|x2|y2|cx|cy|r|stroke-width)="-?[0-9]+,)")))
      << svg;
  EXPECT_THAT(svg, testing::HasSubstr(">0.2</text>"));
}

TEST(PlotLocaleTest, CxxGlobalLocaleWithADecimalCommaChangesNoNumber) {
  test::TempDir dir;
  const BoundsSeries s = one_joint(dir);
  const std::locale before = std::locale::global(std::locale(std::locale::classic(), new CommaPunct));
  std::ostringstream probe;
  probe << 0.5;
  EXPECT_EQ(probe.str(), "0,5");  // the facet is in effect for new streams
  expect_no_decimal_commas(s);
  std::locale::global(before);
}

// The C library's LC_NUMERIC (what printf follows). When no comma locale is installed, one is
// compiled with localedef (Debian's `locales` package) into a temporary folder named by LOCPATH.
TEST(PlotLocaleTest, CLocaleWithADecimalCommaChangesNoNumber) {
  test::TempDir dir;
  const BoundsSeries s = one_joint(dir);
  const std::string old = std::setlocale(LC_NUMERIC, nullptr);
  const char* found = nullptr;
  for (const char* name : {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8"})
    if (!found && std::setlocale(LC_NUMERIC, name)) found = name;
  if (!found &&
      test::run_program("localedef", "-i de_DE -f UTF-8 " + dir.path().string() + "/de_DE.UTF-8").exit_code <=
          1) {  // 1: written with warnings
    setenv("LOCPATH", dir.path().c_str(), 1);
    if (std::setlocale(LC_NUMERIC, "de_DE.UTF-8")) found = "de_DE.UTF-8 (compiled by localedef)";
    unsetenv("LOCPATH");
  }
  if (!found)
    GTEST_SKIP() << "no comma locale: de_DE.UTF-8 is not installed and localedef could not compile it "
                    "(install Debian's locales package)";
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%.1f", 0.5);
  EXPECT_STREQ(buf, "0,5") << found;  // printf now writes decimal commas
  expect_no_decimal_commas(s);
  // A sweep's CSV file reads the same (std::stod would stop at the '.').
  const SweepSeries sweep =
      read_sweep_csv(dir.write("s.csv", "max_cells,boxes,time_ms,cf\n100,60,18.3,0.9\n"));
  EXPECT_DOUBLE_EQ(sweep.points.at(0).time_ms, 18.3);
  std::setlocale(LC_NUMERIC, old.c_str());
}

// PNG and SVG are written from one drawing: the SVG has every tick label of the drawing, in order;
// the PNG has the drawing's size and its band colour where the band is.
TEST(PlotTest, SvgAndPngShowTheSameDrawing) {
  test::TempDir dir;
  const BoundsSeries s = one_joint(dir);
  const auto d = detail::bounds_drawing(s, 400, 300, PlotX::kTime);
  const auto ticks = d.texts("tick");
  // x: 0 .. 0.55 s in 5 -> 0.11 -> 0.2; y: [-0.04, 0.93] + 5 % -> [-0.0885, 0.9785] in 4 -> 0.5.
  EXPECT_EQ(ticks, (std::vector<std::string>{"0.0", "0.2", "0.4", "0.0", "0.5"}));
  const std::string svg = bounds_svg(s, 400, 300);
  size_t at = 0;
  for (const auto& t : ticks) {
    at = svg.find("class=\"tick\"", at);
    ASSERT_NE(at, std::string::npos);
    at = svg.find(">" + t + "</text>", at);
    ASSERT_NE(at, std::string::npos) << t;
  }
  const Image im = bounds_image(s, 400, 300);
  EXPECT_EQ(im.width, 400);
  // Panel area x 64 .. 380, y 82 .. 264. At 0.1 s (pixel 64 + 316 * 0.1 / 0.55 = 121.5) the band
  // spans 0.013 .. 0.897 rad; 0.6 rad is at row 264 - 182 * (0.6 + 0.0885) / 1.067 = 146.5: the
  // band (0.62, 0.79, 0.88) half-opaque over the pane (250, 250, 250) is 204, 226, 237.
  EXPECT_EQ(im.at(121, 146), (std::array<unsigned char, 3>{204, 226, 237}));
}

// The guide spans the joint's whole range, the band only [-0.1, 0.1]: the y range is the band plus
// half its height either side, [-0.2, 0.2], padded by 5 % to [-0.22, 0.22]; the guide runs along
// the edges and each of its four clipped waypoint values is marked.
TEST(PlotTest, GuideSpanningTheJointRangeIsClippedAndMarked) {
  test::TempDir dir;
  const BoundsSeries s = read_bounds_series(dir.write("g.json", R"({"joints": ["j1"], "waypoints": [
    {"q": [0], "lower": [-0.1], "upper": [0.1], "guide_lower": [-3], "guide_upper": [3]},
    {"q": [0], "lower": [-0.1], "upper": [0.1], "guide_lower": [-3], "guide_upper": [3]}]})"));
  const auto d = detail::bounds_drawing(s, 400, 300, PlotX::kPathParameter);
  EXPECT_EQ(d.texts("tick"),
            (std::vector<std::string>{"0.0", "0.2", "0.4", "0.6", "0.8", "1.0", "-0.2", "0.0", "0.2"}));
  EXPECT_EQ(d.texts("clip-note"), (std::vector<std::string>{"guide clipped at the edge"}));
  int marks = 0;
  for (const auto& it : d.items) {
    if (it.cls == "guide-clipped") ++marks;
    if (it.cls == "band") {  // rows 173 -+ 182 * 0.1 / 0.44 (131.64 .. 214.36)
      for (const auto& p : it.points) EXPECT_NEAR(std::abs(p.second - 173), 182 * 0.1 / 0.44, 1e-9);
    }
    if (it.cls == "guide-upper") {  // along the top edge, y = 82
      for (const auto& p : it.points) EXPECT_NEAR(p.second, 82, 1e-9);
    }
  }
  EXPECT_EQ(marks, 4);
}

TEST(PlotTest, SizesTooSmallForThePanelsAreRefused) {
  test::TempDir dir;
  std::string wps;
  for (int w = 0; w < 2; ++w)
    wps += std::string(w ? "," : "") +
           R"({"q": [0,0,0,0,0,0], "lower": [-1,-1,-1,-1,-1,-1], "upper": [1,1,1,1,1,1]})";
  const BoundsSeries s = read_bounds_series(
      dir.write("six.json", R"({"joints": ["a","b","c","d","e","f"], "waypoints": [)" + wps + "]}"));
  // Two columns of three rows: at least 2 * 200 wide and 58 + 3 * 160 = 538 high.
  EXPECT_EQ(test::error_of([&] { bounds_svg(s, 1400, 500); }),
            "plot size 1400x500 is too small for 6 joint panels in 3 row(s) of 2: at least 400x538 pixels");
  EXPECT_NO_THROW(bounds_svg(s, 400, 538));
  // At the minimum size the y labels of a panel (right-aligned ticks) stand at least 20 pixels
  // apart: a step of at least a quarter of the range on a plot area 100 pixels high, the 8-pixel
  // font never overlapping.
  const auto d = detail::bounds_drawing(s, 400, 538, PlotX::kTime);
  double last = -1e9;
  int labels = 0;
  for (const auto& it : d.items) {
    if (it.kind == detail::Item::kGroupBegin) last = -1e9;
    if (it.kind != detail::Item::kText || it.cls != "tick" || it.anchor != 2) continue;
    if (last > -1e9) {
      EXPECT_GE(std::abs(it.y - last), 20) << it.text;
    }
    last = it.y;
    ++labels;
  }
  EXPECT_GE(labels, 12);  // at least two per panel
  EXPECT_THROW(bounds_image(s, 399, 538), InputError);
  EXPECT_THROW(sweep_svg({{"leeway", {{100, 40, 1, 99}}}}, "t", 599, 400), InputError);
}

}  // namespace
}  // namespace leeway
