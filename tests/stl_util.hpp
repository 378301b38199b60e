#pragma once
// Test support: small STL files written by the tests (binary and ASCII), so that no mesh needs to
// be committed.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace leeway::test {

using Triangle = std::array<Eigen::Vector3d, 3>;

//! The 12 triangles of the cuboid [lo, hi].
inline std::vector<Triangle> cuboid(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  auto corner = [&](int i) {
    return Eigen::Vector3d(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  };
  // Two triangles per face, by corner index (bit 0: x, bit 1: y, bit 2: z).
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  std::vector<Triangle> out;
  for (const auto& f : faces) {
    out.push_back({corner(f[0]), corner(f[1]), corner(f[2])});
    out.push_back({corner(f[0]), corner(f[2]), corner(f[3])});
  }
  return out;
}

//! Writes a binary STL (little-endian floats); `header` fills the 80-byte header.
inline void write_binary_stl(const std::string& path, const std::vector<Triangle>& triangles,
                             const std::string& header = "leeway test mesh") {
  std::ofstream out(path, std::ios::binary);
  char head[80] = {};
  std::memcpy(head, header.data(), std::min<size_t>(header.size(), 80));
  out.write(head, 80);
  auto put_u32 = [&](std::uint32_t v) {
    const unsigned char b[4] = {static_cast<unsigned char>(v), static_cast<unsigned char>(v >> 8),
                                static_cast<unsigned char>(v >> 16), static_cast<unsigned char>(v >> 24)};
    out.write(reinterpret_cast<const char*>(b), 4);
  };
  auto put_float = [&](double v) {
    const float f = static_cast<float>(v);
    std::uint32_t bits = 0;
    std::memcpy(&bits, &f, 4);
    put_u32(bits);
  };
  put_u32(static_cast<std::uint32_t>(triangles.size()));
  for (const auto& t : triangles) {
    for (int k = 0; k < 3; ++k) put_float(0);  // normal (readers recompute it)
    for (const auto& v : t)
      for (int k = 0; k < 3; ++k) put_float(v[k]);
    out.write("\0\0", 2);  // attribute byte count
  }
}

//! Writes an ASCII STL with the values printed to 17 significant digits.
inline void write_ascii_stl(const std::string& path, const std::vector<Triangle>& triangles) {
  std::ofstream out(path);
  out.precision(17);
  out << "solid leeway_test\n";
  for (const auto& t : triangles) {
    out << "  facet normal 0 0 0\n    outer loop\n";
    for (const auto& v : t) out << "      vertex " << v.x() << " " << v.y() << " " << v.z() << "\n";
    out << "    endloop\n  endfacet\n";
  }
  out << "endsolid leeway_test\n";
}

}  // namespace leeway::test
