#include "leeway/viz/plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

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

// ---------------------------------------------------------------------------------------------
// Shared: axis ticks, numbers, colours.

std::string fixed(double v, int digits = 2) {
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

// A tick label: up to 4 significant digits, no trailing zeros.
std::string tick_label(double v) {
  if (std::abs(v) < 1e-12) return "0";
  char buf[48];
  if (std::abs(v) >= 1e4 && std::abs(v) < 1e9 && v == std::round(v)) {  // 10000, not 1e+04
    std::snprintf(buf, sizeof(buf), "%.0f", v);
    return buf;
  }
  std::snprintf(buf, sizeof(buf), "%.4g", v);
  return buf;
}

std::string escape(const std::string& s) { return detail::xml_escape(s); }

// About `n` ticks at 1, 2 or 5 times a power of ten within [lo, hi].
std::vector<double> nice_ticks(double lo, double hi, int n) {
  const double raw = (hi - lo) / std::max(1, n);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double f : {1.0, 2.0, 5.0, 10.0})
    if (f * mag >= raw) {
      step = f * mag;
      break;
    }
  std::vector<double> out;
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step; t += step)
    out.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  return out;
}

// The y range of a panel: the data's, padded by 5 % (or +-0.1 when flat).
std::pair<double, double> padded(double lo, double hi) {
  if (!(hi > lo)) return {lo - 0.1, hi + 0.1};
  const double pad = 0.05 * (hi - lo);
  return {lo - pad, hi + pad};
}

struct Rgb {
  float r, g, b;
  std::string hex() const {
    char buf[8];
    std::snprintf(buf, sizeof(buf), "#%02x%02x%02x", static_cast<int>(std::lround(255 * r)),
                  static_cast<int>(std::lround(255 * g)), static_cast<int>(std::lround(255 * b)));
    return buf;
  }
};
constexpr Rgb kLower{0.13f, 0.44f, 0.71f}, kUpper{0.80f, 0.09f, 0.11f}, kNominal{0.1f, 0.1f, 0.1f};
constexpr Rgb kGuide{0.55f, 0.55f, 0.55f}, kCollapsed{1.0f, 0.5f, 0.0f}, kBand{0.62f, 0.79f, 0.88f};
constexpr Rgb kSeries[] = {
    {0.13f, 0.44f, 0.71f}, {0.90f, 0.45f, 0.05f}, {0.2f, 0.6f, 0.2f}, {0.5f, 0.3f, 0.6f}};

// A minimal SVG writer: every coordinate in pixels with two decimals (deterministic text).
class Svg {
 public:
  Svg(int width, int height) {
    o_ << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" width=\""
       << width << "\" height=\"" << height << "\" viewBox=\"0 0 " << width << " " << height
       << "\" font-family=\"DejaVu Sans, Arial, sans-serif\" font-size=\"12\">\n"
       << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  }
  void raw(const std::string& s) { o_ << s; }
  void text(double x, double y, const std::string& s, const char* anchor = "start", int size = 12,
            const char* extra = "") {
    o_ << "<text x=\"" << fixed(x) << "\" y=\"" << fixed(y) << "\" text-anchor=\"" << anchor
       << "\" font-size=\"" << size << "\"" << extra << ">" << escape(s) << "</text>\n";
  }
  void line(double x1, double y1, double x2, double y2, const std::string& stroke, double width = 1,
            const char* extra = "") {
    o_ << "<line x1=\"" << fixed(x1) << "\" y1=\"" << fixed(y1) << "\" x2=\"" << fixed(x2) << "\" y2=\""
       << fixed(y2) << "\" stroke=\"" << stroke << "\" stroke-width=\"" << width << "\"" << extra << "/>\n";
  }
  void polyline(const std::vector<std::pair<double, double>>& pts, const std::string& cls, const Rgb& c,
                double width, const char* extra = "") {
    o_ << "<polyline class=\"" << cls << "\" fill=\"none\" stroke=\"" << c.hex() << "\" stroke-width=\""
       << width << "\"" << extra << " points=\"";
    for (size_t i = 0; i < pts.size(); ++i)
      o_ << (i ? " " : "") << fixed(pts[i].first) << "," << fixed(pts[i].second);
    o_ << "\"/>\n";
  }
  std::string str() { return o_.str() + "</svg>\n"; }

