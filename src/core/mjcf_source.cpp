#include "leeway/core/mjcf_source.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "leeway/core/file_io.hpp"

namespace leeway {
namespace {

namespace fs = std::filesystem;

// An element's start tag as read from the text: attributes with entities decoded.
struct XmlElement {
  std::string tag;
  std::vector<std::pair<std::string, std::string>> attributes;
  int line = 0;
  int parent = -1;  // index of the enclosing element, -1 at the top

  const std::string* attribute(const std::string& name) const {
    for (const auto& [key, value] : attributes)
      if (key == name) return &value;
    return nullptr;
  }
};

// How deep elements may nest; MuJoCo's XML parser (tinyxml2) stops far earlier.
constexpr int kMaxDepth = 1000;
// How deep includes may nest (as volume_mjcf).
constexpr int kMaxIncludeDepth = 16;

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

// `text` with XML's predefined entities and character references decoded (as tinyxml2 does for
// attribute values); an unknown or malformed reference stays as written.
std::string decode_entities(const std::string& text) {
  if (text.find('&') == std::string::npos) return text;
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '&') {
      out += text[i];
      continue;
    }
    const size_t semi = text.find(';', i);
    if (semi == std::string::npos || semi - i > 12) {
      out += text[i];
      continue;
    }
    const std::string ref = text.substr(i + 1, semi - i - 1);
    static const std::pair<const char*, char> kNamed[] = {
        {"lt", '<'}, {"gt", '>'}, {"amp", '&'}, {"quot", '"'}, {"apos", '\''}};
    bool decoded = false;
    for (const auto& [name, ch] : kNamed)
      if (ref == name) {
        out += ch;
        decoded = true;
      }
    if (!decoded && ref.size() > 1 && ref[0] == '#') {
      const bool hex = ref[1] == 'x' || ref[1] == 'X';
      const std::string digits = ref.substr(hex ? 2 : 1);
      char* end = nullptr;
      errno = 0;
      const unsigned long code = std::strtoul(digits.c_str(), &end, hex ? 16 : 10);
      if (!digits.empty() && *end == '\0' && errno == 0 && code > 0 && code <= 0x10FFFF) {
        // UTF-8, as tinyxml2 writes a character reference into the value.
        if (code < 0x80) {
          out += static_cast<char>(code);
        } else if (code < 0x800) {
          out += static_cast<char>(0xC0 | (code >> 6));
          out += static_cast<char>(0x80 | (code & 0x3F));
        } else if (code < 0x10000) {
          out += static_cast<char>(0xE0 | (code >> 12));
          out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
          out += static_cast<char>(0x80 | (code & 0x3F));
        } else {
          out += static_cast<char>(0xF0 | (code >> 18));
          out += static_cast<char>(0x80 | ((code >> 12) & 0x3F));
          out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
          out += static_cast<char>(0x80 | (code & 0x3F));
        }
        decoded = true;
      }
    }
    if (!decoded) {
      out += text[i];
      continue;
    }
    i = semi;
  }
  return out;
}

