#include "leeway/viz/export_mjcf.hpp"

#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "leeway/core/error.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/viz/render.hpp"

namespace leeway {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot read the " + what);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Calls `fn(position, tag)` for every tag outside comments, in order (a tag runs from '<' to '>').
template <class Fn>
void for_each_tag(const std::string& text, Fn&& fn) {
  size_t i = 0;
  while (i < text.size()) {
    const size_t lt = text.find('<', i);
    if (lt == std::string::npos) return;
    if (text.compare(lt, 4, "<!--") == 0) {
      const size_t end = text.find("-->", lt + 4);
      i = end == std::string::npos ? text.size() : end + 3;
      continue;
    }
    const size_t gt = text.find('>', lt);
    const size_t stop = gt == std::string::npos ? text.size() : gt + 1;
    fn(lt, text.substr(lt, stop - lt));
    i = stop;
  }
}

// The text with every tag outside comments replaced by `fn(tag)`.
template <class Fn>
std::string map_tags(const std::string& text, Fn&& fn) {
  std::string out;
  size_t copied = 0;
  for_each_tag(text, [&](size_t pos, const std::string& tag) {
    out.append(text, copied, pos - copied);
    out += fn(tag);
    copied = pos + tag.size();
  });
  return out.append(text, copied, std::string::npos);
}

std::string tag_name(const std::string& tag) {
  size_t b = 1;
  while (b < tag.size() && (tag[b] == '/' || tag[b] == '?')) ++b;
  size_t e = b;
  while (e < tag.size() && (std::isalnum(static_cast<unsigned char>(tag[e])) || tag[e] == '_')) ++e;
  return tag.substr(b, e - b);
}

// The value of attribute `name` in a tag, or nothing.
bool attribute(const std::string& tag, const std::string& name, std::string& value, size_t& pos,
               size_t& len) {
  const std::regex re("\\s" + name + "\\s*=\\s*([\"'])(.*?)\\1");
  std::smatch m;
  if (!std::regex_search(tag, m, re)) return false;
  value = m[2];
  pos = static_cast<size_t>(m.position(2));
  len = static_cast<size_t>(m.length(2));
  return true;
}

// The children of an included file's <mujoco> element (MuJoCo 2.2.2: an included file is a model
// whose top element's children are inserted where the include stood).
std::string mujoco_children(const std::string& text, const fs::path& file) {
  size_t open = std::string::npos, close = std::string::npos;
  for_each_tag(text, [&](size_t pos, const std::string& t) {
    if (tag_name(t) != "mujoco") return;
    if (t[1] == '/')
      close = pos;
    else if (open == std::string::npos)
      open = pos + t.size();
  });
  if (open == std::string::npos || close == std::string::npos || close < open)
    throw InputError(file.string() + ": an included file must be a <mujoco> element");
  return text.substr(open, close - open);
}

std::string expand_includes(const std::string& text, const fs::path& model_dir, int depth) {
  if (depth > 16) throw InputError(model_dir.string() + ": includes nest deeper than 16 levels");
  return map_tags(text, [&](const std::string& t) -> std::string {
    if (tag_name(t) != "include" || t[1] == '/') return t;
    std::string file;
    size_t pos = 0, len = 0;
    if (!attribute(t, "file", file, pos, len)) return t;
    const fs::path path = fs::path(file).is_absolute() ? fs::path(file) : model_dir / file;
    const std::string inner = mujoco_children(read_text(path, "included file"), path);
    return "<!-- leeway: begin " + file + " -->" + expand_includes(inner, model_dir, depth + 1) +
           "<!-- leeway: end " + file + " -->";
  });
}

// A path of the cell's folder as seen from the output's folder.
std::string relocate(const std::string& value, const fs::path& model_dir, const fs::path& out_dir) {
  if (value.empty() || fs::path(value).is_absolute()) return value;
  const fs::path target = fs::weakly_canonical(model_dir / value);
  const fs::path rel = target.lexically_relative(fs::weakly_canonical(out_dir));
  std::string s = rel.empty() ? target.string() : rel.generic_string();
  // A directory attribute keeps its trailing slash.
  if (!value.empty() && value.back() == '/' && (s.empty() || s.back() != '/')) s += '/';
  return s;
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

std::string volume_body(const std::vector<Box>& boxes) {
  const double max_top = highest_top(boxes);
  std::string out = std::string("\n    <!-- leeway: the generated volume, ") + std::to_string(boxes.size()) +
                    " boxes [m], visual only, coloured by the height of their top -->\n    <body name=\"" +
                    kExportBodyName + "\">\n";
  for (size_t i = 0; i < boxes.size(); ++i) {
    const Box& b = boxes[i];
    if (!b.center.allFinite() || !b.half_size.allFinite() || (b.half_size.array() <= 0).any())
      throw InputError("volume box #" + std::to_string(i) + " has a non-finite or non-positive size");
    const auto c = height_colour(b.center.z() + b.half_size.z(), max_top);
    out += "      <geom name=\"leeway_volume_box_" + std::to_string(i) + "\" type=\"box\" pos=\"" +
           number(b.center.x()) + " " + number(b.center.y()) + " " + number(b.center.z()) + "\" size=\"" +
           number(b.half_size.x()) + " " + number(b.half_size.y()) + " " + number(b.half_size.z()) + "\"";
    if (!b.rotation.isIdentity(0)) {
      Eigen::Matrix<double, 3, 3, Eigen::RowMajor> r = b.rotation;
      mjtNum quat[4];
      mju_mat2Quat(quat, r.data());
      out += " quat=\"" + number(quat[0]) + " " + number(quat[1]) + " " + number(quat[2]) + " " +
             number(quat[3]) + "\"";
    }
    out += " contype=\"0\" conaffinity=\"0\" rgba=\"" + number(c[0]) + " " + number(c[1]) + " " +
           number(c[2]) + " 0.45\"/>\n";
  }
  return out + "    </body>\n  ";
}

}  // namespace

std::string volume_mjcf(const std::string& cell_path, const std::vector<Box>& boxes,
                        const std::string& out_path) {
  const fs::path cell(cell_path);
  const fs::path model_dir = cell.has_parent_path() ? cell.parent_path() : fs::path(".");
  fs::path out_dir = fs::path(out_path).parent_path();
  if (out_dir.empty()) out_dir = ".";
  std::string xml = expand_includes(read_text(cell, "cell"), model_dir, 0);

  // Paths left after inlining: the compiler's asset folders, and asset files where no folder is set.
  bool meshdir = false, texturedir = false;
  map_tags(xml, [&](const std::string& t) {
    std::string v;
    size_t p = 0, l = 0;
    if (tag_name(t) == "compiler") {
      meshdir = meshdir || attribute(t, "meshdir", v, p, l);
      texturedir = texturedir || attribute(t, "texturedir", v, p, l);
    }
    return t;
  });
  xml = map_tags(xml, [&](std::string t) {
    const std::string name = tag_name(t);
    std::vector<std::string> keys;
    if (name == "compiler") keys = {"meshdir", "texturedir"};
    if ((name == "mesh" || name == "hfield" || name == "skin") && !meshdir) keys = {"file"};
    if (name == "texture" && !texturedir)
      keys = {"file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback"};
    for (const auto& key : keys) {
      std::string v;
      size_t p = 0, l = 0;
      if (attribute(t, key, v, p, l)) t.replace(p, l, relocate(v, model_dir, out_dir));
    }
    return t;
  });

  // Before the last </worldbody> outside comments.
  size_t close = std::string::npos;
  for_each_tag(xml, [&close](size_t pos, const std::string& t) {
    if (t.compare(0, 12, "</worldbody>") == 0) close = pos;
  });
  if (close == std::string::npos)
    throw InputError(cell_path + ": has no </worldbody>; leeway adds its volume there");
  xml.insert(close, volume_body(boxes));
  const std::string note =
      "<!-- leeway: " + cell.filename().string() + " with its generated volume (" +
      std::to_string(boxes.size()) +
      " boxes), written by leeway bounds; includes inlined; units: metres, radians -->\n";
  const size_t decl = xml.rfind("?>", xml.find("<mujoco"));
  const size_t at = xml.compare(0, 5, "<?xml") == 0 && decl != std::string::npos ? decl + 2 : 0;
  xml.insert(at, at == 0 ? note : "\n" + note);
  return xml;
}

std::string volume_mjb(const std::string& cell_path, const std::vector<Box>& boxes,
                       const std::string& out_path) {
  install_mujoco_error_handlers();
  const std::string xml = volume_mjcf(cell_path, boxes, out_path);
  // Compiled as a file beside the output, where its relative paths point from.
  ModelPtr m;
  try {
    m = load_model_text(xml, out_path + ".leeway-export.xml");
  } catch (const InputError& e) {
    throw InputError(cell_path + ": does not compile with the volume added (" + e.what() + ")");
  }
  take_mujoco_warnings();
  // mj_sizeModel counts the in-memory alignment padding that mj_saveModel does not write (a loader
  // then warns "Model file is too large"), so save to a scratch file and take its bytes. The file is
  // in a folder of its own that only this user can enter (mkdtemp, mode 0700): mj_saveModel opens
  // its file with fopen, which would follow a link another user planted at a predictable name.
  std::string folder = (fs::temp_directory_path() / "leeway-export-XXXXXX").string();
  if (!::mkdtemp(folder.data()))
    throw InputError(folder + ": cannot make a scratch folder for the MJB (" + std::strerror(errno) + ")");
  const fs::path scratch = fs::path(folder) / "model.mjb";
  std::string bytes;
  {
    mj_saveModel(m.get(), scratch.c_str(), nullptr, 0);
    std::ifstream in(scratch, std::ios::binary);
    if (in) bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::error_code ec;
  fs::remove_all(folder, ec);
  if (bytes.empty()) throw std::runtime_error("MuJoCo did not save the model to " + scratch.string());
  return bytes;
}

}  // namespace leeway