 private:
  std::ostringstream o_;
};

// A rectangle of the image: the plot area of one panel.
struct Area {
  double x, y, w, h;
};

// Axes, grid and tick labels of a panel; x and y map data to pixels.
template <class X, class Y>
void axes(Svg& svg, const Area& a, const std::vector<double>& xt, const std::vector<std::string>& xl,
          const std::vector<double>& yt, const std::vector<std::string>& yl, X&& x, Y&& y) {
  svg.raw("<rect x=\"" + fixed(a.x) + "\" y=\"" + fixed(a.y) + "\" width=\"" + fixed(a.w) + "\" height=\"" +
          fixed(a.h) + "\" fill=\"#fafafa\" stroke=\"#444\" stroke-width=\"1\"/>\n");
  for (size_t i = 0; i < xt.size(); ++i) {
    svg.line(x(xt[i]), a.y, x(xt[i]), a.y + a.h, "#ddd");
    svg.text(x(xt[i]), a.y + a.h + 14, xl[i], "middle", 10);
  }
  for (size_t i = 0; i < yt.size(); ++i) {
    svg.line(a.x, y(yt[i]), a.x + a.w, y(yt[i]), "#ddd");
    svg.text(a.x - 4, y(yt[i]) + 3.5, yl[i], "end", 10);
  }
}

std::vector<std::string> labels(const std::vector<double>& v) {
  std::vector<std::string> out;
  for (double t : v) out.push_back(tick_label(t));
  return out;
}

// ---------------------------------------------------------------------------------------------
// MuJoCo figures (PNG output).

// An empty model: mjr_makeContext needs one for its offscreen buffer size and fonts.
ModelPtr empty_model() { return load_model_text("<mujoco model=\"leeway_plot\"/>", "leeway_plot.xml"); }

std::unique_ptr<mjvFigure> new_figure(const std::string& title, const std::string& xlabel) {
  auto fig = std::make_unique<mjvFigure>();
  mjv_defaultFigure(fig.get());
  fig->flg_legend = 0;  // one legend for all panels, in the image's title band
  fig->flg_extend = 0;
  fig->linewidth = 2;
  fig->gridsize[0] = 5;
  fig->gridsize[1] = 5;
  const float white[4] = {1, 1, 1, 1}, pane[4] = {0.98f, 0.98f, 0.98f, 1}, legend[4] = {1, 1, 1, 0.8f};
  std::memcpy(fig->figurergba, white, sizeof(white));
  std::memcpy(fig->panergba, pane, sizeof(pane));
  std::memcpy(fig->legendrgba, legend, sizeof(legend));
  const float text[3] = {0.1f, 0.1f, 0.1f}, grid[3] = {0.75f, 0.75f, 0.75f};
  std::memcpy(fig->textrgb, text, sizeof(text));
  std::memcpy(fig->gridrgb, grid, sizeof(grid));
  std::snprintf(fig->title, sizeof(fig->title), "%s", title.c_str());
  std::snprintf(fig->xlabel, sizeof(fig->xlabel), "%s", xlabel.c_str());
  std::snprintf(fig->yformat, sizeof(fig->yformat), "%%.3g");
  std::snprintf(fig->xformat, sizeof(fig->xformat), "%%.2g");
  return fig;
}

