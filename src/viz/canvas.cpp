#include "canvas.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <sstream>

#include "io/mjcf_text.hpp"

namespace leeway::detail {

namespace {

// The classic 5x7 bitmap font (with descenders in an eighth row) for printable ASCII, 0x20 to 0x7e:
// five columns per glyph, bit 0 the top row.
constexpr std::uint8_t kFont[95][5] = {
    {0x00, 0x00, 0x00, 0x00, 0x00}, {0x00, 0x00, 0x5F, 0x00, 0x00}, {0x00, 0x07, 0x00, 0x07, 0x00},
    {0x14, 0x7F, 0x14, 0x7F, 0x14}, {0x24, 0x2A, 0x7F, 0x2A, 0x12}, {0x23, 0x13, 0x08, 0x64, 0x62},
    {0x36, 0x49, 0x56, 0x20, 0x50}, {0x00, 0x05, 0x03, 0x00, 0x00}, {0x00, 0x1C, 0x22, 0x41, 0x00},
    {0x00, 0x41, 0x22, 0x1C, 0x00}, {0x2A, 0x1C, 0x7F, 0x1C, 0x2A}, {0x08, 0x08, 0x3E, 0x08, 0x08},
    {0x00, 0x80, 0x70, 0x30, 0x00}, {0x08, 0x08, 0x08, 0x08, 0x08}, {0x00, 0x00, 0x60, 0x60, 0x00},
    {0x20, 0x10, 0x08, 0x04, 0x02}, {0x3E, 0x51, 0x49, 0x45, 0x3E}, {0x00, 0x42, 0x7F, 0x40, 0x00},
    {0x42, 0x61, 0x51, 0x49, 0x46}, {0x21, 0x41, 0x45, 0x4B, 0x31}, {0x18, 0x14, 0x12, 0x7F, 0x10},
    {0x27, 0x45, 0x45, 0x45, 0x39}, {0x3C, 0x4A, 0x49, 0x49, 0x30}, {0x01, 0x71, 0x09, 0x05, 0x03},
    {0x36, 0x49, 0x49, 0x49, 0x36}, {0x06, 0x49, 0x49, 0x29, 0x1E}, {0x00, 0x36, 0x36, 0x00, 0x00},
    {0x00, 0x56, 0x36, 0x00, 0x00}, {0x08, 0x14, 0x22, 0x41, 0x00}, {0x14, 0x14, 0x14, 0x14, 0x14},
    {0x00, 0x41, 0x22, 0x14, 0x08}, {0x02, 0x01, 0x51, 0x09, 0x06}, {0x32, 0x49, 0x79, 0x41, 0x3E},
    {0x7E, 0x11, 0x11, 0x11, 0x7E}, {0x7F, 0x49, 0x49, 0x49, 0x36}, {0x3E, 0x41, 0x41, 0x41, 0x22},
    {0x7F, 0x41, 0x41, 0x22, 0x1C}, {0x7F, 0x49, 0x49, 0x49, 0x41}, {0x7F, 0x09, 0x09, 0x09, 0x01},
    {0x3E, 0x41, 0x49, 0x49, 0x7A}, {0x7F, 0x08, 0x08, 0x08, 0x7F}, {0x00, 0x41, 0x7F, 0x41, 0x00},
    {0x20, 0x40, 0x41, 0x3F, 0x01}, {0x7F, 0x08, 0x14, 0x22, 0x41}, {0x7F, 0x40, 0x40, 0x40, 0x40},
    {0x7F, 0x02, 0x0C, 0x02, 0x7F}, {0x7F, 0x04, 0x08, 0x10, 0x7F}, {0x3E, 0x41, 0x41, 0x41, 0x3E},
    {0x7F, 0x09, 0x09, 0x09, 0x06}, {0x3E, 0x41, 0x51, 0x21, 0x5E}, {0x7F, 0x09, 0x19, 0x29, 0x46},
    {0x46, 0x49, 0x49, 0x49, 0x31}, {0x01, 0x01, 0x7F, 0x01, 0x01}, {0x3F, 0x40, 0x40, 0x40, 0x3F},
    {0x1F, 0x20, 0x40, 0x20, 0x1F}, {0x3F, 0x40, 0x38, 0x40, 0x3F}, {0x63, 0x14, 0x08, 0x14, 0x63},
    {0x07, 0x08, 0x70, 0x08, 0x07}, {0x61, 0x51, 0x49, 0x45, 0x43}, {0x00, 0x7F, 0x41, 0x41, 0x00},
    {0x02, 0x04, 0x08, 0x10, 0x20}, {0x00, 0x41, 0x41, 0x7F, 0x00}, {0x04, 0x02, 0x01, 0x02, 0x04},
    {0x40, 0x40, 0x40, 0x40, 0x40}, {0x00, 0x01, 0x02, 0x04, 0x00}, {0x20, 0x54, 0x54, 0x54, 0x78},
    {0x7F, 0x48, 0x44, 0x44, 0x38}, {0x38, 0x44, 0x44, 0x44, 0x20}, {0x38, 0x44, 0x44, 0x48, 0x7F},
    {0x38, 0x54, 0x54, 0x54, 0x18}, {0x08, 0x7E, 0x09, 0x01, 0x02}, {0x18, 0xA4, 0xA4, 0xA4, 0x7C},
    {0x7F, 0x08, 0x04, 0x04, 0x78}, {0x00, 0x44, 0x7D, 0x40, 0x00}, {0x20, 0x40, 0x44, 0x3D, 0x00},
    {0x7F, 0x10, 0x28, 0x44, 0x00}, {0x00, 0x41, 0x7F, 0x40, 0x00}, {0x7C, 0x04, 0x18, 0x04, 0x78},
    {0x7C, 0x08, 0x04, 0x04, 0x78}, {0x38, 0x44, 0x44, 0x44, 0x38}, {0xFC, 0x24, 0x24, 0x24, 0x18},
    {0x18, 0x24, 0x24, 0x18, 0xFC}, {0x7C, 0x08, 0x04, 0x04, 0x08}, {0x48, 0x54, 0x54, 0x54, 0x20},
    {0x04, 0x3F, 0x44, 0x40, 0x20}, {0x3C, 0x40, 0x40, 0x20, 0x7C}, {0x1C, 0x20, 0x40, 0x20, 0x1C},
    {0x3C, 0x40, 0x30, 0x40, 0x3C}, {0x44, 0x28, 0x10, 0x28, 0x44}, {0x1C, 0xA0, 0xA0, 0xA0, 0x7C},
    {0x44, 0x64, 0x54, 0x4C, 0x44}, {0x00, 0x08, 0x36, 0x41, 0x00}, {0x00, 0x00, 0x7F, 0x00, 0x00},
    {0x00, 0x41, 0x36, 0x08, 0x00}, {0x08, 0x04, 0x08, 0x10, 0x08}};

// The font's scale for a text size: one font pixel per image pixel up to 17 px, then two.
int font_scale(double size) { return size >= 18 ? 2 : 1; }

// The shortest text that reads back as v ('.' as the decimal point in any locale).
std::string shortest(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

std::string xy(double x, double y) { return format_fixed(x, 2) + "," + format_fixed(y, 2); }

std::string dash_attr(const std::vector<double>& dash) {
  if (dash.empty()) return "";
  std::string out = " stroke-dasharray=\"";
  for (size_t i = 0; i < dash.size(); ++i) out += (i ? "," : "") + shortest(dash[i]);
  return out + "\"";
}

void svg_item(std::ostringstream& o, const Item& it) {
  const std::string cls = it.cls.empty() ? "" : " class=\"" + it.cls + "\"";
  switch (it.kind) {
    case Item::kGroupBegin:
      o << "<g " << it.attrs << ">\n";
      break;
    case Item::kGroupEnd:
      o << "</g>\n";
      break;
    case Item::kPolyline:
      if (it.points.size() == 2 && it.cls.empty()) {  // grid lines and legend samples
        o << "<line x1=\"" << format_fixed(it.points[0].first, 2) << "\" y1=\""
          << format_fixed(it.points[0].second, 2) << "\" x2=\"" << format_fixed(it.points[1].first, 2)
          << "\" y2=\"" << format_fixed(it.points[1].second, 2) << "\"";
      } else {
        o << "<polyline" << cls << " fill=\"none\" points=\"";
        for (size_t i = 0; i < it.points.size(); ++i)
          o << (i ? " " : "") << xy(it.points[i].first, it.points[i].second);
        o << "\"";
      }
      o << " stroke=\"" << it.stroke.hex() << "\" stroke-width=\"" << shortest(it.width) << "\""
        << dash_attr(it.dash) << (it.attrs.empty() ? "" : " " + it.attrs) << "/>\n";
      break;
    case Item::kPolygon:
      o << "<path" << cls << " d=\"M";
      for (size_t i = 0; i < it.points.size(); ++i)
        o << (i ? " L " : " ") << xy(it.points[i].first, it.points[i].second);
      o << " Z\" fill=\"" << it.fill.hex() << "\"";
      if (it.opacity < 1) o << " fill-opacity=\"" << shortest(it.opacity) << "\"";
      if (it.width > 0)
        o << " stroke=\"" << it.stroke.hex() << "\" stroke-width=\"" << shortest(it.width) << "\"/>\n";
      else
        o << " stroke=\"none\"/>\n";
      break;
    case Item::kCircle:
      o << "<circle" << cls << " cx=\"" << format_fixed(it.x, 2) << "\" cy=\"" << format_fixed(it.y, 2)
        << "\" r=\"" << shortest(it.r) << "\"";
      if (it.filled)
        o << " fill=\"" << it.fill.hex() << "\"";
      else
        o << " fill=\"none\" stroke=\"" << it.stroke.hex() << "\" stroke-width=\"" << shortest(it.width)
          << "\"";
      if (it.text.empty())
        o << "/>\n";
      else
        o << "><title>" << xml_escape(it.text) << "</title></circle>\n";
      break;
    case Item::kText: {
      static const char* const kAnchor[] = {"start", "middle", "end"};
      o << "<text" << cls << " x=\"" << format_fixed(it.x, 2) << "\" y=\"" << format_fixed(it.y, 2)
        << "\" text-anchor=\"" << kAnchor[it.anchor] << "\" font-size=\"" << shortest(it.size) << "\""
        << (it.bold ? " font-weight=\"bold\"" : "") << ">" << xml_escape(it.text) << "</text>\n";
      break;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Rasterising.

class Raster {
 public:
  explicit Raster(const Drawing& d) {
    image_.width = d.width;
    image_.height = d.height;
    image_.rgb.assign(3 * static_cast<size_t>(d.width) * static_cast<size_t>(d.height), 255);
  }
  Image take() { return std::move(image_); }

  // Even-odd scanline fill sampled at pixel centres, blended by `opacity`.
  void fill(const Points& p, const Rgb& c, double opacity) {
    if (p.size() < 3) return;
    double ymin = p[0].second, ymax = ymin;
    for (const auto& v : p) {
      ymin = std::min(ymin, v.second);
      ymax = std::max(ymax, v.second);
    }
    const int r0 = std::max(0, static_cast<int>(std::floor(ymin - 0.5)));
    const int r1 = std::min(image_.height - 1, static_cast<int>(std::ceil(ymax)));
    std::vector<double> xs;
    for (int row = r0; row <= r1; ++row) {
      const double yc = row + 0.5;
      xs.clear();
      for (size_t i = 0; i < p.size(); ++i) {
        const auto& a = p[i];
        const auto& b = p[(i + 1) % p.size()];
        if ((a.second <= yc) != (b.second <= yc))
          xs.push_back(a.first + (yc - a.second) / (b.second - a.second) * (b.first - a.first));
      }
      std::sort(xs.begin(), xs.end());
      for (size_t k = 0; k + 1 < xs.size(); k += 2) {
        const int c0 = std::max(0, static_cast<int>(std::ceil(xs[k] - 0.5)));
        const int c1 = std::min(image_.width - 1, static_cast<int>(std::ceil(xs[k + 1] - 0.5)) - 1);
        for (int col = c0; col <= c1; ++col) blend(col, row, c, opacity);
      }
    }
  }

  // A line of `width` pixels along the polyline, cut into dashes when `dash` is not empty.
  void stroke(const Points& p, const Rgb& c, double width, const std::vector<double>& dash) {
    const double w = std::max(1.0, width);
    std::vector<double> pat = dash;  // an odd pattern repeats once, as in SVG
    if (pat.size() % 2) pat.insert(pat.end(), dash.begin(), dash.end());
    size_t k = 0;
    double left = pat.empty() ? 1e300 : pat[0];  // length left in the current dash or gap
    for (size_t i = 0; i + 1 < p.size(); ++i) {
      const double dx = p[i + 1].first - p[i].first, dy = p[i + 1].second - p[i].second;
      const double len = std::hypot(dx, dy);
      double at = 0;
      while (at < len) {
        const double step = std::min(left, len - at);
        if (k % 2 == 0 && len > 0) segment(p[i], dx / len, dy / len, at, at + step, w, c);
        at += step;
        left -= step;
        if (left <= 1e-9 && !pat.empty()) {
          k = (k + 1) % pat.size();
          left = pat[k];
        }
      }
    }
  }

  void text(const Item& it) {
    const int s = font_scale(it.size);
    double x = it.x - (it.anchor == 0 ? 0 : text_width(it.text, it.size) / (it.anchor == 1 ? 2 : 1));
    const int top = static_cast<int>(std::lround(it.y)) - 7 * s;
    for (const char ch : it.text) {
      const int g = ch >= 0x20 && ch < 0x7f ? ch - 0x20 : '?' - 0x20;
      const int left = static_cast<int>(std::lround(x));
      for (int col = 0; col < 5; ++col)
        for (int row = 0; row < 8; ++row)
          if (kFont[g][col] >> row & 1)
            for (int a = 0; a < s; ++a)
              for (int b = 0; b < s; ++b) blend(left + col * s + a, top + row * s + b, it.stroke, 1);
      x += 6 * s;
    }
  }

 private:
  void segment(const std::pair<double, double>& o, double ux, double uy, double a, double b, double w,
               const Rgb& c) {
    const double nx = -uy * w / 2, ny = ux * w / 2;
    const double ax = o.first + ux * a, ay = o.second + uy * a, bx = o.first + ux * b, by = o.second + uy * b;
    fill({{ax + nx, ay + ny}, {bx + nx, by + ny}, {bx - nx, by - ny}, {ax - nx, ay - ny}}, c, 1);
  }
  void blend(int x, int y, const Rgb& c, double alpha) {
    if (x < 0 || y < 0 || x >= image_.width || y >= image_.height) return;
    unsigned char* px =
        &image_
             .rgb[3 * (static_cast<size_t>(y) * static_cast<size_t>(image_.width) + static_cast<size_t>(x))];
    const double ch[3] = {c.r, c.g, c.b};
    for (int k = 0; k < 3; ++k)
      px[k] = static_cast<unsigned char>(std::lround(alpha * 255 * ch[k] + (1 - alpha) * px[k]));
  }
  Image image_;
};

Points circle_points(double x, double y, double r) {
  Points p;
  constexpr int kSides = 32;
  for (int i = 0; i <= kSides; ++i) {
    const double a = 2 * M_PI * i / kSides;
    p.emplace_back(x + r * std::cos(a), y + r * std::sin(a));
  }
  return p;
}

}  // namespace

std::string Rgb::hex() const {
  static const char* const kDigits = "0123456789abcdef";
  std::string out = "#";
  for (double v : {r, g, b}) {
    const int i = static_cast<int>(std::lround(255 * std::clamp(v, 0.0, 1.0)));
    out += kDigits[i / 16];
    out += kDigits[i % 16];
  }
  return out;
}

void Drawing::group(const std::string& attrs) {
  Item it;
  it.kind = Item::kGroupBegin;
  it.attrs = attrs;
  items.push_back(std::move(it));
}

void Drawing::end_group() {
  Item it;
  it.kind = Item::kGroupEnd;
  items.push_back(std::move(it));
}

void Drawing::polyline(Points pts, const Rgb& c, double line_width, std::vector<double> dash, std::string cls,
                       std::string attrs) {
  Item it;
  it.kind = Item::kPolyline;
  it.points = std::move(pts);
  it.stroke = c;
  it.width = line_width;
  it.dash = std::move(dash);
  it.cls = std::move(cls);
  it.attrs = std::move(attrs);
  items.push_back(std::move(it));
}

void Drawing::polygon(Points pts, const Rgb& fill, double opacity, std::string cls, const Rgb& stroke,
                      double stroke_width) {
  Item it;
  it.kind = Item::kPolygon;
  it.points = std::move(pts);
  it.fill = fill;
  it.opacity = opacity;
  it.cls = std::move(cls);
  it.stroke = stroke;
  it.width = stroke_width;
  items.push_back(std::move(it));
}

void Drawing::rect(double x, double y, double w, double h, const Rgb& fill, const Rgb& stroke,
                   double stroke_width) {
  polygon({{x, y}, {x + w, y}, {x + w, y + h}, {x, y + h}}, fill, 1, "", stroke, stroke_width);
}

void Drawing::circle(double x, double y, double r, const Rgb& c, bool filled, double line_width,
                     std::string cls, std::string title) {
  Item it;
  it.kind = Item::kCircle;
  it.x = x;
  it.y = y;
  it.r = r;
  it.fill = it.stroke = c;
  it.filled = filled;
  it.width = line_width;
  it.cls = std::move(cls);
  it.text = std::move(title);
  items.push_back(std::move(it));
}

void Drawing::label(double x, double y, const std::string& s, double size, int anchor, bool bold,
                    std::string cls) {
  Item it;
  it.kind = Item::kText;
  it.x = x;
  it.y = y;
  it.text = s;
  it.size = size;
  it.anchor = anchor;
  it.bold = bold;
  it.stroke = {0.1, 0.1, 0.1};
  it.cls = std::move(cls);
  items.push_back(std::move(it));
}

std::vector<std::string> Drawing::texts(const std::string& cls) const {
  std::vector<std::string> out;
  for (const auto& it : items)
    if (it.kind == Item::kText && it.cls == cls) out.push_back(it.text);
  return out;
}

std::string to_svg(const Drawing& d) {
  std::ostringstream o;
  o.imbue(std::locale::classic());
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" width=\""
    << d.width << "\" height=\"" << d.height << "\" viewBox=\"0 0 " << d.width << " " << d.height
    << "\" font-family=\"DejaVu Sans, Arial, sans-serif\" font-size=\"12\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  for (const auto& it : d.items) svg_item(o, it);
  o << "</svg>\n";
  return o.str();
}

Image to_image(const Drawing& d) {
  Raster r(d);
  for (const auto& it : d.items) {
    switch (it.kind) {
      case Item::kPolyline:
        r.stroke(it.points, it.stroke, it.width, it.dash);
        break;
      case Item::kPolygon:
        r.fill(it.points, it.fill, it.opacity);
        if (it.width > 0) {
          Points closed = it.points;
          closed.push_back(it.points.front());
          r.stroke(closed, it.stroke, it.width, {});
        }
        break;
      case Item::kCircle:
        if (it.filled)
          r.fill(circle_points(it.x, it.y, it.r), it.fill, 1);
        else
          r.stroke(circle_points(it.x, it.y, it.r), it.stroke, it.width, {});
        break;
      case Item::kText:
        r.text(it);
        break;
      default:
        break;
    }
  }
  return r.take();
}

std::string format_fixed(double v, int digits) {
  char buf[400];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v, std::chars_format::fixed, std::max(0, digits));
  std::string out(buf, r.ptr);
  if (out[0] == '-' && out.find_first_not_of("-0.") == std::string::npos) out.erase(0, 1);
  return out;
}

Ticks nice_ticks(double lo, double hi, int n) {
  Ticks out;
  if (!(hi > lo)) return out;
  const double raw = (hi - lo) / std::max(1, n);
  const int e = static_cast<int>(std::floor(std::log10(raw)));
  const double mag = std::pow(10.0, e);
  int f = 10;
  for (int m : {1, 2, 5})
    if (m * mag >= raw * (1 - 1e-9)) {
      f = m;
      break;
    }
  const double step = f * mag;
  const int digits = f == 10 ? std::max(0, -e - 1) : std::max(0, -e);
  for (auto k = static_cast<long long>(std::ceil(lo / step - 1e-9));
       static_cast<double>(k) * step <= hi + 1e-9 * step; ++k) {
    // k * f * 10^e computed as an exact integer times a power of ten: 0.3, not 0.30000000000000004.
    const double v =
        e >= 0 ? static_cast<double>(k * f) * mag : static_cast<double>(k * f) / std::pow(10.0, -e);
    out.values.push_back(v);
    out.labels.push_back(format_fixed(v, digits));
  }
  return out;
}

double text_width(const std::string& s, double size) {
  const int k = font_scale(size);
  return s.empty() ? 0 : static_cast<double>(6 * k * static_cast<int>(s.size()) - k);
}

}  // namespace leeway::detail
