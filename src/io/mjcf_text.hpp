#pragma once
// Internal: writing MJCF and XML text (numbers that read back exactly, XML escapes), shared by the
// URDF importer, the cell template, the plots and the JUnit report (not part of the public API).

#include <cmath>
#include <cstdlib>
#include <locale>
#include <sstream>
#include <string>

namespace leeway::detail {

//! The shortest text that reads back as the same double (so written kinematics and limits are
//! exact); values within 1e-15 of zero (rounding noise of composed rotations) are written as 0.
inline std::string exact_number(double v) {
  if (std::abs(v) < 1e-15) v = 0;
  std::string text;
  for (int precision = 15; precision <= 17; ++precision) {
    std::ostringstream os;
    os.imbue(std::locale::classic());
    os.precision(precision);
    os << v;
    text = os.str();
    if (std::strtod(text.c_str(), nullptr) == v) break;
  }
  return text;
}

//! `text` escaped for XML attributes and character data: &, <, >, " and ' as entities; tab, line
//! feed and carriage return kept; other control characters (which XML 1.0 does not allow, not even
//! as references) replaced by '?'.
inline std::string xml_escape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      case '\n':
      case '\t':
      case '\r':
        out += c;
        break;
      default:
        out += static_cast<unsigned char>(c) < 0x20 ? '?' : c;
    }
  }
  return out;
}

//! `s` made safe inside an XML comment, which may not contain "--".
inline std::string comment_text(std::string s) {
  for (size_t p = s.find("--"); p != std::string::npos; p = s.find("--", p)) s.replace(p, 2, "- -");
  return s;
}

//! `text` as an XML comment `<!-- text -->` starting at column `indent`, its words wrapped so that
//! lines stay within 100 columns where the words allow (continuation lines under the text's start).
//! Ends with a line feed.
inline std::string wrapped_comment(const std::string& text, size_t indent) {
  const std::string pad(indent, ' ');
  std::string out = pad + "<!--", line_start = pad + "     ";
  size_t column = out.size();
  std::istringstream words(comment_text(text));
  for (std::string w; words >> w;) {
    if (column + 1 + w.size() > 100 && column > line_start.size()) {
      out += "\n" + line_start;
      column = line_start.size();
    } else {
      out += ' ';
      ++column;
    }
    out += w;
    column += w.size();
  }
  return out + " -->\n";
}

}  // namespace leeway::detail