// Adds a line (at most mjMAXLINEPNT points: longer series are thinned evenly); returns its index.
int add_line(mjvFigure& fig, int& n, const std::string& name, const Rgb& c,
             const std::vector<std::pair<double, double>>& pts) {
  if (n >= mjMAXLINE || pts.empty()) return -1;
  const size_t stride = (pts.size() + mjMAXLINEPNT - 1) / mjMAXLINEPNT;
  int k = 0;
  for (size_t i = 0; i < pts.size(); i += stride, ++k) {
    fig.linedata[n][2 * k] = static_cast<float>(pts[i].first);
    fig.linedata[n][2 * k + 1] = static_cast<float>(pts[i].second);
  }
  fig.linepnt[n] = k;
  fig.linergb[n][0] = c.r;
  fig.linergb[n][1] = c.g;
  fig.linergb[n][2] = c.b;
  std::snprintf(fig.linename[n], sizeof(fig.linename[n]), "%s", name.c_str());
  return n++;
}

// Two lines of text at the top of the image: a title and a legend.
void title_band(detail::OffscreenContext& gl, const std::string& title, const std::string& legend) {
  const mjrRect v = gl.viewport();
  mjr_label({0, v.height - 32, v.width, 32}, mjFONT_NORMAL, title.c_str(), 1, 1, 1, 1, 0.1f, 0.1f, 0.1f,
            &gl.mjr());
  mjr_label({0, v.height - 64, v.width, 32}, mjFONT_NORMAL, legend.c_str(), 1, 1, 1, 1, 0.3f, 0.3f, 0.3f,
            &gl.mjr());
}

// Panels in a grid of `cols` columns filling the image below a `top` band.
mjrRect cell_rect(int i, int cols, int rows, int width, int height, int top) {
  const int w = width / cols, h = (height - top) / rows;
  const int r = i / cols, c = i % cols;
  return {c * w, height - top - (r + 1) * h, w, h};  // OpenGL rows count from the bottom
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
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": unexpected content: " + e.what());
  }
  const size_t n = out.q.size();
  for (size_t w = 0; w < n; ++w)
    out.s.push_back(n > 1 ? static_cast<double>(w) / static_cast<double>(n - 1) : 0.0);
  return out;
}

