#include "leeway/viz/plot.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "canvas.hpp"
#include "core/json_io.hpp"
#include "io/mjcf_text.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/io/bounds_file.hpp"
#include "offscreen.hpp"

namespace leeway {
namespace detail {
extern const char* const kThesisTablesCsv;  // docs/data/thesis_tables.csv, embedded by CMake
}  // namespace detail

namespace {

using detail::Drawing;
using detail::Points;
using detail::Rgb;
using detail::Ticks;

// ---------------------------------------------------------------------------------------------
// Shared: axes, colours, sizes.

// The y range of a panel: the data's, padded by 5 % (or +-0.1 when flat).
std::pair<double, double> padded(double lo, double hi) {
  if (!(hi > lo)) return {lo - 0.1, hi + 0.1};
  const double pad = 0.05 * (hi - lo);
  return {lo - pad, hi + pad};
}

constexpr Rgb kLower{0.13, 0.44, 0.71}, kUpper{0.80, 0.09, 0.11}, kNominal{0.1, 0.1, 0.1};
constexpr Rgb kGuide{0.55, 0.55, 0.55}, kCollapsed{1.0, 0.5, 0.0}, kBand{0.62, 0.79, 0.88};
constexpr Rgb kPane{0.98, 0.98, 0.98}, kFrame{0.267, 0.267, 0.267}, kGrid{0.867, 0.867, 0.867};
constexpr Rgb kSeries[] = {{0.13, 0.44, 0.71}, {0.90, 0.45, 0.05}, {0.2, 0.6, 0.2}, {0.5, 0.3, 0.6}};
const std::vector<double> kGuideDash = {5, 3}, kSeriesDash = {6, 3};
constexpr double kBandOpacity = 0.5;
constexpr double kTop = 58;  // the title and legend band [px]

// The smallest panel that still has room for its title, five tick labels and the x axis label.
constexpr int kMinPanelWidth = 200, kMinPanelHeight = 160;

// A rectangle of the image: the plot area of one panel.
struct Area {
  double x, y, w, h;
};

// Axes, grid and tick labels of a panel; x and y map data to pixels.
template <class X, class Y>
void axes(Drawing& d, const Area& a, const Ticks& xt, const Ticks& yt, X&& x, Y&& y) {
  d.rect(a.x, a.y, a.w, a.h, kPane, kFrame, 1);
  for (size_t i = 0; i < xt.values.size(); ++i) {
    d.polyline({{x(xt.values[i]), a.y}, {x(xt.values[i]), a.y + a.h}}, kGrid, 1);
    d.label(x(xt.values[i]), a.y + a.h + 14, xt.labels[i], 10, 1, false, "tick");
  }
  for (size_t i = 0; i < yt.values.size(); ++i) {
    d.polyline({{a.x, y(yt.values[i])}, {a.x + a.w, y(yt.values[i])}}, kGrid, 1);
    d.label(a.x - 4, y(yt.values[i]) + 3.5, yt.labels[i], 10, 2, false, "tick");
  }
}

// A legend entry: a line sample (dashed when `dash` is set) and its text; returns the next x.
double legend_line(Drawing& d, double x, const std::string& text, const Rgb& c,
                   const std::vector<double>& dash) {
  d.polyline({{x, 40}, {x + 24, 40}}, c, 2, dash);
  d.label(x + 30, 44, text, 12);
  return x + 40 + 7.0 * static_cast<double>(text.size());
}

// Refuses an image too small for its panels (they would be drawn with no room for their axes).
void check_panels(int width, int height, int cols, int rows, const std::string& what) {
  const int min_w = cols * kMinPanelWidth, min_h = static_cast<int>(kTop) + rows * kMinPanelHeight;
  if (width < min_w || height < min_h)
    throw InputError("plot size " + std::to_string(width) + "x" + std::to_string(height) +
                     " is too small for " + what + " in " + std::to_string(rows) + " row(s) of " +
                     std::to_string(cols) + ": at least " + std::to_string(min_w) + "x" +
                     std::to_string(min_h) + " pixels");
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Bounds plots.

bool BoundsSeries::shrunk(size_t w, size_t k) const {
  const auto i = static_cast<Eigen::Index>(k);
  return lower[w][i] > guide_lower[w][i] || upper[w][i] < guide_upper[w][i];
}

BoundsSeries read_bounds_series(const std::string& path) {
  const nlohmann::json j = detail::read_json_file(path, "bounds file");
  auto fail = [&](const std::string& what) { throw InputError(path + ": " + what); };
  BoundsSeries out;
  out.source = path;
  try {
    require_bounds_shape(j, path);
    out.joints = j.at("joints").get<std::vector<std::string>>();
    const size_t dof = out.joints.size();
    if (dof == 0) fail("'joints' is empty");
    out.kinds.assign(dof, "");
    if (j.contains("joint_bounding")) {
      out.kinds = j.at("joint_bounding").get<std::vector<std::string>>();
      if (out.kinds.size() != dof)
        fail("'joint_bounding' has " + std::to_string(out.kinds.size()) + " entries, 'joints' " +
             std::to_string(dof));
    }
    const auto& wps = j.at("waypoints");
    if (!wps.is_array() || wps.empty()) fail("'waypoints' must be a non-empty list");
    for (size_t w = 0; w < wps.size(); ++w) {
      const std::string where = "waypoint " + std::to_string(w);
      auto vec = [&](const char* key, bool optional, const Eigen::VectorXd& fallback) -> Eigen::VectorXd {
        if (optional && !wps[w].contains(key)) return fallback;
        const auto v = wps[w].at(key).get<std::vector<double>>();
        if (v.size() != dof)
          fail(where + " '" + key + "' has " + std::to_string(v.size()) + " values, 'joints' names " +
               std::to_string(dof));
        for (size_t k = 0; k < dof; ++k)
          if (!std::isfinite(v[k]))
            fail(where + " '" + key + "' joint '" + out.joints[k] + "' is not a finite number");
        return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(dof));
      };
      out.q.push_back(vec("q", false, {}));
      out.lower.push_back(vec("lower", false, {}));
      out.upper.push_back(vec("upper", false, {}));
      out.guide_lower.push_back(vec("guide_lower", true, out.lower.back()));
      out.guide_upper.push_back(vec("guide_upper", true, out.upper.back()));
      for (size_t k = 0; k < dof; ++k) {
        const auto i = static_cast<Eigen::Index>(k);
        if (!(out.lower[w][i] <= out.q[w][i] && out.q[w][i] <= out.upper[w][i]))
          fail(where + " joint '" + out.joints[k] + "': nominal " + format_number(out.q[w][i]) +
               " is not within [" + format_number(out.lower[w][i]) + ", " + format_number(out.upper[w][i]) +
               "]");
      }
      std::vector<bool> collapsed(dof, false);
      if (wps[w].contains("collapsed"))
        for (const auto& name : wps[w].at("collapsed").get<std::vector<std::string>>()) {
          const auto it = std::find(out.joints.begin(), out.joints.end(), name);
          if (it == out.joints.end()) fail(where + " 'collapsed' names '" + name + "', not one of 'joints'");
          collapsed[static_cast<size_t>(it - out.joints.begin())] = true;
        }
      out.collapsed.push_back(collapsed);
      if (wps[w].contains("t") && out.t.size() == w) {
        const double t = wps[w].at("t").get<double>();
        if (!std::isfinite(t) || t < 0 || (w > 0 && t < out.t.back()))
          fail(where + " 't' " + format_number(t) + " s: times are finite, from 0 and never decrease");
        out.t.push_back(t);
      }
    }
    if (out.t.size() != wps.size()) out.t.clear();  // times on some waypoints only: none
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": unexpected content: " + e.what());
  }
  const size_t n = out.q.size();
  for (size_t w = 0; w < n; ++w)
    out.s.push_back(n > 1 ? static_cast<double>(w) / static_cast<double>(n - 1) : 0.0);
  return out;
}

namespace {

// The x value of waypoint w: its time [s] or its path parameter s.
double x_of(const BoundsSeries& series, bool time, size_t w) { return time ? series.t[w] : series.s[w]; }

// The y range of joint k's panel: the band (bounds and nominal) plus a margin of half its height
// on either side, widened to the guide bounds only as far as that margin, so that a guide spanning
// the whole joint range does not squeeze the certified band into a sliver. Padded by 5 %.
std::pair<double, double> joint_range(const BoundsSeries& series, size_t k) {
  const auto i = static_cast<Eigen::Index>(k);
  double blo = series.q[0][i], bhi = blo, glo = blo, ghi = blo;
  for (size_t w = 0; w < series.q.size(); ++w) {
    blo = std::min(blo, series.lower[w][i]);
    bhi = std::max(bhi, series.upper[w][i]);
    glo = std::min(glo, series.guide_lower[w][i]);
    ghi = std::max(ghi, series.guide_upper[w][i]);
  }
  const double margin = bhi > blo ? 0.5 * (bhi - blo) : 0.1;
  return padded(std::min(blo, std::max(glo, blo - margin)), std::max(bhi, std::min(ghi, bhi + margin)));
}

void bounds_legend(Drawing& d, const BoundsSeries& series, bool time) {
  d.label(d.width / 2.0, 20,
          "Joint bounds along the path: " + series.source + " (SI units: rad, m" + (time ? ", s)" : ")"), 14,
          1, true);
  double lx = 20;
  lx = legend_line(d, lx, "lower bound", kLower, {});
  lx = legend_line(d, lx, "nominal", kNominal, {});
  lx = legend_line(d, lx, "upper bound", kUpper, {});
  lx = legend_line(d, lx, "before the safety stage (shrunk)", kGuide, kGuideDash);
  d.circle(lx + 6, 40, 5, kCollapsed, false, 2);
  d.label(lx + 16, 44, "collapsed (widened by the guard)", 12);
}

// The guide bounds of joint k, clamped to the panel; a triangle at the panel's edge marks each
// waypoint whose guide bound lies beyond the axis (pointing up at the top, down at the bottom).
template <class X, class Y>
void guide_lines(Drawing& d, const BoundsSeries& series, size_t k, const Area& a, bool time, X&& x, Y&& y,
                 double ylo, double yhi) {
  const auto i = static_cast<Eigen::Index>(k);
  bool clipped = false;
  for (const auto* v : {&series.guide_lower, &series.guide_upper}) {
    Points pts;
    for (size_t w = 0; w < series.q.size(); ++w) {
      const double value = (*v)[w][i], px = x(x_of(series, time, w));
      pts.emplace_back(px, y(std::clamp(value, ylo, yhi)));
      if (value > yhi)
        d.polygon({{px - 4, a.y + 7}, {px + 4, a.y + 7}, {px, a.y + 1}}, kGuide, 1, "guide-clipped");
      if (value < ylo)
        d.polygon({{px - 4, a.y + a.h - 7}, {px + 4, a.y + a.h - 7}, {px, a.y + a.h - 1}}, kGuide, 1,
                  "guide-clipped");
      clipped = clipped || value > yhi || value < ylo;
    }
    d.polyline(pts, kGuide, 1.5, kGuideDash, v == &series.guide_lower ? "guide-lower" : "guide-upper");
  }
  if (clipped) d.label(a.x + a.w - 4, a.y + 14, "guide clipped at the edge", 10, 2, false, "clip-note");
}

void bounds_panel(Drawing& d, const BoundsSeries& series, size_t k, const Area& a, bool time, double py) {
  const auto i = static_cast<Eigen::Index>(k);
  const size_t n = series.q.size();
  const auto [ylo, yhi] = joint_range(series, k);
  const double xmax = time ? series.t.back() : 1.0;
  auto x = [&a, xmax](double v) { return a.x + v / xmax * a.w; };
  auto y = [&a, ylo = ylo, yhi = yhi](double v) { return a.y + a.h - (v - ylo) / (yhi - ylo) * a.h; };
  d.group("class=\"joint\" data-joint=\"" + detail::xml_escape(series.joints[k]) + "\"");
  const std::string kind = series.kinds[k].empty() ? "" : ", " + series.kinds[k];
  d.label(a.x + a.w / 2, py + 16, series.joints[k] + " [" + series.unit(k) + "]" + kind, 13, 1, true);
  axes(d, a, detail::nice_ticks(0, xmax, 5), detail::nice_ticks(ylo, yhi, 4), x, y);
  d.label(a.x + a.w / 2, a.y + a.h + 30,
          time ? "time t [s]; lines join the waypoints"
               : "path parameter s = k / (n - 1) [1]; lines join the waypoints",
          10, 1);
  auto pts = [&](const std::vector<Eigen::VectorXd>& v) {
    Points out;
    for (size_t w = 0; w < n; ++w) out.emplace_back(x(x_of(series, time, w)), y(v[w][i]));
    return out;
  };
  Points band = pts(series.upper), lower = pts(series.lower);
  band.insert(band.end(), lower.rbegin(), lower.rend());
  d.polygon(band, kBand, kBandOpacity, "band");
  bool shrunk = false;
  for (size_t w = 0; w < n; ++w) shrunk = shrunk || series.shrunk(w, k);
  if (shrunk) guide_lines(d, series, k, a, time, x, y, ylo, yhi);
  d.polyline(lower, kLower, 2, {}, "lower");
  d.polyline(pts(series.q), kNominal, 1.5, {}, "nominal");
  d.polyline(pts(series.upper), kUpper, 2, {}, "upper");
  for (size_t w = 0; w < n; ++w) {  // the waypoints as dots on the bounds (a single one is a dot)
    d.circle(x(x_of(series, time, w)), y(series.lower[w][i]), 2.5, kLower, true, 0, "waypoint");
    d.circle(x(x_of(series, time, w)), y(series.upper[w][i]), 2.5, kUpper, true, 0, "waypoint");
    if (series.collapsed[w][k])
      d.circle(x(x_of(series, time, w)), y(series.q[w][i]), 6, kCollapsed, false, 2, "collapsed",
               "waypoint " + std::to_string(w) + ": collapsed, widened by the guard");
  }
  d.end_group();
}

}  // namespace

namespace detail {

Drawing bounds_drawing(const BoundsSeries& series, int width, int height, PlotX x_axis) {
  detail::check_image_size(width, height, "plot size");
  const size_t dof = series.joints.size();
  const int cols = dof > 3 ? 2 : 1;
  const int rows = static_cast<int>((dof + static_cast<size_t>(cols) - 1) / static_cast<size_t>(cols));
  check_panels(width, height, cols, rows, std::to_string(dof) + " joint panels");
  const bool time = x_axis == PlotX::kTime && series.has_times();
  const double pw = static_cast<double>(width) / cols, ph = (height - kTop) / rows;
  Drawing d;
  d.width = width;
  d.height = height;
  bounds_legend(d, series, time);
  for (size_t k = 0; k < dof; ++k) {
    const double px = static_cast<double>(k % static_cast<size_t>(cols)) * pw;
    const double py = kTop + static_cast<double>(k / static_cast<size_t>(cols)) * ph;
    bounds_panel(d, series, k, {px + 64, py + 24, pw - 84, ph - 60}, time, py);
  }
  return d;
}

}  // namespace detail

std::string bounds_svg(const BoundsSeries& series, int width, int height, PlotX x) {
  return detail::to_svg(detail::bounds_drawing(series, width, height, x));
}

Image bounds_image(const BoundsSeries& series, int width, int height, PlotX x) {
  return detail::to_image(detail::bounds_drawing(series, width, height, x));
}

// ---------------------------------------------------------------------------------------------
// Sweep plots.

// ---------------------------------------------------------------------------------------------
// Sweep plots.

namespace {

// A whole field as a number, read with '.' as the decimal point whatever the locale (std::stod
// follows the C locale's LC_NUMERIC); "nan" and "inf" read as such, for the finiteness check.
bool parse_number(const std::string& text, double& v) {
  const char* end = text.data() + text.size();
  const auto r = std::from_chars(text.data() + (!text.empty() && text[0] == '+'), end, v);
  return !text.empty() && r.ec == std::errc() && r.ptr == end;
}

// The fields of one CSV line as a spreadsheet writes them back: a field may be quoted ("a,b",
// with "" for a quote inside), spaces around a field are dropped, a line may end in CR (CRLF).
std::vector<std::string> csv_fields(std::string line, const std::string& where) {
  if (!line.empty() && line.back() == '\r') line.pop_back();
  std::vector<std::string> fields(1);
  bool quoted = false, was_quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c != '"') {
        fields.back() += c;
      } else if (i + 1 < line.size() && line[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else {
        quoted = false;
      }
    } else if (c == '"' && !was_quoted && fields.back().find_first_not_of(" \t") == std::string::npos) {
      fields.back().clear();
      quoted = was_quoted = true;
    } else if (c == ',') {
      fields.emplace_back();
      was_quoted = false;
    } else if (!(was_quoted && (c == ' ' || c == '\t'))) {
      fields.back() += c;
    }
  }
  if (quoted) throw InputError(where + ": a quoted field is not closed");
  for (auto& f : fields) {
    const size_t b = f.find_first_not_of(" \t"), e = f.find_last_not_of(" \t");
    f = b == std::string::npos ? std::string() : f.substr(b, e - b + 1);
  }
  return fields;
}

}  // namespace

