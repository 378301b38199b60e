// leeway-tune: searches the height-function parameters with NLopt to maximise the Confidence
// Factor per unit of time on a set of (cell, path) cases. docs/tuning.md describes the
// objective, the algorithm, the noise handling and a full run. Units SI; times in ms unless noted.
// This file wires CLI11 and runs the stages in order; each stage is in its own file (stages.hpp).
#include <CLI/CLI.hpp>

#include <fstream>
#include <iostream>
#include <string>

#include "cli/support.hpp"
#include "distribute.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/mujoco_util.hpp"
#include "problem.hpp"
#include "stages.hpp"

namespace {

using namespace leeway::tune_cli;

// The search, the tuned file, the before/after summary and the ranking check.
int tune(Problem& pb, std::ostream* log) {
  const Options& o = pb.o;
  const double t0 = now_s();
  const auto result = search(pb, log, t0);
  if (!result) return kExitInterrupted;
  const bool stopped_by_user = interrupted();
  if (o.no_summary || interrupt_count() >= 2) return stopped_by_user ? kExitInterrupted : leeway::kExitOk;
  if (stopped_by_user) std::cerr << "summary of the best so far (Ctrl-C again to skip it)\n";
  FinalEvals evals(pb);
  summary(pb, *result, evals);
  if (o.recheck > 0 && interrupt_count() < 2) recheck(pb, *result, evals);
  std::cout << "total " << fixed_num(now_s() - t0, 1) << " s\n";
  return stopped_by_user ? kExitInterrupted : leeway::kExitOk;
}

// leeway-tune's options, into `o` (docs/tuning.md).
void add_options(CLI::App& app, Options& o) {
  app.add_option("--case", o.cases, "A case CELL.xml:FROM:TO (repeat for more; required)");
  app.add_option(
      "--budget-evals", o.budget_evals,
      "Stop after this many evaluations (0: no limit; default 150, no limit with --budget-seconds)");
  app.add_option("--budget-seconds", o.budget_seconds,
                 "Stop the search after this wall time [s] (0: no limit)")
      ->check(leeway::cli::finite_check())
      ->capture_default_str();
  app.add_option("--seed", o.seed, "Seed of the stochastic algorithms, the calibration and --noise-study")
      ->check(leeway::cli::seed_check_for(o.seed))
      ->capture_default_str();
  app.add_option("--out", o.out, "Tuned parameter file (for leeway bounds --params)")
      ->check(leeway::cli::file_name_check())
      ->capture_default_str();
  app.add_option("--log", o.log, "CSV log of every evaluation")->check(leeway::cli::file_name_check());
  app.add_option("--report", o.report, "JSON report: settings, time proxy, before/after summary")
      ->check(leeway::cli::file_name_check());
  app.add_option("--params", o.params, "Base parameter file: its keys apply to every case before tuning")
      ->check(leeway::cli::file_name_check());
  app.add_option("--algorithm", o.algorithm,
                 "Stages joined by '+', e.g. direct+cobyla; stages: " + leeway::tune::stage_names())
      ->capture_default_str();
  app.add_option("--global-share", o.global_share, "Share of the budgets for the global stages")
      ->capture_default_str();
  app.add_option("--step", o.step, "Local stages' initial step, as a fraction of each variable's range")
      ->capture_default_str();
  app.add_option("--population", o.population,
                 "Population of isres, crs2, esch (0: 2 x (free variables + 1))")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  app.add_option("--aggregate", o.aggregate, "Aggregate the cases' scores by their mean or the worst")
      ->check(CLI::IsMember({"mean", "worst"}))
      ->capture_default_str();
  app.add_option("--lambda", o.objective.lambda, "Objective: CF percentage points per second of time")
      ->check(leeway::cli::finite_check())
      ->capture_default_str();
  app.add_option("--mu", o.objective.mu, "Objective: CF percentage points for a path of narrow intervals")
      ->check(leeway::cli::finite_check())
      ->capture_default_str();
  app.add_option("--min-width", o.objective.min_width,
                 "Objective: bisected intervals narrower [rad] fall short")
      ->check(leeway::cli::finite_check())
      ->capture_default_str();
  app.add_option("--time", o.time, "Time in the objective: calibrated proxy, or measured wall or CPU time")
      ->check(CLI::IsMember({"proxy", "wall", "cpu"}))
      ->capture_default_str();
  app.add_option("--time-model", o.time_model,
                 "The proxy's coefficients A,B,C,D [ms] (fixed, per check, per check and box, per check and "
                 "near pair) instead of calibrating them: reproducible objectives across machines");
  app.add_option("--repeats", o.repeats,
                 "Runs per evaluation whose median is the time (default: 1 proxy, 3 else)")
      ->check(CLI::Range(1, 1000));
  app.add_option("--cf-windows", o.cf.windows, "CF windows")->capture_default_str();
  app.add_option("--cf-samples", o.cf.samples, "CF samples per window during the search")
      ->capture_default_str();
  app.add_option("--cf-seed", o.cf.seed, "CF seed during the search (the same for every evaluation)")
      ->check(leeway::cli::seed_check_for(o.cf.seed))
      ->capture_default_str();
  app.add_option("--final-samples", o.final_samples, "CF samples per window in the summary")
      ->capture_default_str();
  app.add_option("--final-seed", o.final_seed, "CF seed in the summary (not --cf-seed: fresh samples)")
      ->check(leeway::cli::seed_check_for(o.final_seed))
      ->capture_default_str();
  app.add_option("--final-repeats", o.final_repeats, "Runs whose median is a summary time")
      ->capture_default_str();
  app.add_option("--recheck", o.recheck,
                 "Re-score K of the best evaluations (each next one at least 0.02 below the previous in J) "
                 "with measured times and the summary's CF")
      ->capture_default_str();
  app.add_option("--threads", o.threads, "Threads of the CF (the timed bounding step runs on one)")
      ->capture_default_str();
  app.add_option("--waypoints", o.waypoints, "Waypoints along each joint-linear path")->capture_default_str();
  app.add_option("--fix", o.fixes, "Keep a variable at a value: NAME=VALUE (max_cells in cells)");
  app.add_option("--range", o.ranges, "Change a variable's bounds: NAME=LO:HI (max_cells in cells)");
  app.add_flag("--no-summary", o.no_summary, "Skip the before/after summary");
  app.add_option("--noise-study", o.noise_study,
                 "Instead of tuning: evaluate the start and K-1 random points repeatedly into --log")
      ->check(CLI::Range(1, 100000));
  app.add_option("--noise-center", o.noise_center,
                 "--noise-study around this parameter file's point instead of over the whole box")
      ->check(leeway::cli::file_name_check());
  app.add_option("--noise-radius", o.noise_radius, "--noise-center's moves, as a fraction of each range")
      ->capture_default_str();
  app.add_option("--tool", o.tool, "Name of the robot's tool site")->capture_default_str();
}

}  // namespace

