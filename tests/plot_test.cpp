// plot.hpp: the thesis's tables as embedded, bounds files read for plotting, and bad plot input.
#include "leeway/viz/plot.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "leeway/core/error.hpp"
#include "test_util.hpp"

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

}  // namespace
}  // namespace leeway
