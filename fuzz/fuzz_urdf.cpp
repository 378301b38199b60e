// libFuzzer target: a URDF file through import_urdf, and the imported robot through MuJoCo and
// Scene in a minimal cell (docs/testing.md, "Fuzzing").
//
// Contract: import_urdf (urdf_import.hpp) returns an MJCF robot fragment or throws
// leeway::InputError naming the file, element and value: unreadable or invalid URDF (urdfdom's
// message, urdfdom's own exceptions included), a joint loop, a pose, size or limit that is not a
// finite number, a mesh that cannot be resolved, found or read as STL, a chain joint leeway cannot
// model, nothing that moves; UrdfOptionError (an InputError) for a missing tool or base link or a
// refused continuous joint. A fragment it returns must compile with MuJoCo inside a cell: the
// target writes it beside a cell that includes it and loads that with Scene::load, which may
// refuse the robot with an InputError of its own (a joint range beyond kMaxLength, a limit MuJoCo's
// compiler reads differently), but "MJCF does not compile" means the importer wrote MJCF MuJoCo
// rejects, a finding. Anything else is a finding: another exception, a crash, a sanitizer report,
// a leak, a timeout. One leak is urdfdom's, not leeway's, and suppressed for this target only:
// fuzz/urdf.lsan.supp says which.
//
// The input is TMP/leeway-fuzz-XXXXXX/robot.urdf; the folder also holds meshes/cube.stl and the
// package pkgs/leeway_test_irb6700/meshes/link_{3,5}.stl (unit cubes, ASCII STL), with pkgs as the
// package path, so that mesh references in the seeds resolve.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "fuzz_input.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/scene.hpp"
#include "leeway/io/urdf_import.hpp"

namespace {

namespace fs = std::filesystem;

const leeway::fuzz::InputFile& input() {
  static const leeway::fuzz::InputFile file("robot.urdf");
  return file;
}

// The unit cube [0, 1]^3 as an ASCII STL: two triangles per face.
std::string cube_stl() {
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  auto corner = [](int i) {
    return std::to_string(i & 1) + " " + std::to_string((i >> 1) & 1) + " " + std::to_string((i >> 2) & 1);
  };
  std::string out = "solid cube\n";
  for (const auto& f : faces)
    for (const auto& t : {std::array<int, 3>{f[0], f[1], f[2]}, std::array<int, 3>{f[0], f[2], f[3]}}) {
      out += "facet normal 0 0 0\nouter loop\n";
      for (int c : t) out += "vertex " + corner(c) + "\n";
      out += "endloop\nendfacet\n";
    }
  return out + "endsolid cube\n";
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  leeway::install_mujoco_error_handlers();
  const fs::path dir = input().dir();
  const fs::path meshes = dir / "pkgs" / "leeway_test_irb6700" / "meshes";
  fs::create_directories(meshes);
  fs::create_directories(dir / "meshes");
  for (const fs::path& p : {dir / "meshes" / "cube.stl", meshes / "link_3.stl", meshes / "link_5.stl"})
    std::ofstream(p) << cube_stl();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = input().write(data, size);
  leeway::UrdfImportOptions options;
  options.package_paths = {(input().dir() / "pkgs").string()};
  leeway::UrdfImport robot;
  try {
    robot = leeway::import_urdf(path, options);
  } catch (const leeway::InputError& e) {
    leeway::fuzz::require_names_file(e, path);
    return 0;
  }
  // The fragments in a cell, as leeway new-cell writes one (new_cell.hpp): the robot in the world
  // body, the excludes (and the mesh geoms' assets) at the top level, the mesh copies beside them.
  const fs::path dir = input().dir();
  for (const leeway::UrdfMeshFile& mesh : robot.meshes) {
    const fs::path file(mesh.file);
    if (file.is_absolute() || mesh.file.find("..") != std::string::npos) return 0;  // stays in dir
    fs::create_directories((dir / file).parent_path());
    std::ofstream(dir / file, std::ios::binary) << mesh.bytes;
  }
  std::ofstream(dir / "robot.xml") << robot.mjcf;
  std::ofstream(dir / "robot_excludes.xml") << robot.excludes_mjcf;
  const std::string cell = (dir / "cell.xml").string();
  std::ofstream(cell) << "<mujoco>\n  <compiler angle=\"radian\" autolimits=\"true\"/>\n"
                         "  <include file=\"robot_excludes.xml\"/>\n"
                         "  <worldbody>\n    <include file=\"robot.xml\"/>\n  </worldbody>\n</mujoco>\n";
  try {
    leeway::Scene::load(cell);
  } catch (const leeway::InputError& e) {
    const std::string message = e.what();
    if (message.find("MJCF does not compile") != std::string::npos) {
      std::fprintf(stderr, "leeway fuzz: the imported robot does not compile:\n%s\n--- robot.xml:\n%s\n",
                   message.c_str(), robot.mjcf.c_str());
      std::abort();
    }
  }
  leeway::take_mujoco_warnings();
  return 0;
}