// The start tags of `text` in document order, with their nesting. A scanner rather than a tree
// parser: it never recurses (a deeply nested file cannot exhaust the stack) and needs no library
// beyond MuJoCo's, which parses the file itself afterwards and reports what is not well-formed.
// Comments, CDATA sections, processing instructions and the DOCTYPE are skipped.
// @throws MjcfSyntaxError naming `file` and the line for an unterminated markup or nesting beyond
// kMaxDepth.
std::vector<XmlElement> scan_elements(const std::string& text, const std::string& file) {
  std::vector<XmlElement> elements;
  std::vector<int> open;  // the enclosing elements
  size_t i = 0;
  int line = 1;
  size_t counted = 0;  // `line` counts the line feeds before this position
  auto line_at = [&](size_t pos) {
    for (; counted < pos && counted < text.size(); ++counted)
      if (text[counted] == '\n') ++line;
    return line;
  };
  auto fail = [&](size_t pos, const std::string& what) {
    throw MjcfSyntaxError(file + ": line " + std::to_string(line_at(pos)) + ": " + what);
  };
  auto skip_past = [&](size_t from, const char* end, const char* what) {
    const size_t at = text.find(end, from);
    if (at == std::string::npos) fail(from, std::string("unterminated ") + what);
    return at + std::char_traits<char>::length(end);
  };
  while (true) {
    const size_t lt = text.find('<', i);
    if (lt == std::string::npos) break;
    if (text.compare(lt, 4, "<!--") == 0) {
      i = skip_past(lt + 4, "-->", "comment");
    } else if (text.compare(lt, 9, "<![CDATA[") == 0) {
      i = skip_past(lt + 9, "]]>", "CDATA section");
    } else if (text.compare(lt, 2, "<?") == 0) {
      i = skip_past(lt + 2, "?>", "processing instruction");
    } else if (text.compare(lt, 2, "<!") == 0) {
      // <!DOCTYPE ...> with an optional internal subset in brackets.
      size_t k = lt + 2;
      int brackets = 0;
      for (; k < text.size(); ++k) {
        if (text[k] == '[') ++brackets;
        if (text[k] == ']') --brackets;
        if (text[k] == '>' && brackets <= 0) break;
      }
      if (k >= text.size()) fail(lt, "unterminated <! declaration");
      i = k + 1;
    } else if (text.compare(lt, 2, "</") == 0) {
      i = skip_past(lt + 2, ">", "end tag");
      if (!open.empty()) open.pop_back();
    } else {
      XmlElement e;
      e.line = line_at(lt);
      e.parent = open.empty() ? -1 : open.back();
      size_t k = lt + 1;
      while (k < text.size() && !is_space(text[k]) && text[k] != '/' && text[k] != '>') ++k;
      e.tag = text.substr(lt + 1, k - lt - 1);
      if (e.tag.empty()) fail(lt, "a '<' that starts no element");
      bool closed = false;
      while (true) {
        while (k < text.size() && is_space(text[k])) ++k;
        if (k >= text.size()) fail(lt, "unterminated start tag <" + e.tag + ">");
        if (text[k] == '>') {
          ++k;
          break;
        }
        if (text.compare(k, 2, "/>") == 0) {
          k += 2;
          closed = true;
          break;
        }
        const size_t name_start = k;
        while (k < text.size() && !is_space(text[k]) && text[k] != '=' && text[k] != '>' && text[k] != '/')
          ++k;
        const std::string name = text.substr(name_start, k - name_start);
        while (k < text.size() && is_space(text[k])) ++k;
        if (name.empty() || k >= text.size() || text[k] != '=')
          fail(lt, "attribute '" + name + "' of <" + e.tag + "> has no value");
        ++k;
        while (k < text.size() && is_space(text[k])) ++k;
        if (k >= text.size() || (text[k] != '"' && text[k] != '\''))
          fail(lt, "attribute '" + name + "' of <" + e.tag + "> has no quoted value");
        const size_t close = text.find(text[k], k + 1);
        if (close == std::string::npos)
          fail(lt, "attribute '" + name + "' of <" + e.tag + "> is unterminated");
        e.attributes.emplace_back(name, decode_entities(text.substr(k + 1, close - k - 1)));
        k = close + 1;
      }
      elements.push_back(std::move(e));
      if (!closed) {
        open.push_back(static_cast<int>(elements.size()) - 1);
        if (static_cast<int>(open.size()) > kMaxDepth)
          fail(lt, "elements nest deeper than " + std::to_string(kMaxDepth) + " levels");
      }
      i = k;
    }
  }
  return elements;
}

