#include <algorithm>
#include <iostream>
#include <random>

#include "stages.hpp"

namespace leeway::tune_cli {

// --noise-study K: the start and K-1 random points (or, with --noise-center, a point and K-1 moves
// around it), each on every case with the bounding step repeated (wall and CPU times), the CF at
// three seeds of the search's size and once at the summary's size. One CSV row per (point, case);
// tools/make_tuning_doc.py analyses them.
int noise_study(Problem& pb, std::ostream& log) {
  const Options& o = pb.o;
  std::mt19937_64 rng(o.seed);
  std::vector<std::vector<double>> points{pb.start};
  if (o.noise_center.empty()) {
    while (static_cast<int>(points.size()) < o.noise_study) points.push_back(pb.random_point(rng));
  } else {
    // Around a parameter file's point: each free variable moved uniformly by up to +- radius x its
    // range, within the bounds, keeping LB + gap <= UB.
    const std::vector<double>& center = pb.noise_center;
    points = {center};
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int attempt = 0; static_cast<int>(points.size()) < o.noise_study; ++attempt) {
      require(attempt < 100000, "--noise-center " + o.noise_center + ": no feasible point around it");
      std::vector<double> x = center;
      for (size_t i = 0; i < pb.size(); ++i)
        if (!pb.fixed[i])
          x[i] = std::clamp(center[i] + o.noise_radius * (pb.upper(i) - pb.lower(i)) * u(rng), pb.lower(i),
                            pb.upper(i));
      if (leeway::meets_bound_constraints(x)) points.push_back(x);
    }
  }
  log << "point,case";
  for (const auto& v : pb.vars) log << "," << v.name;
  log << ",max_cells,checks,boxes,cells,cost_ms";
  for (int r = 0; r < o.repeats; ++r) log << ",wall_ms_" << r + 1;
  for (int r = 0; r < o.repeats; ++r) log << ",cpu_ms_" << r + 1;
  log << ",cf_seed_a,cf_seed_b,cf_seed_c,cf_final,bisected,collapsed,mean_width,shortfall,near\n"
      << std::flush;
  const double t0 = now_s();
  for (size_t pi = 0; pi < points.size() && !interrupted(); ++pi) {
    for (size_t k = 0; k < pb.cases.size() && !interrupted(); ++k) {
      auto& c = *pb.cases[k];
      const Params p = pb.params(k, points[pi]);
      std::vector<double> wall, cpu;
      leeway::BoundsRun run;
      for (int r = 0; r < o.repeats; ++r) {
        const auto t = leeway::timed_bounds(c, p, 1);
        wall.push_back(t.wall_ms);
        cpu.push_back(t.cpu_ms);
        run = t.run;
      }
      CaseEval e;
      leeway::width_stats(c.scene(), p.bounds, run.bounds, o.objective.min_width, e);
      std::vector<double> cfs;
      for (std::uint64_t s = 0; s < 3; ++s) {
        leeway::CfParams cp = o.cf;
        cp.seed = o.cf.seed + s;
        cfs.push_back(leeway::confidence_factor(c.scene(), run.bounds, cp, o.threads).cf);
      }
      leeway::CfParams fp = o.cf;
      fp.samples = o.final_samples;
      fp.seed = o.final_seed;
      cfs.push_back(leeway::confidence_factor(c.scene(), run.bounds, fp, o.threads).cf);
      const long boxes = static_cast<long>(run.volume.boxes.size());
      log << pi + 1 << "," << pb.labels[k];
      for (double v : points[pi]) log << "," << num(v, 10);
      const double near = leeway::near_pairs(c.scene(), c.path(), run.volume.boxes);
      log << "," << p.height_map.max_cells << "," << run.checks << "," << boxes << ","
          << run.volume.cells_evaluated << "," << num(pb.model.predict(run.checks, boxes, near));
      for (double t : wall) log << "," << num(t);
      for (double t : cpu) log << "," << num(t);
      for (double v : cfs) log << "," << num(v, 10);
      log << "," << e.bisected << "," << e.collapsed << "," << num(e.mean_width) << "," << num(e.shortfall)
          << "," << num(near) << "\n"
          << std::flush;
    }
    std::cerr << "noise study: point " << pi + 1 << " of " << points.size() << ", "
              << fixed_num(now_s() - t0, 1) << " s\n";
  }
  pb.report["noise_study"] = {{"center", o.noise_center.empty() ? json(nullptr) : json(o.noise_center)},
                              {"radius", o.noise_radius},
                              {"points", points.size()},
                              {"repeats", o.repeats},
                              {"final_samples", o.final_samples},
                              {"seconds", now_s() - t0}};
  pb.write_report();
  return interrupted() ? kExitInterrupted : leeway::kExitOk;
}

}  // namespace leeway::tune_cli
