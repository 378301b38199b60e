// A program that links the core layer alone (leeway::core, not the umbrella target): loads a
// workcell and checks its home keyframe for collisions. The ctest core_needed_libraries reads this
// program's ELF NEEDED entries: core must bring in no OSMesa, urdfdom, MPI or OMPL.
#include <cstdio>
#include <exception>
#include <string>

#include "leeway/core/error.hpp"
#include "leeway/core/kinematics.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/scene.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s CELL.xml\n", argv[0]);
    return 2;
  }
  leeway::install_mujoco_error_handlers();
  try {
    const leeway::Scene scene = leeway::Scene::load(argv[1]);
    leeway::RobotState state(scene);
    const bool home_hits = state.in_collision(scene.keyframe("home").q);
    std::printf("%s: %d joints, home %s\n", argv[1], scene.dof(), home_hits ? "in collision" : "free");
    return home_hits ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
