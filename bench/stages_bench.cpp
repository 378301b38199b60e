// Stage times of leeway's method against the number of volume boxes, on the bundled cells' thesis
// paths. Prints a Markdown table of medians over repeated runs measured in this one process.
//
// Usage: leeway-bench-stages [--repeats N] [--cells LIST] [--cell NAME] [--from A] [--to B]
//                            [--threads T] [--margin M]
// Every number is SI: milliseconds for stage times, microseconds per collision check.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "apps/statistics.hpp"
#include "core/random.hpp"
#include "leeway/apps/tuning.hpp"
#include "leeway/core/cell_defaults.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/path/nominal_path.hpp"

namespace {

using leeway::detail::median;

double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace

int main(int argc, char** argv) {
  int repeats = 5, threads = 1;
  double margin = 0.0;
  std::string cell = "dallara", from = "home", to = "patch";
  std::string cells_list = "100,500,1000,2000,5000,10000,20000,25000,50000,100000";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--repeats")
      repeats = std::atoi(v.c_str());
    else if (k == "--cells")
      cells_list = v;
    else if (k == "--cell")
      cell = v;
    else if (k == "--from")
      from = v;
    else if (k == "--to")
      to = v;
    else if (k == "--threads")
      threads = std::atoi(v.c_str());
    else if (k == "--margin")
      margin = std::atof(v.c_str());
    else {
      std::cerr << "unknown option " << k << "\n";
      return 2;
    }
  }
  try {
    const std::string path_file = std::string(LEEWAY_MJCF_DIR) + "/workcells/" + cell + ".xml";
    const leeway::Scene scene = leeway::Scene::load(path_file);
    leeway::Params base;
    leeway::apply_cell_defaults(scene, base);
    base.safety.mode = leeway::SafetyMode::kNone;  // the method's own stages (the thesis preset)
    base.volume.trail_margin = margin;
    const auto path = leeway::keyframe_path(scene, from, to, 2);
    std::vector<int> cells;
    for (const double c : leeway::parse_vector(cells_list, "--cells")) cells.push_back(static_cast<int>(c));

    const double t0 = now_ms();
    leeway::VolumeModel world(scene, *std::max_element(cells.begin(), cells.end()) + 16);
    const double setup_ms = now_ms() - t0;

    std::printf("# %s %s -> %s, %d repeat(s), %d thread(s), trail_margin %.3f m; medians\n", cell.c_str(),
                from.c_str(), to.c_str(), repeats, threads, margin);
    std::printf(
        "# one-off set-up (the volume model: the link geoms and a pool grown to %d geoms): %.1f ms\n\n",
        world.capacity(), setup_ms);
    std::printf(
        "| MAX_cells | boxes | checks | categorize ms | volume ms | inject ms | bounds ms | total ms |"
        " us/check | kinematics us | collision us |\n");
    std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int c : cells) {
      leeway::Params p = base;
      p.height_map.max_cells = c;
      std::vector<double> cat, vol, inj, bnd, tot;
      long checks = 0;
      size_t boxes = 0;
      for (int r = 0; r < repeats; ++r) {
        const auto run = leeway::compute_bounds(scene, world, path, p, threads);
        cat.push_back(run.ms_categorize);
        vol.push_back(run.ms_volume);
        inj.push_back(run.ms_inject);
        bnd.push_back(run.ms_bounds);
        tot.push_back(run.ms_total());
        checks = run.checks;
        boxes = run.volume.boxes.size();
      }
      // Where a check's time goes: robot kinematics alone against a whole check, on 400 random
      // configurations near the path (the volume of the last run is still in the pool).
      leeway::VolumeChecker checker(world);
      leeway::RobotState robot(scene);
      std::mt19937_64 rng(1);
      std::vector<Eigen::VectorXd> qs;
      for (int k = 0; k < 400; ++k) {
        const double s = leeway::detail::unit(rng);
        Eigen::VectorXd q = path[0] + s * (path[1] - path[0]);
        for (int i = 0; i < q.size(); ++i) q[i] += 0.2 * (leeway::detail::unit(rng) - 0.5);
        qs.push_back(q.cwiseMax(scene.lower_limits()).cwiseMin(scene.upper_limits()));
      }
      std::vector<double> kin, full;
      for (int r = 0; r < 3; ++r) {
        double a = now_ms();
        for (const auto& q : qs) robot.set(q);
        kin.push_back((now_ms() - a) * 1000 / static_cast<double>(qs.size()));
        a = now_ms();
        for (const auto& q : qs) checker.in_collision(q);
        full.push_back((now_ms() - a) * 1000 / static_cast<double>(qs.size()));
      }
      const double k_us = median(kin), f_us = median(full);
      std::printf("| %d | %zu | %ld | %.2f | %.2f | %.2f | %.1f | %.1f | %.1f | %.1f | %.1f |\n", c, boxes,
                  checks, median(cat), median(vol), median(inj), median(bnd), median(tot),
                  median(bnd) * 1000 * threads / static_cast<double>(std::max(1L, checks)), k_us,
                  f_us - k_us);
      std::fflush(stdout);
    }
  } catch (const leeway::InputError& e) {
    std::cerr << "leeway-bench-stages: error: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