SweepSeries read_sweep_csv(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the sweep CSV file");
  std::string line;
  if (!std::getline(in, line)) throw InputError(path + ": empty sweep CSV file");
  if (line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // a UTF-8 byte order mark
  const auto header = csv_fields(line, path + ": line 1");
  std::vector<size_t> col;
  for (const char* name : {"max_cells", "boxes", "time_ms", "cf"}) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end())
      throw InputError(path + ": line 1 has no column '" + name + "' (a leeway sweep --csv file)");
    col.push_back(static_cast<size_t>(it - header.begin()));
  }
  SweepSeries out{std::filesystem::path(path).stem().string(), {}};
  for (int number = 2; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    if (line == "\r") continue;
    const auto f = csv_fields(line, path + ": line " + std::to_string(number));
    double v[4] = {};
    for (size_t k = 0; k < 4; ++k) {
      const std::string where =
          path + ": line " + std::to_string(number) + " column '" + header[col[k]] + "'";
      if (col[k] >= f.size()) throw InputError(where + " is missing");
      if (!parse_number(f[col[k]], v[k])) throw InputError(where + ": '" + f[col[k]] + "' is not a number");
      if (!std::isfinite(v[k])) throw InputError(where + ": '" + f[col[k]] + "' is not a finite number");
    }
    if (v[0] < 1 || v[0] != std::floor(v[0]) || v[0] > kMaxCellsLimit)
      throw InputError(path + ": line " + std::to_string(number) + ": max_cells " + format_number(v[0]) +
                       " is not a whole number from 1 to 1000000");
    out.points.push_back({static_cast<int>(v[0]), v[1], v[2], 100 * v[3]});
  }
  if (out.points.empty()) throw InputError(path + ": no rows");
  return out;
}

