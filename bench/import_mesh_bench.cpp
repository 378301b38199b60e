// leeway import-mesh's convex split on meshes built here: tori (closed, curved everywhere; one
// with seam vertices off by 1e-9 m, as an STL exporter's rounding leaves them), a table with four
// legs, a ladder (two rails and five rungs), and the table drawn in millimetres and scaled by 0.001
// as `--scale 0.001` does. Prints a Markdown table: triangles, closed, pieces, worst excess [m],
// wall and process CPU time [s] of one convex_split per mesh, default options unless given.
//
// Usage: leeway-bench-import-mesh [--meshes LIST] [--tolerance M] [--max-pieces N]
//   LIST: comma-separated names among torus-2k, torus-2k-seams, torus-20k, table, ladder, table-mm
//   (default: all).
#include <Eigen/Core>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "apps/statistics.hpp"
#include "leeway/io/convex_split.hpp"

namespace {

using Eigen::Vector3d;
using Mesh = std::vector<Vector3d>;  // three vertices per triangle

// A torus about z (major radius R, minor radius r) of 2 n m triangles, outward normals; the seam
// vertices (the last column and row meet the first) are shared exactly, or moved by `seam` [m] along
// x on the closing side, as independently rounded coordinates would be.
Mesh torus(double big_r, double small_r, int n, int m, double seam = 0) {
  auto at = [&](int i, int j) {
    const double u = 2 * M_PI * (i % n) / n, v = 2 * M_PI * (j % m) / m;
    Vector3d p((big_r + small_r * std::cos(v)) * std::cos(u), (big_r + small_r * std::cos(v)) * std::sin(u),
               small_r * std::sin(v));
    if (i == n || j == m) p.x() += seam;
    return p;
  };
  Mesh out;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const Vector3d a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
      out.insert(out.end(), {a, b, c, a, c, d});
    }
  return out;
}

// The 12 triangles of the cuboid [lo, hi], outward normals.
void cuboid(Mesh& out, const Vector3d& lo, const Vector3d& hi) {
  auto corner = [&](int i) {
    return Vector3d(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  };
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces)
    out.insert(out.end(),
               {corner(f[0]), corner(f[1]), corner(f[2]), corner(f[0]), corner(f[2]), corner(f[3])});
}

// The table of tests/import_mesh_test.cpp: a 1.2 x 0.8 x 0.05 m top at 0.7 m on four 0.05 m legs,
// in units of `unit` metres (1000 per metre: millimetres).
Mesh table(double per_metre = 1) {
  Mesh out;
  const double k = per_metre;
  cuboid(out, k * Vector3d(0, 0, 0.7), k * Vector3d(1.2, 0.8, 0.75));
  for (const double x : {0.0, 1.15})
    for (const double y : {0.0, 0.75})
      cuboid(out, k * Vector3d(x, y, 0), k * Vector3d(x + 0.05, y + 0.05, 0.7));
  return out;
}

// A ladder: two 0.04 m square rails 2 m tall, 0.5 m apart, and five 0.03 m square rungs between.
Mesh ladder() {
  Mesh out;
  cuboid(out, Vector3d(0, 0, 0), Vector3d(0.04, 0.04, 2));
  cuboid(out, Vector3d(0.54, 0, 0), Vector3d(0.58, 0.04, 2));
  for (int k = 0; k < 5; ++k) {
    const double z = 0.2 + 0.4 * k;
    cuboid(out, Vector3d(0.04, 0.005, z), Vector3d(0.54, 0.035, z + 0.03));
  }
  return out;
}

struct Case {
  std::string name, what;
  std::function<Mesh()> mesh;
};

}  // namespace

int main(int argc, char** argv) {
  std::string only;
  leeway::ConvexSplitOptions options;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--meshes")
      only = "," + v + ",";
    else if (k == "--tolerance")
      options.tolerance = std::atof(v.c_str());
    else if (k == "--max-pieces")
      options.max_pieces = std::atoi(v.c_str());
    else {
      std::cerr << "unknown option " << k << "\n";
      return 2;
    }
  }
  const std::vector<Case> cases = {
      {"torus-2k", "torus R 0.3 m, r 0.1 m, 32 x 32", [] { return torus(0.3, 0.1, 32, 32); }},
      {"torus-2k-seams", "same, seams off by 1e-9 m", [] { return torus(0.3, 0.1, 32, 32, 1e-9); }},
      {"torus-20k", "torus R 0.3 m, r 0.1 m, 100 x 100", [] { return torus(0.3, 0.1, 100, 100); }},
      {"table", "table, five boxes (m)", [] { return table(); }},
      {"ladder", "ladder, 2 x 2 m rails, 5 rungs", [] { return ladder(); }},
      {"table-mm", "table in mm, scaled by 0.001", [] {
         Mesh mesh = table(1000);
         for (auto& p : mesh) p *= 0.001;
         return mesh;
       }}};
  std::printf("convex_split, tolerance %g m, at most %d pieces, %d samples per piece\n\n", options.tolerance,
              options.max_pieces, options.samples);
  std::printf("| mesh | triangles | closed | pieces | worst excess [m] | reached | wall [s] | CPU [s] |\n");
  std::printf("|---|---:|---|---:|---:|---|---:|---:|\n");
  for (const auto& c : cases) {
    if (!only.empty() && only.find("," + c.name + ",") == std::string::npos) continue;
    const Mesh mesh = c.mesh();
    const double cpu0 = leeway::detail::process_cpu_ms();
    const auto t0 = std::chrono::steady_clock::now();
    const leeway::ConvexSplit split = leeway::convex_split(mesh, options);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double cpu = (leeway::detail::process_cpu_ms() - cpu0) / 1e3;
    std::printf("| %s (%s) | %d | %s | %zu | %.3g | %s | %.2f | %.2f |\n", c.name.c_str(), c.what.c_str(),
                split.triangles, split.closed ? "yes" : "no", split.pieces.size(), split.worst_excess,
                split.reached ? "yes" : "no", wall, cpu);
    std::fflush(stdout);
  }
  return 0;
}