// Attributes whose values are numbers in every element that has them (MuJoCo 2.2.2's schema);
// names that are a number in one element and a name in another (joint, actuator, camera, light,
// com, inertia, data) are decided by their element in is_numeric.
const std::set<std::string>& numeric_attributes() {
  static const std::set<std::string> kNames = {
      // frames and sizes (body, geom, site, joint, inertial, camera, light, frames of equalities)
      "pos", "quat", "axisangle", "xyaxes", "zaxis", "euler", "size", "fromto", "axis", "dir", "anchor",
      "relpose", "refpos", "refquat", "scale", "fitscale",
      // joints, tendons and their limits
      "range", "ref", "springref", "springdamper", "stiffness", "damping", "armature", "frictionloss",
      "springlength", "width", "polycoef", "torquescale", "divisor", "coef",
      // contact
      "margin", "gap", "friction", "solmix", "solref", "solimp", "solreflimit", "solimplimit",
      "solreffriction", "solimpfriction", "solrefsmooth", "solimpsmooth", "solreffix", "solimpfix",
      // inertia
      "mass", "density", "diaginertia", "fullinertia", "fluidcoef", "boundmass", "boundinertia",
      "settotalmass",
      // actuators and sensors
      "ctrlrange", "forcerange", "actrange", "lengthrange", "gear", "cranklength", "dynprm", "gainprm",
      "biasprm", "kp", "kv", "timeconst", "area", "diameter", "bias", "gain", "lmin", "lmax", "vmax", "fpmax",
      "fvmax", "force", "noise", "cutoff", "user",
      // keyframes
      "time", "qpos", "qvel", "act", "ctrl", "mpos", "mquat",
      // option and the compiler's length-range computation
      "timestep", "apirate", "impratio", "tolerance", "gravity", "wind", "magnetic", "viscosity", "o_margin",
      "o_solref", "o_solimp", "accel", "maxforce", "inttotal", "inteval", "tolrange",
      // cameras, lights, materials, textures, meshes, height fields, skins, composites
      "fovy", "ipd", "attenuation", "exponent", "ambient", "diffuse", "specular", "emission", "shininess",
      "reflectance", "rgba", "texrepeat", "rgb1", "rgb2", "markrgb", "random", "vertex", "normal", "texcoord",
      "elevation", "inflate", "bindpos", "bindquat", "vertweight", "spacing", "offset"};
  return kNames;
}

bool is_numeric(const std::vector<XmlElement>& elements, const XmlElement& e, const std::string& attr) {
  // Every attribute of <statistic> and of <visual>'s elements is a number.
  if (e.tag == "statistic") return true;
  if (e.parent >= 0 && elements[static_cast<size_t>(e.parent)].tag == "visual") return true;
  if (attr == "data") return e.tag == "numeric";  // <text data> is text
  return numeric_attributes().count(attr) > 0;
}

// "geom 'block'", or for an unnamed element where it is: "geom in body 'link2'", "geom in default
// class 'obstacle'", "compiler".
std::string element_label(const std::vector<XmlElement>& elements, const XmlElement& e) {
  if (const std::string* name = e.attribute("name")) return e.tag + " '" + *name + "'";
  for (int p = e.parent; p >= 0; p = elements[static_cast<size_t>(p)].parent) {
    const XmlElement& up = elements[static_cast<size_t>(p)];
    if (up.tag == "default") {
      const std::string* cls = up.attribute("class");
      return e.tag + " in default class '" + (cls ? *cls : std::string("main")) + "'";
    }
    if (const std::string* name = up.attribute("name")) return e.tag + " in " + up.tag + " '" + *name + "'";
  }
  if (e.parent >= 0 && elements[static_cast<size_t>(e.parent)].tag != "mujoco")
    return elements[static_cast<size_t>(e.parent)].tag + " " + e.tag;
  return e.tag;
}

// `value` for a message: at most 80 characters.
std::string shown(const std::string& value) {
  size_t b = 0, e = value.size();
  while (b < e && is_space(value[b])) ++b;
  while (e > b && is_space(value[e - 1])) --e;
  const std::string v = value.substr(b, e - b);
  return v.size() <= 80 ? v : v.substr(0, 77) + "...";
}

