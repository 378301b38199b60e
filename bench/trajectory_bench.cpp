// BoundsTrajectory's queries, with Google Benchmark: at_t on a 1,000-waypoint path of six joints
// (allocation-free and allocating forms), and sample(0.001) over the whole path. The waypoints are
// synthetic (a seeded random walk within +-0.2 rad boxes); the queries' cost depends only on their
// count and the joint count, not on the cell.
//
// Usage: leeway-bench-trajectory [Google Benchmark flags], e.g.
//   build/leeway-bench-trajectory --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// Targets: at_t <= 1 us per call; sample(0.001) on 1,000 waypoints reported (the Python target,
// <= 50 ms, adds the conversion to numpy).
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "leeway/core/bounds_trajectory.hpp"

namespace {

using namespace leeway;

const BoundsTrajectory& path_of_1000() {
  static const BoundsTrajectory tr = [] {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> step(-0.01, 0.01), half(0.0, 0.2);
    std::vector<WaypointBounds> w;
    std::vector<double> times;
    Eigen::VectorXd q = Eigen::VectorXd::Zero(6);
    double t = 0;
    for (int i = 0; i < 1000; ++i) {
      Eigen::VectorXd lo(6), hi(6);
      for (int j = 0; j < 6; ++j) {
        q[j] += step(rng);
        lo[j] = q[j] - half(rng);
        hi[j] = q[j] + half(rng);
      }
      w.emplace_back(q, lo, hi);
      times.push_back(t);
      t += 0.01;  // 10 ms per segment: a 9.99 s path
    }
    return BoundsTrajectory(std::move(w), std::move(times), true);
  }();
  return tr;
}

void BM_AtTInto(benchmark::State& state) {
  const BoundsTrajectory& tr = path_of_1000();
  Eigen::VectorXd nominal(6), lower(6), upper(6);
  double t = 0;
  for (auto _ : state) {
    tr.at_t(t, nominal, lower, upper);
    benchmark::DoNotOptimize(lower.data());
    t += 0.0137;
    if (t > tr.duration()) t -= tr.duration();
  }
}
BENCHMARK(BM_AtTInto);

void BM_AtT(benchmark::State& state) {
  const BoundsTrajectory& tr = path_of_1000();
  double t = 0;
  for (auto _ : state) {
    BoundsStage b = tr.at_t(t);
    benchmark::DoNotOptimize(b.lower.data());
    t += 0.0137;
    if (t > tr.duration()) t -= tr.duration();
  }
}
BENCHMARK(BM_AtT);

void BM_Sample1ms(benchmark::State& state) {
  const BoundsTrajectory& tr = path_of_1000();
  for (auto _ : state) {
    std::vector<BoundsStage> rows = tr.sample(0.001);
    benchmark::DoNotOptimize(rows.data());
  }
}
BENCHMARK(BM_Sample1ms)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
