#include "io/convex_hull.hpp"

#include <cstdio>
#include <cstdlib>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace leeway::detail {

Hull convex_hull(const std::vector<Eigen::Vector3d>& points) {
  Hull hull;
  if (points.size() < 4) return hull;
  std::vector<coordT> coords;
  coords.reserve(3 * points.size());
  for (const auto& p : points) coords.insert(coords.end(), {p.x(), p.y(), p.z()});
  // qhull writes warnings and errors to a stream: a memory stream, so nothing reaches the terminal.
  char* buffer = nullptr;
  size_t size = 0;
  FILE* messages = ::open_memstream(&buffer, &size);
  qhT context;
  qhT* qh = &context;
  qh_zero(qh, messages);
  char flags[] = "qhull Qt";
  const int code =
      qh_new_qhull(qh, 3, static_cast<int>(points.size()), coords.data(), False, flags, nullptr, messages);
  if (code == 0) {
    hull.ok = true;
    vertexT* vertex = nullptr;
    vertexT** vertexp = nullptr;
    facetT* facet = nullptr;
    FORALLvertices {
      const coordT* c = vertex->point;
      hull.vertices.emplace_back(c[0], c[1], c[2]);
    }
    FORALLfacets {
      std::array<Eigen::Vector3d, 3> tri;
      int k = 0;
      FOREACHvertex_(facet->vertices) {
        if (k < 3) tri[k] = Eigen::Vector3d(vertex->point[0], vertex->point[1], vertex->point[2]);
        ++k;
      }
      if (k == 3) hull.triangles.push_back(tri);
      hull.planes.emplace_back(facet->normal[0], facet->normal[1], facet->normal[2], facet->offset);
    }
    qh_getarea(qh, qh->facet_list);
    hull.volume = qh->totvol;
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong = 0, totlong = 0;
  qh_memfreeshort(qh, &curlong, &totlong);
  std::fclose(messages);
  std::free(buffer);
  return hull;
}

}  // namespace leeway::detail