// Refuses a value whose numbers are not all finite. Words that are no number are left to MuJoCo,
// which refuses them with its own message.
void check_numbers(const std::string& file, const std::vector<XmlElement>& elements, const XmlElement& e,
                   const std::string& attr, const std::string& value) {
  std::istringstream words(value);
  std::string word;
  std::vector<std::string> all;
  while (words >> word) all.push_back(word);
  for (size_t k = 0; k < all.size(); ++k) {
    char* end = nullptr;
    const double v = std::strtod(all[k].c_str(), &end);
    if (end == all[k].c_str() || *end != '\0' || std::isfinite(v)) continue;
    throw InputError(
        file + ": " + element_label(elements, e) + " " + attr + " '" + shown(value) + "' is not finite (" +
        (all.size() > 1 ? "value " + std::to_string(k + 1) + " '" + all[k] + "', " : std::string()) +
        "line " + std::to_string(e.line) + "); MJCF numbers must be finite");
  }
}

// Refuses a name with a control character: names are printed in one-line messages, text reports
// and CSV rows, and a newline written as &#10; would split a line so that a second could be forged.
void check_name(const std::string& file, const XmlElement& e, const std::string& attr,
                const std::string& value) {
  for (size_t k = 0; k < value.size(); ++k) {
    const auto c = static_cast<unsigned char>(value[k]);
    if (c >= 0x20 && c != 0x7f) continue;
    char code[8];
    std::snprintf(code, sizeof code, "0x%02X", c);
    throw InputError(file + ": " + e.tag + " " + attr + " (line " + std::to_string(e.line) +
                     ") holds the control character " + code + " at character " + std::to_string(k + 1) +
                     "; names must be printable");
  }
}

// Most memory one texture or height field may ask MuJoCo for: it allocates what the attributes say
// before reading anything (a builtin texture of 40,000 x 40,000 pixels asks for 4.5 GiB).
constexpr double kMaxAssetBytes = 512.0 * 1024 * 1024;