std::string bounds_svg(const BoundsSeries& series, int width, int height) {
  detail::check_image_size(width, height, "plot size");
  const size_t dof = series.joints.size(), n = series.q.size();
  const int cols = dof > 3 ? 2 : 1;
  const int rows = static_cast<int>((dof + static_cast<size_t>(cols) - 1) / static_cast<size_t>(cols));
  const double top = 58;
  const double pw = static_cast<double>(width) / cols, ph = (height - top) / rows;
  Svg svg(width, height);
  svg.text(width / 2.0, 20, "Joint bounds along the path: " + series.source + " (SI units: rad, m)", "middle",
           14, " font-weight=\"bold\"");
  // Legend.
  struct Entry {
    const char* label;
    Rgb c;
    const char* dash;
  };
  const Entry legend[] = {{"lower bound", kLower, ""},
                          {"nominal", kNominal, ""},
                          {"upper bound", kUpper, ""},
                          {"before the safety stage (shrunk)", kGuide, " stroke-dasharray=\"5,3\""}};
  double lx = 20;
  for (const auto& e : legend) {
    svg.line(lx, 40, lx + 24, 40, e.c.hex(), 2, e.dash);
    svg.text(lx + 30, 44, e.label);
    lx += 40 + 7.0 * static_cast<double>(std::strlen(e.label));
  }
  svg.raw("<circle cx=\"" + fixed(lx + 6) + "\" cy=\"40\" r=\"5\" fill=\"none\" stroke=\"" +
          kCollapsed.hex() + "\" stroke-width=\"2\"/>\n");
  svg.text(lx + 16, 44, "collapsed (widened by the guard)");

  for (size_t k = 0; k < dof; ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    const double px = static_cast<double>(k % static_cast<size_t>(cols)) * pw;
    const double py = top + static_cast<double>(k / static_cast<size_t>(cols)) * ph;
    const Area a{px + 64, py + 24, pw - 84, ph - 60};
    double lo = series.q[0][i], hi = lo;
    for (size_t w = 0; w < n; ++w) {
      lo = std::min({lo, series.lower[w][i], series.guide_lower[w][i]});
      hi = std::max({hi, series.upper[w][i], series.guide_upper[w][i]});
    }
    const auto [ylo, yhi] = padded(lo, hi);
    auto x = [&a](double s) { return a.x + s * a.w; };
    auto y = [&a, ylo = ylo, yhi = yhi](double v) { return a.y + a.h - (v - ylo) / (yhi - ylo) * a.h; };
    svg.raw("<g class=\"joint\" data-joint=\"" + escape(series.joints[k]) + "\">\n");
    const std::string kind = series.kinds[k].empty() ? "" : ", " + series.kinds[k];
    svg.text(a.x + a.w / 2, py + 16, series.joints[k] + " [" + series.unit(k) + "]" + kind, "middle", 13,
             " font-weight=\"bold\"");
    const std::vector<double> xt = {0, 0.25, 0.5, 0.75, 1}, yt = nice_ticks(ylo, yhi, 4);
    axes(svg, a, xt, labels(xt), yt, labels(yt), x, y);
    svg.text(a.x + a.w / 2, a.y + a.h + 30,
             "path parameter s = k / (n - 1) at waypoint k; lines join the waypoints", "middle", 10);
    // The band between the bounds.
    std::string d = "M";
    for (size_t w = 0; w < n; ++w) d += " " + fixed(x(series.s[w])) + "," + fixed(y(series.upper[w][i]));
    for (size_t w = n; w-- > 0;) d += " L " + fixed(x(series.s[w])) + "," + fixed(y(series.lower[w][i]));
    svg.raw("<path class=\"band\" d=\"" + d + " Z\" fill=\"" + kBand.hex() +
            "\" fill-opacity=\"0.5\" stroke=\"none\"/>\n");
    auto pts = [&](const std::vector<Eigen::VectorXd>& v) {
      std::vector<std::pair<double, double>> out;
      for (size_t w = 0; w < n; ++w) out.emplace_back(x(series.s[w]), y(v[w][i]));
      return out;
    };
    bool shrunk = false;
    for (size_t w = 0; w < n; ++w) shrunk = shrunk || series.shrunk(w, k);
    if (shrunk) {
      svg.polyline(pts(series.guide_lower), "guide-lower", kGuide, 1.5, " stroke-dasharray=\"5,3\"");
      svg.polyline(pts(series.guide_upper), "guide-upper", kGuide, 1.5, " stroke-dasharray=\"5,3\"");
    }
    svg.polyline(pts(series.lower), "lower", kLower, 2);
    svg.polyline(pts(series.q), "nominal", kNominal, 1.5);
    svg.polyline(pts(series.upper), "upper", kUpper, 2);
    // Single points (a one-waypoint file) and the waypoints themselves as dots on the bounds.
    for (size_t w = 0; w < n; ++w) {
      for (const auto* v : {&series.lower, &series.upper})
        svg.raw("<circle class=\"waypoint\" cx=\"" + fixed(x(series.s[w])) + "\" cy=\"" +
                fixed(y((*v)[w][i])) + "\" r=\"2.5\" fill=\"" + (v == &series.lower ? kLower : kUpper).hex() +
                "\"/>\n");
      if (series.collapsed[w][k])
        svg.raw("<circle class=\"collapsed\" cx=\"" + fixed(x(series.s[w])) + "\" cy=\"" +
                fixed(y(series.q[w][i])) + "\" r=\"6\" fill=\"none\" stroke=\"" + kCollapsed.hex() +
                "\" stroke-width=\"2\"><title>waypoint " + std::to_string(w) +
                ": collapsed, widened by the guard</title></circle>\n");
    }
    svg.raw("</g>\n");
  }
  return svg.str();
}

