#pragma once
//! @file plot.hpp
//! Plots: each joint's bounds along the path (the thesis's figs. 4.4-4.16), and a
//! sweep's boxes, time and CF against MAX_cells (tables 4.1-4.9) beside the thesis's published
//! values. Each plot is drawn once and written as SVG or as a PNG rasterised by leeway itself (no
//! OpenGL), with the same content; numbers are written the same under any locale.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "leeway/viz/render.hpp"

namespace leeway {

//! A bounds file's intervals, as the plot needs them (no cell required).
struct BoundsSeries {
  std::string source;               //!< the file, for titles and messages
  std::vector<std::string> joints;  //!< joint names in order
  std::vector<std::string> kinds;   //!< per joint: bisected, fixed, linear_axis (or "" in older files)
  //! Per waypoint: nominal, bounds, and the guide bounds before the safety stage [rad or m].
  std::vector<Eigen::VectorXd> q, lower, upper, guide_lower, guide_upper;
  std::vector<std::vector<bool>> collapsed;  //!< per waypoint and joint: widened by the collapse guard
  //! Path parameter of each waypoint: s = k / (n - 1) (the joint-linear interpolation parameter on
  //! a path between two keyframes; the waypoint index's fraction on a planned path).
  std::vector<double> s;
  //! Time of each waypoint [s] (format 2's `t`); empty when a waypoint has none.
  std::vector<double> t;
  //! True when every waypoint has a time and the path lasts longer than 0 s.
  bool has_times() const { return !t.empty() && t.back() > 0; }
  //! Joint k's unit: "m" for the linear axis, "rad" otherwise.
  std::string unit(size_t k) const { return kinds[k] == "linear_axis" ? "m" : "rad"; }
  //! True when the safety stage shrank joint k's interval at waypoint w.
  bool shrunk(size_t w, size_t k) const;
};

//! Reads the series of a bounds file (format leeway-bounds-1, or older files without guide bounds).
//! @throws InputError naming the file, waypoint and joint on a malformed file, sizes that differ,
//! non-finite values, lower > nominal > upper, or times `t` that are not finite, start below 0 or
//! decrease.
BoundsSeries read_bounds_series(const std::string& path);

//! The bounds plot's x axis: time t [s] (when the file has times, else s) or the path parameter s.
enum class PlotX { kTime, kPathParameter };

//! The bounds plot as SVG: one panel per joint with the band between lower and upper, the nominal,
//! the guide bounds where the safety stage shrank the interval, and collapsed intervals marked.
//! Every joint's panel is a `<g class="joint" data-joint="NAME">` holding polylines of class
//! `lower`, `nominal` and `upper`, a `<path class="band">`, and `guide-lower`/`guide-upper` where
//! shrunk. A panel's y range is the band plus half its height on either side: guide bounds beyond
//! it run along the panel's edge, each such waypoint marked by a grey triangle (class
//! `guide-clipped`) pointing out of the panel. @throws InputError on a size outside 16 .. 8192
//! pixels or too small for the panels (200 x 160 pixels each below a 58-pixel title band).
std::string bounds_svg(const BoundsSeries& series, int width, int height, PlotX x = PlotX::kTime);

//! The bounds plot as an image: the same drawing as bounds_svg, rasterised. @throws as bounds_svg.
Image bounds_image(const BoundsSeries& series, int width, int height, PlotX x = PlotX::kTime);

//! One row of a sweep: MAX_cells, boxes, total time [ms] and CF [%].
struct SweepPoint {
  int max_cells = 0;
  double boxes = 0, time_ms = 0, cf_percent = 0;
};

//! A sweep's rows under a label ("leeway", "thesis (table 4.1)").
struct SweepSeries {
  std::string label;
  std::vector<SweepPoint> points;
};

//! Reads a sweep's CSV file as `leeway sweep --csv` writes it (columns max_cells, boxes, time_ms and
//! cf as a fraction, among others), labelled with the file's name without its extension.
//! @throws InputError naming the file, line and column when a column is missing or a value is not a
//! finite number.
SweepSeries read_sweep_csv(const std::string& path);

//! The thesis's published rows (tables 4.1-4.9, docs/data/thesis_tables.csv) for a cell named
//! "dallara", "baltico" or "dlr" and a path "home-patch", "patch-mould" or "mould-home"; empty for
//! any other case. `table` receives the table's number ("4.1").
std::vector<SweepPoint> thesis_table(const std::string& cell, const std::string& path,
                                     std::string* table = nullptr);

//! The sweep plot as SVG: three panels (boxes, time [ms], CF [%]) against MAX_cells on a log axis,
//! one `<polyline class="series" data-series="LABEL">` per series and panel.
//! @throws InputError on a size outside 16 .. 8192 pixels, below 600 x 218 pixels, or no series with
//! points.
std::string sweep_svg(const std::vector<SweepSeries>& series, const std::string& title, int width,
                      int height);

//! The sweep plot as an image: the same drawing as sweep_svg, rasterised. @throws as sweep_svg.
Image sweep_image(const std::vector<SweepSeries>& series, const std::string& title, int width, int height);

}  // namespace leeway