// Refuses a texture (width x height RGB pixels, six faces for a cube or skybox) or a height field
// (nrow x ncol floats) above kMaxAssetBytes, before MuJoCo allocates it.
void check_allocation(const std::string& file, const std::vector<XmlElement>& elements, const XmlElement& e) {
  auto number = [&](const char* key) {
    const std::string* v = e.attribute(key);
    if (!v) return 0.0;
    char* end = nullptr;
    const double x = std::strtod(v->c_str(), &end);
    return end == v->c_str() || !std::isfinite(x) || x < 0 ? 0.0 : x;
  };
  const bool texture = e.tag == "texture";
  const std::string* type = e.attribute("type");
  const double faces = texture && type && (*type == "cube" || *type == "skybox") ? 6 : 1;
  const double a = number(texture ? "width" : "nrow"), b = number(texture ? "height" : "ncol");
  const double bytes = a * b * (texture ? 3 * faces : 4);
  if (bytes <= kMaxAssetBytes) return;
  char size[32];
  std::snprintf(size, sizeof size, "%.1f GiB", bytes / (1024.0 * 1024 * 1024));
  throw InputError(file + ": " + element_label(elements, e) + " " + (texture ? "width" : "nrow") + " " +
                   shown(*e.attribute(texture ? "width" : "nrow")) + " x " + (texture ? "height" : "ncol") +
                   " " + shown(*e.attribute(texture ? "height" : "ncol")) + " needs about " + size +
                   " (line " + std::to_string(e.line) + "); leeway allows 512 MiB per " + e.tag);
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Reader {
  fs::path model_dir;
  std::vector<std::string> includes;  // the model file and its includes, in order
  std::set<std::string> seen;
  // <compiler> settings (the last given wins, as MuJoCo reads each <compiler> in turn).
  std::string meshdir, texturedir;
  bool strippath = false;
  std::vector<std::pair<std::string, bool>> assets;  // file, whether under texturedir

  void read(const std::string& file, int depth) {
    includes.push_back(file);
    const std::vector<XmlElement> elements = scan_elements(read_text(file), file);
    for (const XmlElement& e : elements) {
      for (const auto& [attr, value] : e.attributes)
        if (attr == "name" || attr == "class" || attr == "childclass") check_name(file, e, attr, value);
      for (const auto& [attr, value] : e.attributes)
        if (is_numeric(elements, e, attr)) check_numbers(file, elements, e, attr, value);
      if (e.tag == "texture" || e.tag == "hfield") check_allocation(file, elements, e);
      if (e.tag == "compiler") {
        if (const auto* v = e.attribute("meshdir")) meshdir = *v;
        if (const auto* v = e.attribute("texturedir")) texturedir = *v;
        if (const auto* v = e.attribute("strippath")) strippath = *v == "true";
      } else if (e.tag == "mesh" || e.tag == "hfield" || e.tag == "skin") {
        if (const auto* v = e.attribute("file")) assets.emplace_back(*v, false);
      } else if (e.tag == "texture") {
        for (const char* key :
             {"file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback"})
          if (const auto* v = e.attribute(key)) assets.emplace_back(*v, true);
      } else if (e.tag == "include") {
        const auto* name = e.attribute("file");
        if (!name || depth >= kMaxIncludeDepth) continue;  // MuJoCo reports these
        // MuJoCo 2.2.2 resolves every include, nested ones too, from the model file's folder.
        const fs::path path = fs::path(*name).is_absolute() ? fs::path(*name) : model_dir / *name;
        std::error_code ec;
        if (!fs::exists(path, ec)) continue;  // MuJoCo names the missing file
        // A FIFO would block MuJoCo's reader, as a FIFO given as the cell would.
        try {
          require_regular_input(path.string(), "included file");
        } catch (const InputError& err) {
          // The message names the included path; the file to mend is the one that includes it.
          throw InputError(file + ": include '" + *name + "' (line " + std::to_string(e.line) +
                           "): " + err.what());
        }
        if (!seen.insert(fs::weakly_canonical(path, ec).string()).second) continue;  // MuJoCo's error
        read(path.string(), depth + 1);
      }
    }
  }

  // An asset file as MuJoCo 2.2.2 opens it: the file name (without its folders under strippath),
  // as it is when absolute, else below the asset folder, itself below the model's folder unless
  // absolute.
  std::string resolve(std::string file, bool texture) const {
    if (strippath) file = fs::path(file).filename().string();
    if (fs::path(file).is_absolute()) return file;
    const fs::path dir(texture ? texturedir : meshdir);
    if (dir.is_absolute()) return (dir / file).string();
    return (model_dir / dir / file).string();
  }
};

}  // namespace

MjcfSource read_mjcf_source(const std::string& path) {
  require_regular_input(path, "file");
  Reader r;
  r.model_dir = fs::path(path).has_parent_path() ? fs::path(path).parent_path() : fs::path(".");
  std::error_code ec;
  r.seen.insert(fs::weakly_canonical(path, ec).string());
  r.read(path, 0);
  MjcfSource out;
  out.files = r.includes;
  for (const auto& [file, texture] : r.assets) out.files.push_back(r.resolve(file, texture));
  return out;
}

void require_shallow_xml(const std::string& text, const std::string& file) { scan_elements(text, file); }

std::string first_model_section(const std::string& path) {
  require_regular_input(path, "MJCF file");
  static const std::set<std::string> sections = {
      "compiler", "option",    "size",    "visual",   "statistic", "default",  "extension", "custom",
      "asset",    "worldbody", "contact", "equality", "tendon",    "actuator", "sensor",    "keyframe"};
  const std::vector<XmlElement> elements = scan_elements(read_text(path), path);
  for (const XmlElement& e : elements)
    if (e.parent == 0 && sections.count(e.tag))
      return "<" + e.tag + "> (line " + std::to_string(e.line) + ")";
  return "";
}

std::vector<std::string> model_input_files(const std::string& path) {
  if (fs::path(path).extension() == ".mjb") return {path};
  return read_mjcf_source(path).files;
}

}  // namespace leeway
