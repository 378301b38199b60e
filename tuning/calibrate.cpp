#include <cmath>
#include <iostream>
#include <random>

#include "stages.hpp"

namespace leeway::tune_cli {

namespace {

constexpr int kCalibrationRandomPoints = 24;

}  // namespace

// The time proxy, fitted once on this machine to process CPU times (medians of 3 runs; CPU time is
// what a single-threaded run costs, undisturbed by other processes on a shared machine): the start
// at 5 MAX_cells spread log-evenly over the range on the first case, plus random points of the
// search box spread over the cases, so that checks, boxes and cells vary independently.
bool calibrate(Problem& pb) {
  if (!pb.o.time_model.empty()) {
    // Given coefficients (a calibration of an earlier run, or a test's): the objective no longer
    // depends on this machine's timings.
    const Eigen::VectorXd c = leeway::parse_vector(pb.o.time_model, "--time-model");
    if (c.size() != 4 || !c.allFinite() || (c.array() < 0).any())
      throw leeway::InputError("--time-model '" + pb.o.time_model +
                               "' must be four finite coefficients >= 0 [ms]: fixed, per check, per check "
                               "and box, per check and near pair");
    pb.model.ms_fixed = c[0];
    pb.model.ms_per_check = c[1];
    pb.model.ms_per_check_box = c[2];
    pb.model.ms_per_check_near = c[3];
    pb.report["time_model"] = {{"ms_fixed", c[0]},
                               {"ms_per_check", c[1]},
                               {"ms_per_check_box", c[2]},
                               {"ms_per_check_near", c[3]},
                               {"given", true}};
    std::cerr << "time proxy [ms] given: " << pb.o.time_model << "\n";
    return true;
  }
  const double lo = pb.lower(kCellsIndex);
  const double hi = pb.upper(kCellsIndex);
  std::vector<std::pair<size_t, std::vector<double>>> points;
  for (int m = 0; m < 5; ++m) {
    std::vector<double> x = pb.start;
    x[kCellsIndex] = lo + (hi - lo) * m / 4;
    points.emplace_back(0, x);
  }
  std::mt19937_64 rng(pb.o.seed + 1000);
  for (int k = 0; k < kCalibrationRandomPoints; ++k)
    points.emplace_back(static_cast<size_t>(k) % pb.cases.size(), pb.random_point(rng));
  std::cerr << "calibrating the time proxy on " << points.size() << " runs ...\n";
  std::vector<leeway::TimingSample> samples;
  json jruns = json::array();
  for (const auto& [c, x] : points) {
    if (interrupted()) return false;
    const auto t = leeway::timed_bounds(*pb.cases[c], pb.params(c, x), 3);
    const double near = leeway::near_pairs(pb.cases[c]->scene(), pb.cases[c]->path(), t.run.volume.boxes);
    samples.push_back({t.run.checks, static_cast<long>(t.run.volume.boxes.size()), near, t.cpu_ms});
    jruns.push_back({{"case", pb.labels[c]},
                     {"checks", t.run.checks},
                     {"boxes", t.run.volume.boxes.size()},
                     {"near", near},
                     {"cells", t.run.volume.cells_evaluated},
                     {"cpu_ms", t.cpu_ms},
                     {"wall_ms", t.wall_ms}});
  }
  pb.model = leeway::fit_time_model(samples);
  const auto& m = pb.model;
  std::cerr << "time proxy [ms] = " << num(m.ms_fixed, 4) << " + " << num(m.ms_per_check, 4) << " checks + "
            << num(m.ms_per_check_box, 4) << " checks x boxes + " << num(m.ms_per_check_near, 4)
            << " checks x near pairs  (R^2 " << num(m.r2, 4) << ", median relative error "
            << num(100 * m.median_rel_error, 3) << " % on " << m.samples << " runs)\n";
  pb.report["time_model"] = {{"ms_fixed", m.ms_fixed},
                             {"ms_per_check", m.ms_per_check},
                             {"ms_per_check_box", m.ms_per_check_box},
                             {"ms_per_check_near", m.ms_per_check_near},
                             {"r2", m.r2},
                             {"median_rel_error", m.median_rel_error},
                             {"runs", jruns}};
  return true;
}

}  // namespace leeway::tune_cli