Image bounds_image(const BoundsSeries& series, int width, int height) {
  detail::check_image_size(width, height, "plot size");
  const size_t dof = series.joints.size(), n = series.q.size();
  const int cols = dof > 3 ? 2 : 1;
  const int rows = static_cast<int>((dof + static_cast<size_t>(cols) - 1) / static_cast<size_t>(cols));
  ModelPtr model = empty_model();
  detail::OffscreenContext gl(*model, width, height);
  mjr_rectangle(gl.viewport(), 1, 1, 1, 1);
  const int top = 64;
  title_band(gl, "Joint bounds along the path (SI units: rad, m): " + series.source,
             "lower: blue, nominal: black, upper: red, before the safety stage: grey, collapsed: orange");
  for (size_t k = 0; k < dof; ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    const std::string kind = series.kinds[k].empty() ? "" : ", " + series.kinds[k];
    auto fig = new_figure(series.joints[k] + " [" + series.unit(k) + "]" + kind, "path parameter s");
    int lines = 0;
    auto pts = [&](const std::vector<Eigen::VectorXd>& v) {
      std::vector<std::pair<double, double>> out;
      for (size_t w = 0; w < n; ++w) out.emplace_back(series.s[w], v[w][i]);
      return out;
    };
    double lo = series.q[0][i], hi = lo;
    bool shrunk = false;
    for (size_t w = 0; w < n; ++w) {
      lo = std::min({lo, series.lower[w][i], series.guide_lower[w][i]});
      hi = std::max({hi, series.upper[w][i], series.guide_upper[w][i]});
      shrunk = shrunk || series.shrunk(w, k);
    }
    const auto [ylo, yhi] = padded(lo, hi);
    fig->range[0][0] = 0;
    fig->range[0][1] = 1;
    fig->range[1][0] = static_cast<float>(ylo);
    fig->range[1][1] = static_cast<float>(yhi);
    add_line(*fig, lines, "lower", kLower, pts(series.lower));
    add_line(*fig, lines, "nominal", kNominal, pts(series.q));
    add_line(*fig, lines, "upper", kUpper, pts(series.upper));
    if (shrunk) {
      add_line(*fig, lines, "before safety", kGuide, pts(series.guide_lower));
      add_line(*fig, lines, "", kGuide, pts(series.guide_upper));
    }
    // Collapsed intervals: a short vertical mark through the nominal value.
    bool named = false;
    for (size_t w = 0; w < n; ++w)
      if (series.collapsed[w][k]) {
        const double h = 0.06 * (yhi - ylo);
        add_line(*fig, lines, named ? "" : "collapsed", kCollapsed,
                 {{series.s[w], series.q[w][i] - h}, {series.s[w], series.q[w][i] + h}});
        named = true;
      }
    mjr_figure(cell_rect(static_cast<int>(k), cols, rows, width, height, top), fig.get(), &gl.mjr());
  }
  return gl.read();
}

// ---------------------------------------------------------------------------------------------
// Sweep plots.