std::vector<SweepPoint> thesis_table(const std::string& cell, const std::string& path, std::string* table) {
  std::vector<SweepPoint> out;
  std::istringstream in(detail::kThesisTablesCsv);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("table,", 0) == 0) continue;
    // table,cell,path,max_cells,boxes,time_ms,cf_percent
    std::vector<std::string> f;
    std::stringstream fields(line);
    for (std::string x; std::getline(fields, x, ',');) f.push_back(x);
    LEEWAY_DEMAND(f.size() == 7);
    if (f[1] != cell || f[2] != path) continue;
    if (table) *table = f[0];
    double v[4] = {};
    for (size_t k = 0; k < 4; ++k) LEEWAY_DEMAND(parse_number(f[3 + k], v[k]));
    out.push_back({static_cast<int>(v[0]), v[1], v[2], v[3]});
  }
  return out;
}

namespace {

struct Quantity {
  const char* key;
  const char* title;
  bool log;
  double SweepPoint::*value;
};
constexpr Quantity kQuantities[] = {{"boxes", "boxes", true, &SweepPoint::boxes},
                                    {"time", "time [ms]", true, &SweepPoint::time_ms},
                                    {"cf", "CF [%]", false, &SweepPoint::cf_percent}};

void check_sweep(const std::vector<SweepSeries>& series, int width, int height) {
  detail::check_image_size(width, height, "plot size");
  bool any = false;
  for (const auto& s : series) any = any || !s.points.empty();
  if (!any) throw InputError("sweep plot: no MAX_cells rows to plot");
  for (const auto& s : series)
    for (const auto& p : s.points)
      if (p.max_cells < 1 || !std::isfinite(p.boxes) || !std::isfinite(p.time_ms) ||
          !std::isfinite(p.cf_percent))
        throw InputError("sweep plot: series '" + s.label + "' has a row at MAX_cells " +
                         std::to_string(p.max_cells) + " that is not finite or positive");
}

double safe_log(double v) { return std::log10(std::max(v, 1e-3)); }

}  // namespace

