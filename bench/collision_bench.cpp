// The fast collision core against MuJoCo's full pass, with Google Benchmark: one check
// against volumes of growing size for both checkers, a whole bounds run against MAX_cells, and
// `leeway cf`'s sampling. Dallara home-patch with the thesis's parameters (section 4.1).
//
// Usage: leeway-bench-collision [Google Benchmark flags], e.g.
//   build/leeway-bench-collision --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// Times are per iteration: one collision check, one compute_bounds run (one thread, or two for
// BM_BoundsThreads), one CF evaluation of 300,000 samples.
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <random>
#include <string>

#include "core/random.hpp"
#include "leeway/core/categorize.hpp"
#include "leeway/core/cell_defaults.hpp"
#include "leeway/core/confidence.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/path/nominal_path.hpp"

namespace {

using namespace leeway;

// One scene per checker, loaded once.
const Scene& scene(CollisionChecker checker) {
  static std::map<CollisionChecker, std::unique_ptr<Scene>> scenes;
  auto& s = scenes[checker];
  if (!s) {
    SceneOptions o;
    o.checker = checker;
    s = std::make_unique<Scene>(Scene::load(std::string(LEEWAY_MJCF_DIR) + "/workcells/dallara.xml", o));
  }
  return *s;
}

Params thesis_params(const Scene& s, int max_cells) {
  Params p = preset_params("thesis");
  apply_cell_defaults(s, p);
  p.height_map.max_cells = max_cells;
  return p;
}

// Configurations within 0.1 rad of the path (near the volume), the same for every run.
std::vector<Eigen::VectorXd> near_path(const Scene& s, const std::vector<Eigen::VectorXd>& path, int n) {
  std::mt19937_64 rng(1);
  std::vector<Eigen::VectorXd> out;
  for (int k = 0; k < n; ++k) {
    Eigen::VectorXd q = path[0] + detail::unit(rng) * (path[1] - path[0]);
    for (int i = 0; i < q.size(); ++i) q[i] += 0.2 * (detail::unit(rng) - 0.5);
    out.push_back(q.cwiseMax(s.lower_limits()).cwiseMin(s.upper_limits()));
  }
  return out;
}

// One check of the robot against the volume and the real obstacles (VolumeChecker, then
// RobotState), at MAX_cells = range(1), checker = range(0).
void BM_Check(benchmark::State& state) {
  const auto checker = static_cast<CollisionChecker>(state.range(0));
  const Scene& s = scene(checker);
  const auto path = keyframe_path(s, "home", "patch", 2);
  const Params p = thesis_params(s, static_cast<int>(state.range(1)));
  const Volume volume = generate_volume(categorize(s, path, p.categorize), p.height_map, p.volume);
  VolumeModel world(s, static_cast<int>(volume.boxes.size()) + 1);
  world.set_boxes(volume.boxes);
  VolumeChecker volume_checker(world);
  RobotState robot(s);
  const auto qs = near_path(s, path, 256);
  size_t k = 0;
  long hits = 0;
  for (auto _ : state) {
    const Eigen::VectorXd& q = qs[k++ % qs.size()];
    hits += volume_checker.in_collision(q) || robot.in_collision(q);
  }
  benchmark::DoNotOptimize(hits);
  state.counters["boxes"] = static_cast<double>(volume.boxes.size());
  state.SetLabel(checker_name(checker));
}
BENCHMARK(BM_Check)
    ->ArgsProduct({{static_cast<int>(CollisionChecker::kMidphase)}, {1000, 5000, 25000, 100000}})
    ->ArgsProduct({{static_cast<int>(CollisionChecker::kMujoco)}, {1000, 5000, 25000}})
    ->Unit(benchmark::kMicrosecond);

// A whole compute_bounds run (categorise, volume, inject, bound; thesis preset: no safety stage) on
// `threads` threads, MAX_cells = range(0).
void bounds_run(benchmark::State& state, int threads) {
  const Scene& s = scene(CollisionChecker::kMidphase);
  const auto path = keyframe_path(s, "home", "patch", 2);
  const Params p = thesis_params(s, static_cast<int>(state.range(0)));
  VolumeModel world(s, p.height_map.max_cells + 64);
  BoundsRun run;
  for (auto _ : state) run = compute_bounds(s, world, path, p, threads);
  state.counters["boxes"] = static_cast<double>(run.volume.boxes.size());
  state.counters["checks"] = static_cast<double>(run.checks);
  state.counters["volume_ms"] = run.ms_volume;
  state.counters["bounds_ms"] = run.ms_bounds;
}
void BM_Bounds(benchmark::State& state) { bounds_run(state, 1); }
void BM_BoundsThreads(benchmark::State& state) { bounds_run(state, 2); }
BENCHMARK(BM_Bounds)->Arg(100)->Arg(1000)->Arg(10000)->Arg(25000)->Arg(100000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BoundsThreads)->Arg(25000)->Unit(benchmark::kMillisecond);

// `leeway cf` on the bounds of the thesis's headline case (MAX_cells 25,000): 30 windows x 10,000
// samples, two threads.
void BM_Cf(benchmark::State& state) {
  const Scene& s = scene(CollisionChecker::kMidphase);
  const auto path = keyframe_path(s, "home", "patch", 2);
  const Params p = thesis_params(s, 25000);
  VolumeModel world(s, p.height_map.max_cells + 64);
  const BoundsRun run = compute_bounds(s, world, path, p, 2);
  CfParams cf;
  double value = 0;
  for (auto _ : state) value = confidence_factor(s, run.bounds, cf, 2).cf;
  state.counters["cf"] = value;
  state.counters["samples"] = static_cast<double>(cf.windows) * static_cast<double>(cf.samples);
}
BENCHMARK(BM_Cf)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  install_mujoco_error_handlers();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