namespace {

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
      try {
        size_t used = 0;
        v[k] = std::stod(f[col[k]], &used);
        if (used != f[col[k]].size()) throw std::invalid_argument("trailing text");
      } catch (const std::exception&) {
        throw InputError(where + ": '" + f[col[k]] + "' is not a number");
      }
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
    out.push_back({std::stoi(f[3]), std::stod(f[4]), std::stod(f[5]), std::stod(f[6])});
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

std::string sweep_svg(const std::vector<SweepSeries>& series, const std::string& title, int width,
                      int height) {
  check_sweep(series, width, height);
  Svg svg(width, height);
  svg.text(width / 2.0, 20, title, "middle", 14, " font-weight=\"bold\"");
  // Legend.
  double lx = 20;
  for (size_t s = 0; s < series.size(); ++s) {
    const Rgb c = kSeries[s % std::size(kSeries)];
    svg.line(lx, 40, lx + 24, 40, c.hex(), 2, s ? " stroke-dasharray=\"6,3\"" : "");
    svg.text(lx + 30, 44, series[s].label);
    lx += 50 + 7.0 * static_cast<double>(series[s].label.size());
  }
  double xmin = 1e300, xmax = -1e300;
  for (const auto& s : series)
    for (const auto& p : s.points) {
      xmin = std::min(xmin, std::log10(p.max_cells));
      xmax = std::max(xmax, std::log10(p.max_cells));
    }
  xmin = std::floor(xmin);
  xmax = std::max(std::ceil(xmax), xmin + 1);
  const double top = 58, pw = width / 3.0;
  for (size_t qi = 0; qi < std::size(kQuantities); ++qi) {
    const Quantity& q = kQuantities[qi];
    const Area a{static_cast<double>(qi) * pw + 60, top + 24, pw - 80, height - top - 70};
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
    std::vector<double> xt, yt;
    std::vector<std::string> xl, yl;
    for (double e = xmin; e <= xmax + 1e-9; e += 1) {
      xt.push_back(e);
      xl.push_back(tick_label(std::pow(10.0, e)));
    }
    if (q.log) {
      for (double e = lo; e <= hi + 1e-9; e += 1) {
        yt.push_back(e);
        yl.push_back(tick_label(std::pow(10.0, e)));
      }
    } else {
      yt = nice_ticks(lo, hi, 5);
      yl = labels(yt);
    }
    svg.raw(std::string("<g class=\"panel\" data-quantity=\"") + q.key + "\">\n");
    svg.text(a.x + a.w / 2, top + 16, std::string(q.title) + (q.log ? " (log scale)" : ""), "middle", 13,
             " font-weight=\"bold\"");
    axes(svg, a, xt, xl, yt, yl, x, y);
    svg.text(a.x + a.w / 2, a.y + a.h + 30, "MAX_cells (log scale)", "middle", 10);
    for (size_t s = 0; s < series.size(); ++s) {
      const Rgb c = kSeries[s % std::size(kSeries)];
      std::vector<std::pair<double, double>> pts;
      for (const auto& p : series[s].points)
        pts.emplace_back(x(std::log10(p.max_cells)), y(q.log ? safe_log(p.*q.value) : p.*q.value));
      const std::string attr =
          " data-series=\"" + escape(series[s].label) + "\"" + (s ? " stroke-dasharray=\"6,3\"" : "");
      svg.polyline(pts, "series", c, 2, attr.c_str());
      for (const auto& [px, py] : pts)
        svg.raw("<circle cx=\"" + fixed(px) + "\" cy=\"" + fixed(py) + "\" r=\"3\" fill=\"" + c.hex() +
                "\"/>\n");
    }
    svg.raw("</g>\n");
  }
  return svg.str();
}

Image sweep_image(const std::vector<SweepSeries>& series, const std::string& title, int width, int height) {
  check_sweep(series, width, height);
  ModelPtr model = empty_model();
  detail::OffscreenContext gl(*model, width, height);
  mjr_rectangle(gl.viewport(), 1, 1, 1, 1);
  const int top = 64;
  std::string legend;
  const char* const kNames[] = {"blue", "orange", "green", "purple"};
  for (size_t s = 0; s < series.size(); ++s)
    legend += (s ? ", " : "") + series[s].label + ": " + kNames[s % std::size(kNames)];
  title_band(gl, title, legend);
  for (size_t qi = 0; qi < std::size(kQuantities); ++qi) {
    const Quantity& q = kQuantities[qi];
    auto fig = new_figure(std::string(q.title) + (q.log ? " (log10)" : ""), "log10 MAX_cells");
    fig->flg_extend = 1;
    fig->range[0][0] = fig->range[0][1] = 0;  // min >= max: automatic
    fig->range[1][0] = fig->range[1][1] = 0;
    int lines = 0;
    for (size_t s = 0; s < series.size(); ++s) {
      std::vector<std::pair<double, double>> pts;
      for (const auto& p : series[s].points)
        pts.emplace_back(std::log10(p.max_cells), q.log ? safe_log(p.*q.value) : p.*q.value);
      add_line(*fig, lines, series[s].label, kSeries[s % std::size(kSeries)], pts);
    }
    mjr_figure(cell_rect(static_cast<int>(qi), 3, 1, width, height, top), fig.get(), &gl.mjr());
  }
  return gl.read();
}

}  // namespace leeway
