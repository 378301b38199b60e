#include "leeway/pipeline.hpp"

#include <chrono>

#include "leeway/categorize.hpp"

namespace leeway {
namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

BoundsRun compute_bounds(const Scene& scene, VolumeModel& world, const std::vector<Eigen::VectorXd>& path,
                         const Params& params, int threads) {
  params.validate();
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
  run.safety = make_safe(scene, run.bounds, params.safety, CertifyBound::kTaylor, threads);
  run.ms_safety = ms_since(t);
  return run;
}

}  // namespace leeway
