#include "leeway/io/stl.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "leeway/core/error.hpp"

namespace leeway {
namespace {

constexpr size_t kHeaderBytes = 80;
constexpr size_t kTriangleBytes = 50;  // normal, three vertices (12 floats), attribute count

float read_float_le(const unsigned char* p) {
  // STL is little-endian IEEE 754; assemble the bits so the host's byte order does not matter.
  const std::uint32_t bits = std::uint32_t{p[0]} | (std::uint32_t{p[1]} << 8) | (std::uint32_t{p[2]} << 16) |
                             (std::uint32_t{p[3]} << 24);
  float f = 0;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

std::uint32_t read_u32_le(const unsigned char* p) {
  return std::uint32_t{p[0]} | (std::uint32_t{p[1]} << 8) | (std::uint32_t{p[2]} << 16) |
         (std::uint32_t{p[3]} << 24);
}

StlMesh read_binary(const std::string& path, const std::string& bytes, std::uint32_t count) {
  StlMesh mesh;
  mesh.binary = true;
  mesh.vertices.reserve(3 * static_cast<size_t>(count));
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  for (std::uint32_t t = 0; t < count; ++t) {
    const unsigned char* tri = data + kHeaderBytes + 4 + kTriangleBytes * t + 12;  // skip the normal
    for (int v = 0; v < 3; ++v) {
      const Eigen::Vector3d p(read_float_le(tri + 12 * v), read_float_le(tri + 12 * v + 4),
                              read_float_le(tri + 12 * v + 8));
      if (!p.allFinite())
        throw InputError(path + ": binary STL triangle " + std::to_string(t + 1) + " vertex " +
                         std::to_string(v + 1) + " is not finite");
      mesh.vertices.push_back(p);
    }
  }
  return mesh;
}

StlMesh read_ascii(const std::string& path, const std::string& text) {
  StlMesh mesh;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    std::istringstream words(line);
    std::string word;
    if (!(words >> word) || word != "vertex") continue;
    std::string xyz[3];
    Eigen::Vector3d p;
    for (int k = 0; k < 3; ++k) {
      if (!(words >> xyz[k]))
        throw InputError(path + ": ASCII STL line " + std::to_string(line_no) +
                         ": vertex has fewer than 3 values");
      char* end = nullptr;
      p[k] = std::strtod(xyz[k].c_str(), &end);
      if (end == xyz[k].c_str() || *end != '\0' || !std::isfinite(p[k]))
        throw InputError(path + ": ASCII STL line " + std::to_string(line_no) + ": vertex value '" + xyz[k] +
                         "' is not a finite number");
    }
    mesh.vertices.push_back(p);
  }
  if (mesh.vertices.size() % 3 != 0)
    throw InputError(path + ": ASCII STL has " + std::to_string(mesh.vertices.size()) +
                     " vertices, not three per facet");
  return mesh;
}

}  // namespace

StlMesh read_stl(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the STL file");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  StlMesh mesh;
  // The size test comes first: binary files may also begin with "solid" in their header.
  const bool sized_as_binary =
      bytes.size() >= kHeaderBytes + 4 &&
      bytes.size() ==
          kHeaderBytes + 4 +
              kTriangleBytes *
                  size_t{read_u32_le(reinterpret_cast<const unsigned char*>(bytes.data()) + kHeaderBytes)};
  if (sized_as_binary) {
    mesh = read_binary(path, bytes,
                       read_u32_le(reinterpret_cast<const unsigned char*>(bytes.data()) + kHeaderBytes));
  } else {
    const size_t start = bytes.find_first_not_of(" \t\r\n");
    if (start == std::string::npos || bytes.compare(start, 5, "solid") != 0) {
      if (bytes.size() >= kHeaderBytes + 4)
        throw InputError(
            path + ": not an STL file: " + std::to_string(bytes.size()) +
            " bytes, which is neither a binary STL of the triangle count its header gives (" +
            std::to_string(read_u32_le(reinterpret_cast<const unsigned char*>(bytes.data()) + kHeaderBytes)) +
            ") nor ASCII STL (starting with 'solid')");
      throw InputError(
          path + ": not an STL file (too short for binary STL, and not ASCII STL starting with 'solid')");
    }
    mesh = read_ascii(path, bytes);
  }
  if (mesh.vertices.empty()) throw InputError(path + ": the STL file holds no triangle");
  return mesh;
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> bounding_box(const std::vector<Eigen::Vector3d>& points) {
  if (points.empty()) throw InputError("bounding box of no points");
  Eigen::Vector3d lo = points.front(), hi = points.front();
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return {lo, hi};
}

}  // namespace leeway
