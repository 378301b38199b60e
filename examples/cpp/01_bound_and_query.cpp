// Example 1: load a cell, bound the joint-linear path between two of its keyframes with the default
// preset (bounds proven free by the certificate), and look the bounds up as a controller would: by
// nominal time t and by path parameter s (docs/cli.md, "Contract for a controller").
//
//   leeway-example-01 [CELL.xml [FROM TO [OUT.json]]]
//
// Defaults: the bundled Dallara cell, home -> patch; OUT.json, when given, receives the bounds file
// (format leeway-bounds-2) for example 2. Units: rad for hinge joints, m for slide joints, s for time.
#include <cstdio>
#include <string>

#include "leeway/core/bounds_trajectory.hpp"
#include "leeway/core/cell_defaults.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/io/bounds_file.hpp"
#include "leeway/path/nominal_path.hpp"

int main(int argc, char** argv) {
  using namespace leeway;
  const std::string cell = argc > 1 ? argv[1] : std::string(LEEWAY_MJCF_DIR) + "/workcells/dallara.xml";
  const std::string from = argc > 3 ? argv[2] : "home", to = argc > 3 ? argv[3] : "patch";
  install_mujoco_error_handlers();  // MuJoCo's errors become exceptions instead of ending the process
  try {
    const Scene scene = Scene::load(cell);
    // The leeway preset (certified safety), with the cell's own defaults (custom numerics).
    Params params = preset_params("leeway");
    apply_cell_defaults(scene, params);
    params.validate();
    validate_for_scene(params, scene);

    // Two waypoints: the keyframes themselves. (`leeway bounds` also checks the straight path
    // between them first and plans around an obstacle; see docs/cli.md.)
    const std::vector<Eigen::VectorXd> path = keyframe_path(scene, from, to, 2);
    VolumeModel world(scene, params.height_map.max_cells + static_cast<int>(scene.obstacle_geoms().size()));
    const BoundsRun run = compute_bounds(scene, world, path, params, /*threads=*/2);
    std::printf("%s, %s -> %s: %s\n", cell.c_str(), from.c_str(), to.c_str(),
                run.safety.all_passed ? "certified free" : "NOT certified");

    // The bounds as a trajectory: boxes at any s (0 .. N - 1) or nominal time t (0 .. duration).
    const BoundsTrajectory trajectory(scene, run.bounds);
    std::printf("duration %.3f s (nominal joint speeds)\n", trajectory.duration());
    for (double t : {0.0, 0.5 * trajectory.duration(), trajectory.duration()}) {
      const BoundsStage b = trajectory.at_t(t);
      std::printf("t = %.3f s, s = %.3f:", b.t, b.s);
      for (int j = 0; j < scene.dof(); ++j)
        std::printf(" %s [%.3f, %.3f]", scene.joint_names()[static_cast<size_t>(j)].c_str(), b.lower[j],
                    b.upper[j]);
      std::printf(" rad\n");
      // The nominal configuration is always inside its own box.
      if (!trajectory.contains(b.s, b.nominal)) return 1;
    }
    if (argc > 4) {
      write_file_atomic(argv[4], bounds_json(scene, run, params).dump(2) + "\n");
      std::printf("wrote %s\n", argv[4]);
    }
    return 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "leeway-example-01: %s\n", e.what());
    return 2;
  }
}