int main(int argc, char** argv) {
  leeway::cli::ignore_sigpipe();  // a closed standard output is exit 2, not SIGPIPE
  CLI::App app{
      "leeway-tune: search the height-function parameters with NLopt to maximise CF per unit of time\n"
      "over (cell, path) cases; writes a parameter file for `leeway bounds --params` (docs/tuning.md).\n"
      "Exit 0 done, 2 bad input (nothing evaluated), 3 internal error, 130 interrupted (best so far "
      "written)."};
  Problem pb;
  Options& o = pb.o;
  o.cf.samples = 1000;
  add_options(app, o);

  return leeway::cli::run_reporting_errors("leeway-tune", [&]() -> int {
    if (const auto code = leeway::cli::parse_cli(app, argc, argv, "leeway-tune")) return *code;
    if (app.count("--budget-evals") == 0 && o.budget_seconds > 0) o.budget_evals = 0;
    leeway::install_mujoco_error_handlers();
    pb.command = "leeway-tune";
    for (int i = 1; i < argc; ++i) pb.command += std::string(" ") + argv[i];
    leeway::install_temp_file_cleanup();
    require(!o.cases.empty(), "--case is required: give at least one case CELL.xml:FROM:TO");
    load(pb);
    // Under mpirun every rank has loaded the problem; ranks other than 0 evaluate cases for rank 0.
    const auto pool = leeway::dist::make_pool(case_handler(pb));
    if (pool->rank() != 0) {
      pool->serve();
      return leeway::kExitOk;
    }
    pb.pool = pool.get();
    // The log is locked before any work (a second run with the same --log is refused now rather
    // than interleaving its rows); its old content stays until the calibration is done.
    leeway::StreamingOutput log;
    if (!o.log.empty()) log = leeway::StreamingOutput(o.log, "--log");
    install_sigint_handler();
    if (!calibrate(pb)) {
      std::cerr << "leeway-tune: interrupted before the first evaluation; nothing written\n";
      return kExitInterrupted;
    }
    // Emptied (an existing log replaced) only now: an interrupted calibration leaves it as it was.
    if (log.is_open()) log.truncate();
    if (o.noise_study > 0) return noise_study(pb, log.stream());
    return tune(pb, log.is_open() ? &log.stream() : nullptr);
  });
}
