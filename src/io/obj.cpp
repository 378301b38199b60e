#include "leeway/io/obj.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "leeway/core/error.hpp"

namespace leeway {
namespace {

std::string where(const std::string& path, int line_no) {
  return path + ": OBJ line " + std::to_string(line_no);
}

Eigen::Vector3d read_vertex(std::istringstream& words, const std::string& path, int line_no) {
  Eigen::Vector3d p;
  for (int k = 0; k < 3; ++k) {
    std::string word;
    if (!(words >> word)) throw InputError(where(path, line_no) + ": vertex 'v' has fewer than 3 values");
    char* end = nullptr;
    p[k] = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0' || !std::isfinite(p[k]))
      throw InputError(where(path, line_no) + ": vertex value '" + word + "' is not a finite number");
  }
  return p;
}

// The vertex index of one face corner ("i", "i/j", "i/j/k", "i//k") as a 0-based index into the
// `count` vertices read so far.
size_t corner_index(const std::string& corner, size_t count, const std::string& path, int line_no) {
  const std::string first = corner.substr(0, corner.find('/'));
  char* end = nullptr;
  errno = 0;
  const long long i = std::strtoll(first.c_str(), &end, 10);
  if (first.empty() || end == first.c_str() || *end != '\0' || errno == ERANGE)
    throw InputError(where(path, line_no) + ": face corner '" + corner + "' is not a vertex index");
  const long long n = static_cast<long long>(count);
  if (i == 0 || i > n || i < -n)
    throw InputError(where(path, line_no) + ": face corner '" + corner + "' names vertex " +
                     std::to_string(i) + ", but " + std::to_string(count) +
                     " vertices are defined before it (indices 1.." + std::to_string(count) + " or -1..-" +
                     std::to_string(count) + ")");
  return static_cast<size_t>(i > 0 ? i - 1 : n + i);
}

}  // namespace

std::vector<Eigen::Vector3d> read_obj(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the OBJ file");
  std::vector<Eigen::Vector3d> points, triangles;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    std::istringstream words(line);
    std::string keyword;
    if (!(words >> keyword)) continue;
    if (keyword == "v") {
      points.push_back(read_vertex(words, path, line_no));
    } else if (keyword == "f") {
      std::vector<size_t> corners;
      for (std::string corner; words >> corner;)
        corners.push_back(corner_index(corner, points.size(), path, line_no));
      if (corners.size() < 3)
        throw InputError(where(path, line_no) + ": face 'f' has " + std::to_string(corners.size()) +
                         " corners; a face needs at least 3");
      for (size_t k = 1; k + 1 < corners.size(); ++k)
        for (const size_t c : {corners[0], corners[k], corners[k + 1]}) triangles.push_back(points[c]);
    }
  }
  if (in.bad()) throw InputError(path + ": reading the OBJ file failed");
  if (triangles.empty()) throw InputError(path + ": the OBJ file holds no face ('f' line)");
  return triangles;
}

}  // namespace leeway
