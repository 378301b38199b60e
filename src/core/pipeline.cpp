#include "leeway/core/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <string>

#include "grow.hpp"
#include "leeway/core/categorize.hpp"
#include "leeway/core/error.hpp"

namespace leeway {
namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

void validate_for_scene(const Params& params, const Scene& scene) {
  params.validate();
  grow_mask(scene, params.safety);
  half_width_caps(scene, params.safety);
  // bound_kinds refuses a 'bounds.bisect' that names a joint the robot lacks or a slide joint.
  const auto kinds = bound_kinds(scene, params.bounds);
  const auto& joints = scene.joints();
  for (const auto& [name, width] : params.bounds.half_width) {
    const auto it = std::find_if(joints.begin(), joints.end(),
                                 [&name = name](const RobotJoint& j) { return j.name == name; });
    const std::string named =
        scene.source() + ": parameter 'bounds.half_width." + name + "' = " + format_number(width);
    if (it == joints.end()) {
      std::string known;
      for (const auto& j : joints) known += (known.empty() ? "" : ", ") + j.name;
      throw InputError(named + " names a joint the robot does not have (joints: " + known + ")");
    }
    if (kinds[static_cast<size_t>(it - joints.begin())] == BoundKind::kBisected)
      throw InputError(named + ": joint '" + name + "' is bisected, so it has no fixed half-width" +
                       (params.bounds.bisect.empty()
                            ? " (without 'bounds.bisect' the first three hinge joints are)"
                            : " (it is in 'bounds.bisect')"));
  }
  for (size_t i = 0; i < kinds.size(); ++i) {
    const RobotJoint& j = scene.joints()[i];
    if (kinds[i] == BoundKind::kBisected && !(2 * params.bounds.min_half_width < j.upper - j.lower))
      throw InputError(scene.source() + ": parameter 'bounds.min_half_width' = " +
                       format_number(params.bounds.min_half_width) +
                       " rad must be smaller than half the range of joint '" + j.name + "' [" +
                       format_number(j.lower) + ", " + format_number(j.upper) + "] rad");
  }
}

BoundsRun compute_bounds(const Scene& scene, VolumeModel& world, const std::vector<Eigen::VectorXd>& path,
                         const Params& params, int threads) {
  validate_for_scene(params, scene);
  BoundsRun run;
  auto t = std::chrono::steady_clock::now();
  run.categories = categorize(scene, path, params.categorize);
  run.ms_categorize = ms_since(t);
  t = std::chrono::steady_clock::now();
  run.volume = generate_volume(run.categories, params.height_map, params.volume);
  run.ms_volume = ms_since(t);
  t = std::chrono::steady_clock::now();
  world.set_boxes(run.volume.boxes);
  run.ms_inject = ms_since(t);
  t = std::chrono::steady_clock::now();
  run.bounds = bound_path(world, path, params.bounds, threads);
  run.ms_bounds = ms_since(t);
  for (const auto& b : run.bounds) run.checks += b.checks;
  t = std::chrono::steady_clock::now();
  run.safety = make_safe(scene, run.bounds, params.safety, threads);
  run.ms_safety = ms_since(t);
  return run;
}

}  // namespace leeway
