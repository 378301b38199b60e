#pragma once
// Internal: writing MJCF text (numbers that read back exactly, XML escapes), shared by the URDF
// importer and the cell template (not part of the public API).

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

//! `s` with &, <, > and " escaped for an XML attribute.
inline std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '&')
      out += "&amp;";
    else if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '"')
      out += "&quot;";
    else
      out += c;
  }
  return out;
}

//! `s` made safe inside an XML comment, which may not contain "--".
inline std::string comment_text(std::string s) {
  for (size_t p = s.find("--"); p != std::string::npos; p = s.find("--", p)) s.replace(p, 2, "- -");
  return s;
}

}  // namespace leeway::detail