namespace {

// Decades lo .. hi as ticks labelled 10^e (0.01, 1, 1000).
Ticks decade_ticks(double lo, double hi) {
  Ticks t;
  for (auto e = static_cast<int>(std::lround(lo)); e <= static_cast<int>(std::lround(hi)); ++e) {
    t.values.push_back(e);
    t.labels.push_back(detail::format_fixed(std::pow(10.0, e), std::max(0, -e)));
  }
  return t;
}

void sweep_panel(Drawing& d, const std::vector<SweepSeries>& series, const Quantity& q, const Area& a,
                 double xmin, double xmax) {
  double lo = 1e300, hi = -1e300;
  for (const auto& s : series)
    for (const auto& p : s.points) {
      const double v = q.log ? safe_log(p.*q.value) : p.*q.value;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  if (q.log) {
    lo = std::floor(lo);
    hi = std::max(std::ceil(hi), lo + 1);
  } else {
    std::tie(lo, hi) = padded(lo, hi);
  }
  auto x = [&](double v) { return a.x + (v - xmin) / (xmax - xmin) * a.w; };
  auto y = [&](double v) { return a.y + a.h - (v - lo) / (hi - lo) * a.h; };
  d.group(std::string("class=\"panel\" data-quantity=\"") + q.key + "\"");
  d.label(a.x + a.w / 2, kTop + 16, std::string(q.title) + (q.log ? " (log scale)" : ""), 13, 1, true);
  axes(d, a, decade_ticks(xmin, xmax), q.log ? decade_ticks(lo, hi) : detail::nice_ticks(lo, hi, 5), x, y);
  d.label(a.x + a.w / 2, a.y + a.h + 30, "MAX_cells (log scale)", 10, 1);
  for (size_t s = 0; s < series.size(); ++s) {
    const Rgb c = kSeries[s % std::size(kSeries)];
    Points pts;
    for (const auto& p : series[s].points)
      pts.emplace_back(x(std::log10(p.max_cells)), y(q.log ? safe_log(p.*q.value) : p.*q.value));
    d.polyline(pts, c, 2, s ? kSeriesDash : std::vector<double>{}, "series",
               "data-series=\"" + detail::xml_escape(series[s].label) + "\"");
    for (const auto& [px, py] : pts) d.circle(px, py, 3, c, true, 0);
  }
  d.end_group();
}

}  // namespace

namespace detail {

Drawing sweep_drawing(const std::vector<SweepSeries>& series, const std::string& title, int width,
                      int height) {
  check_sweep(series, width, height);
  check_panels(width, height, 3, 1, "3 panels");
  Drawing d;
  d.width = width;
  d.height = height;
  d.label(width / 2.0, 20, title, 14, 1, true);
  double lx = 20;
  for (size_t s = 0; s < series.size(); ++s)
    lx = legend_line(d, lx, series[s].label, kSeries[s % std::size(kSeries)],
                     s ? kSeriesDash : std::vector<double>{}) +
         10;
  double xmin = 1e300, xmax = -1e300;
  for (const auto& s : series)
    for (const auto& p : s.points) {
      xmin = std::min(xmin, std::log10(p.max_cells));
      xmax = std::max(xmax, std::log10(p.max_cells));
    }
  xmin = std::floor(xmin);
  xmax = std::max(std::ceil(xmax), xmin + 1);
  const double pw = width / 3.0;
  for (size_t qi = 0; qi < std::size(kQuantities); ++qi)
    sweep_panel(d, series, kQuantities[qi],
                {static_cast<double>(qi) * pw + 60, kTop + 24, pw - 80, height - kTop - 70}, xmin, xmax);
  return d;
}

}  // namespace detail

std::string sweep_svg(const std::vector<SweepSeries>& series, const std::string& title, int width,
                      int height) {
  return detail::to_svg(detail::sweep_drawing(series, title, width, height));
}

Image sweep_image(const std::vector<SweepSeries>& series, const std::string& title, int width, int height) {
  return detail::to_image(detail::sweep_drawing(series, title, width, height));
}

}  // namespace leeway
