#include "leeway/io/bounds_export.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"

namespace leeway {
namespace {

// Writes a TempFile in pieces of about a megabyte, so a long table never sits whole in memory.
class ChunkedWriter {
 public:
  explicit ChunkedWriter(TempFile& file) : file_(file) { buffer_.reserve(kChunk + 4096); }
  void add(const std::string& text) {
    buffer_ += text;
    if (buffer_.size() >= kChunk) flush();
  }
  void add(const char* data, size_t n) {
    buffer_.append(data, n);
    if (buffer_.size() >= kChunk) flush();
  }
  void flush() {
    file_.write(buffer_);
    buffer_.clear();
  }

 private:
  static constexpr size_t kChunk = 1 << 20;
  TempFile& file_;
  std::string buffer_;
};

// Shortest text that reads back as the same double.
std::string num(double v) {
  char text[32];
  for (int precision = 15; precision <= 17; ++precision) {
    std::snprintf(text, sizeof text, "%.*g", precision, v);
    if (std::strtod(text, nullptr) == v) break;
  }
  return text;
}

void require_joints(const BoundsTrajectory& trajectory, const std::vector<std::string>& joints) {
  if (static_cast<int>(joints.size()) != trajectory.dof())
    throw InputError(std::to_string(joints.size()) + " joint names for bounds of " +
                     std::to_string(trajectory.dof()) + " joints");
}

void write_csv(const BoundsTrajectory& tr, const std::vector<std::string>& joints, double dt, long rows,
               const std::string& source, ChunkedWriter& out) {
  out.add("# leeway sample of " + source + ": t [s], s [path parameter: waypoint index], nominal_J lower_J " +
          "upper_J [rad for hinge joints, m for slide joints]; dt " + num(dt) + " s\n");
  std::string header = "t,s";
  for (const auto& j : joints) header += ",nominal_" + j + ",lower_" + j + ",upper_" + j;
  out.add(header + "\n");
  for (long i = 0; i < rows; ++i) {
    const double t = i == rows - 1 ? tr.duration() : std::min(tr.duration(), static_cast<double>(i) * dt);
    const BoundsStage b = tr.at_t(t);
    std::string line = num(b.t) + "," + num(b.s);
    for (int k = 0; k < tr.dof(); ++k)
      line += "," + num(b.nominal[k]) + "," + num(b.lower[k]) + "," + num(b.upper[k]);
    out.add(line + "\n");
  }
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char esc[8];
      std::snprintf(esc, sizeof esc, "\\u%04x", c);
      out += esc;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string json_vector(const Eigen::VectorXd& v) {
  std::string out = "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) out += (i ? ", " : "") + num(v[i]);
  return out + "]";
}

void write_json(const BoundsTrajectory& tr, const std::vector<std::string>& joints, double dt, long rows,
                const std::string& source, ChunkedWriter& out) {
  std::string head =
      "{\n  \"format\": \"leeway-stages-1\",\n  \"units\": \"SI: t in seconds, s the path parameter "
      "(waypoint index), joint values in radians (hinges) or metres (slides)\",\n";
  head += "  \"bounds\": " + json_string(source) + ",\n  \"joints\": [";
  for (size_t i = 0; i < joints.size(); ++i) head += (i ? ", " : "") + json_string(joints[i]);
  head += "],\n  \"dt\": " + num(dt) + ",\n  \"duration\": " + num(tr.duration()) + ",\n  \"stages\": [\n";
  out.add(head);
  for (long i = 0; i < rows; ++i) {
    const double t = i == rows - 1 ? tr.duration() : std::min(tr.duration(), static_cast<double>(i) * dt);
    const BoundsStage b = tr.at_t(t);
    out.add("    {\"t\": " + num(b.t) + ", \"s\": " + num(b.s) + ", \"nominal\": " + json_vector(b.nominal) +
            ", \"lower\": " + json_vector(b.lower) + ", \"upper\": " + json_vector(b.upper) + "}" +
            (i + 1 < rows ? ",\n" : "\n"));
  }
  out.add("  ]\n}\n");
}

// --- .npz: a zip archive (stored, not compressed) of .npy files, as numpy.savez writes. ---

std::uint32_t crc32_update(std::uint32_t crc, const unsigned char* data, size_t n) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (size_t i = 0; i < n; ++i) crc = table[(crc ^ data[i]) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

void put16(std::string& s, unsigned v) {
  s += static_cast<char>(v & 0xFF);
  s += static_cast<char>((v >> 8) & 0xFF);
}
void put32(std::string& s, std::uint32_t v) {
  put16(s, v & 0xFFFF);
  put16(s, v >> 16);
}

// The .npy header of an array with dtype `descr` and shape `shape` ("(M, n)"): version 1.0, padded
// with spaces to a multiple of 64 bytes and ended by a newline.
std::string npy_header(const std::string& descr, const std::string& shape) {
  std::string dict = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + shape + ", }";
  const size_t unpadded = 10 + dict.size() + 1;
  dict += std::string((64 - unpadded % 64) % 64, ' ') + "\n";
  std::string out = "\x93NUMPY";
  out += '\x01';
  out += '\x00';
  put16(out, static_cast<unsigned>(dict.size()));
  return out + dict;
}

struct NpzEntry {
  std::string name;
  std::uint32_t crc = 0, size = 0, offset = 0;
};

class NpzWriter {
 public:
  explicit NpzWriter(ChunkedWriter& out) : out_(out) {}
  // One array: its .npy bytes (header + data) are `npy`.
  void add(const std::string& name, const std::string& npy) {
    NpzEntry e{name + ".npy", crc32_update(0, reinterpret_cast<const unsigned char*>(npy.data()), npy.size()),
               static_cast<std::uint32_t>(npy.size()), offset_};
    std::string local;
    put32(local, 0x04034b50);
    put16(local, 20);    // version needed
    put16(local, 0);     // flags
    put16(local, 0);     // stored
    put16(local, 0);     // time
    put16(local, 0x21);  // date: 1980-01-01
    put32(local, e.crc);
    put32(local, e.size);
    put32(local, e.size);
    put16(local, static_cast<unsigned>(e.name.size()));
    put16(local, 0);
    local += e.name;
    out_.add(local);
    out_.add(npy.data(), npy.size());
    offset_ += static_cast<std::uint32_t>(local.size() + npy.size());
    entries_.push_back(e);
  }
  void finish() {
    std::string central;
    for (const auto& e : entries_) {
      put32(central, 0x02014b50);
      put16(central, 20);
      put16(central, 20);
      put16(central, 0);
      put16(central, 0);
      put16(central, 0);
      put16(central, 0x21);
      put32(central, e.crc);
      put32(central, e.size);
      put32(central, e.size);
      put16(central, static_cast<unsigned>(e.name.size()));
      put16(central, 0);
      put16(central, 0);
      put16(central, 0);
      put16(central, 0);
      put32(central, 0);
      put32(central, e.offset);
      central += e.name;
    }
    std::string end;
    put32(end, 0x06054b50);
    put16(end, 0);
    put16(end, 0);
    put16(end, static_cast<unsigned>(entries_.size()));
    put16(end, static_cast<unsigned>(entries_.size()));
    put32(end, static_cast<std::uint32_t>(central.size()));
    put32(end, offset_);
    put16(end, 0);
    out_.add(central + end);
  }

 private:
  ChunkedWriter& out_;
  std::vector<NpzEntry> entries_;
  std::uint32_t offset_ = 0;
};

void append_doubles(std::string& s, const double* v, size_t n) {
  static_assert(sizeof(double) == 8, "IEEE doubles");
  // .npy '<f8': little-endian, as on every machine leeway builds for (x86-64, aarch64).
  s.append(reinterpret_cast<const char*>(v), n * sizeof(double));
}

void write_npz(const BoundsTrajectory& tr, const std::vector<std::string>& joints, double dt, long rows,
               ChunkedWriter& out) {
  const size_t m = static_cast<size_t>(rows), n = static_cast<size_t>(tr.dof());
  // A plain zip holds at most 4 GiB; the five arrays are about 8 (2 + 3n) M bytes.
  if (8.0 * static_cast<double>(m) * static_cast<double>(2 + 3 * n) > 4.0e9)
    throw InputError("the time step dt " + num(dt) + " s gives " + std::to_string(rows) +
                     " rows, more than an .npz holds (4 GiB); use a larger step or .csv");
  NpzWriter npz(out);
  auto time_at = [&](size_t i) {
    return i + 1 == m ? tr.duration() : std::min(tr.duration(), static_cast<double>(i) * dt);
  };
  const std::string vec_shape = "(" + std::to_string(m) + ",)";
  const std::string mat_shape = "(" + std::to_string(m) + ", " + std::to_string(n) + ")";
  std::string t = npy_header("<f8", vec_shape), s = npy_header("<f8", vec_shape);
  for (size_t i = 0; i < m; ++i) {
    const double ti = time_at(i), si = tr.s_at_t(ti);
    append_doubles(t, &ti, 1);
    append_doubles(s, &si, 1);
  }
  npz.add("t", t);
  t.clear();
  t.shrink_to_fit();
  npz.add("s", s);
  s.clear();
  s.shrink_to_fit();
  Eigen::VectorXd nominal(tr.dof()), lower(tr.dof()), upper(tr.dof());
  for (int which = 0; which < 3; ++which) {
    std::string a = npy_header("<f8", mat_shape);
    a.reserve(a.size() + m * n * 8);
    for (size_t i = 0; i < m; ++i) {
      tr.at_t(time_at(i), nominal, lower, upper);
      const Eigen::VectorXd& v = which == 0 ? nominal : which == 1 ? lower : upper;
      append_doubles(a, v.data(), n);
    }
    npz.add(which == 0 ? "nominal" : which == 1 ? "lower" : "upper", a);
  }
  // The joint names as a fixed-width unicode array ('<Uk': k UTF-32 code units per name).
  size_t width = 1;
  for (const auto& j : joints) width = std::max(width, j.size());
  std::string names = npy_header("<U" + std::to_string(width), "(" + std::to_string(n) + ",)");
  for (const auto& j : joints)
    for (size_t c = 0; c < width; ++c) {
      const std::uint32_t code = c < j.size() ? static_cast<unsigned char>(j[c]) : 0;
      put32(names, code);
    }
  npz.add("joints", names);
  npz.finish();
}

}  // namespace

StagesFormat stages_format_of(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext == ".csv") return StagesFormat::kCsv;
  if (ext == ".json") return StagesFormat::kJson;
  if (ext == ".npz") return StagesFormat::kNpz;
  if (ext == ".yaml" || ext == ".yml") return StagesFormat::kDrakeYaml;
  throw InputError(path + ": the output's name must end in .csv, .json, .npz, or .yaml for drake-yaml");
}

void write_stages(const BoundsTrajectory& trajectory, const std::vector<std::string>& joints, double dt,
                  StagesFormat format, const std::string& path, const std::string& source) {
  require_joints(trajectory, joints);
  const long rows = trajectory.sample_count(dt);
  TempFile file(path);
  ChunkedWriter out(file);
  switch (format) {
    case StagesFormat::kCsv:
      write_csv(trajectory, joints, dt, rows, source, out);
      break;
    case StagesFormat::kJson:
      write_json(trajectory, joints, dt, rows, source, out);
      break;
    case StagesFormat::kNpz:
      write_npz(trajectory, joints, dt, rows, out);
      break;
    case StagesFormat::kDrakeYaml:
      out.add(drake_yaml(trajectory, joints, false, source));
      break;
  }
  out.flush();
  file.commit();
}

std::string drake_yaml(const BoundsTrajectory& trajectory, const std::vector<std::string>& joints,
                       bool segments, const std::string& source) {
  require_joints(trajectory, joints);
  const int n = trajectory.dof();
  std::string joint_list;
  for (const auto& j : joints) joint_list += (joint_list.empty() ? "" : " ") + j;
  std::ostringstream y;
  y << "# leeway bounds of " << source << " as Drake HPolyhedron regions {x : A x <= b}\n"
    << "# (IrisRegions: LoadIrisRegionsYamlFile). x = q (" << joint_list
    << ") for waypoint_III; x = (q, f) for segment_III, f in [0, 1] the fraction of the segment.\n"
    << "# Units: rad for hinge joints, m for slide joints.\n";
  auto row = [&](int dim, int index, double sign, double f_coeff) {
    // One row of A: sign at `index`, f_coeff in the last column when dim > n.
    std::string r = "[";
    for (int c = 0; c < dim; ++c) {
      const double v = c == index ? sign : (dim > n && c == n ? f_coeff : 0.0);
      r += (c ? ", " : "") + num(v);
    }
    return r + "]";
  };
  auto name = [](const char* kind, int i) {
    char text[32];
    std::snprintf(text, sizeof text, "%s_%03d", kind, i);
    return std::string(text);
  };
  const auto& w = trajectory.waypoints();
  for (int i = 0; i < trajectory.waypoint_count(); ++i) {
    y << name("waypoint", i) << ":\n  ambient_dimension: " << n << "\n  A:\n";
    for (int k = 0; k < n; ++k) y << "  - " << row(n, k, 1, 0) << "\n";
    for (int k = 0; k < n; ++k) y << "  - " << row(n, k, -1, 0) << "\n";
    y << "  b: [";
    for (int k = 0; k < n; ++k) y << (k ? ", " : "") << num(w[static_cast<size_t>(i)].upper[k]);
    for (int k = 0; k < n; ++k) y << ", " << num(-w[static_cast<size_t>(i)].lower[k]);
    y << "]\n";
  }
  for (int i = 0; segments && i + 1 < trajectory.waypoint_count(); ++i) {
    const WaypointBounds& a = w[static_cast<size_t>(i)];
    const WaypointBounds& b = w[static_cast<size_t>(i) + 1];
    // q_k <= upper_a + f (upper_b - upper_a)  ->  q_k - (upper_b - upper_a) f <= upper_a
    // q_k >= lower_a + f (lower_b - lower_a)  -> -q_k + (lower_b - lower_a) f <= -lower_a
    y << name("segment", i) << ":\n  ambient_dimension: " << n + 1 << "\n  A:\n";
    for (int k = 0; k < n; ++k) y << "  - " << row(n + 1, k, 1, -(b.upper[k] - a.upper[k])) << "\n";
    for (int k = 0; k < n; ++k) y << "  - " << row(n + 1, k, -1, b.lower[k] - a.lower[k]) << "\n";
    y << "  - " << row(n + 1, n, 1, 1) << "\n  - " << row(n + 1, n, -1, -1) << "\n  b: [";
    for (int k = 0; k < n; ++k) y << (k ? ", " : "") << num(a.upper[k]);
    for (int k = 0; k < n; ++k) y << ", " << num(-a.lower[k]);
    y << ", 1, 0]\n";
  }
  return y.str();
}

}  // namespace leeway
