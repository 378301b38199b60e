#pragma once
// A plot as a small display list, drawn once and written either as SVG text or as a PNG image
// rasterised here (no OpenGL), so both formats show the same lines, dashes, shading and labels.
// Numbers are formatted with std::to_chars: the same text under any process or C++ locale.

#include <string>
#include <utility>
#include <vector>

#include "leeway/viz/plot.hpp"
#include "leeway/viz/render.hpp"

namespace leeway::detail {

//! A colour, each channel in [0, 1].
struct Rgb {
  double r = 0, g = 0, b = 0;
  std::string hex() const;  //!< "#rrggbb"
};

using Points = std::vector<std::pair<double, double>>;  //!< pixel coordinates, y down

//! One element of a drawing. Coordinates in pixels from the image's top left corner.
struct Item {
  enum Kind { kGroupBegin, kGroupEnd, kPolyline, kPolygon, kCircle, kText } kind = kPolyline;
  Points points;               //!< polyline or polygon vertices
  Rgb stroke, fill;            //!< line colour; fill colour of polygons and circles
  double width = 1;            //!< line width [px]; 0: no outline
  std::vector<double> dash;    //!< dash pattern [px] (on, off, ...); empty: solid
  double opacity = 1;          //!< fill opacity of polygons and circles
  bool filled = false;         //!< circles: filled (else outlined)
  double x = 0, y = 0, r = 0;  //!< circle centre and radius; text anchor point (y: baseline)
  std::string text;            //!< text; circles: an SVG tooltip
  double size = 12;            //!< text height [px]
  int anchor = 0;              //!< text: 0 start, 1 middle, 2 end
  bool bold = false;           //!< text weight (SVG only)
  std::string cls;             //!< SVG class ("" for none); tick labels have class "tick"
  std::string attrs;           //!< extra SVG attributes (data-*), written verbatim
};

//! A plot: a white background and its items in drawing order.
struct Drawing {
  int width = 0, height = 0;
  std::vector<Item> items;

  void group(const std::string& attrs);  //!< opens `<g attrs>`
  void end_group();
  void polyline(Points pts, const Rgb& c, double line_width, std::vector<double> dash = {},
                std::string cls = "", std::string attrs = "");
  void polygon(Points pts, const Rgb& fill, double opacity, std::string cls = "", const Rgb& stroke = {},
               double stroke_width = 0);
  void rect(double x, double y, double w, double h, const Rgb& fill, const Rgb& stroke, double stroke_width);
  void circle(double x, double y, double r, const Rgb& c, bool filled, double line_width,
              std::string cls = "", std::string title = "");
  void label(double x, double y, const std::string& s, double size, int anchor = 0, bool bold = false,
             std::string cls = "");
  //! The texts of class `cls` in drawing order (the tick labels: "tick").
  std::vector<std::string> texts(const std::string& cls) const;
};

//! The drawing as SVG text (deterministic: coordinates with two decimals).
std::string to_svg(const Drawing& d);

//! The drawing rasterised: polygons filled by scanlines at pixel centres and blended by their
//! opacity, lines as filled quads along their dashes, text in a built-in 5x7 bitmap font scaled to
//! the text size.
Image to_image(const Drawing& d);

//! `v` with `digits` decimals, '.' as the decimal point whatever the locale; "-0" is written "0".
std::string format_fixed(double v, int digits);

//! Axis ticks: about `n` values at 1, 2 or 5 times a power of ten within [lo, hi], as multiples of
//! the step (no accumulated rounding), with their labels (as many decimals as the step needs).
struct Ticks {
  std::vector<double> values;
  std::vector<std::string> labels;
};
Ticks nice_ticks(double lo, double hi, int n);

//! Width of a text in the built-in font at `size` [px] (what to_image draws).
double text_width(const std::string& s, double size);

//! The bounds plot's drawing (what bounds_svg and bounds_image write). @throws as bounds_svg.
Drawing bounds_drawing(const BoundsSeries& series, int width, int height, PlotX x);

//! The sweep plot's drawing (what sweep_svg and sweep_image write). @throws as sweep_svg.
Drawing sweep_drawing(const std::vector<SweepSeries>& series, const std::string& title, int width,
                      int height);

}  // namespace leeway::detail
