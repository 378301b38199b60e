#pragma once
// Internal to leeway-tune: the command line's settings, the loaded problem (cases, variables, start,
// time proxy, report) and the helpers its stages share (tuning/calibrate.cpp, search.cpp,
// summary.cpp, recheck.cpp, noise_study.cpp). docs/tuning.md describes them.

#include <algorithm>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "apps/dist.hpp"
#include "core/random.hpp"
#include "leeway/apps/tuning.hpp"
#include "leeway/core/confidence.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"

namespace leeway::tune_cli {

using json = nlohmann::json;

inline constexpr int kExitInterrupted = 130;              //!< the shell's code for a SIGINT
inline constexpr size_t kCellsIndex = kMaxCellsVariable;  //!< log10 MAX_cells among the variables

//! Installs the SIGINT handler: the first stops the search (the best parameters are already
//! written), the second skips the rest of the summary, a third kills the program (the default
//! action is restored).
void install_sigint_handler();
//! Whether SIGINT has come at least once.
bool interrupted();
//! How many SIGINTs have come.
int interrupt_count();

//! Seconds on the steady clock.
double now_s();
//! Spearman's rank correlation (1 for fewer than two points).
double spearman(const std::vector<double>& a, const std::vector<double>& b);
//! `v` with `precision` significant digits.
std::string num(double v, int precision = 6);
//! `v` with `decimals` digits after the point.
std::string fixed_num(double v, int decimals);
//! A case's evaluation as JSON (report).
json case_eval_json(const CaseEval& e);
//! @throws InputError(what) unless ok.
void require(bool ok, const std::string& what);

//! Everything the command line sets.
struct Options {
  std::vector<std::string> cases, fixes, ranges;
  long budget_evals = 150;
  double budget_seconds = 0;
  unsigned long seed = 1;
  std::string out = "tuned.json", log, report, params, algorithm = "direct+cobyla", aggregate = "mean",
              time = "proxy", tool = "tool0";
  double global_share = 0.5, step = 0.1;
  int population = 0, repeats = 0, threads = 1, waypoints = 2, final_samples = 10000, final_repeats = 3,
      recheck = 0, noise_study = 0;
  std::string noise_center;
  std::string time_model;  //!< --time-model A,B,C,D: the proxy's coefficients [ms], no calibration
  double noise_radius = 0.05;
  std::uint64_t final_seed = 2;
  bool no_summary = false;
  leeway::CfParams cf;
  Objective objective;
};

//! The loaded problem: cases, variables and their bounds, the start point, the time proxy.
struct Problem {
  Options o;
  std::string command;
  json base_json;  // null without --params
  std::vector<leeway::TunedVariable> vars;
  std::vector<bool> fixed;
  std::vector<double> start;
  std::vector<double> noise_center;  // --noise-center's point (empty without it)
  std::vector<std::unique_ptr<TuningCase>> cases;
  std::vector<std::string> labels;
  leeway::TimeModel model;
  json report;
  dist::Pool* pool = nullptr;  // runs the cases of an evaluation (main.cpp); rank 0 only

  size_t size() const { return vars.size(); }
  double lower(size_t i) const { return fixed[i] ? start[i] : vars[i].lower; }
  double upper(size_t i) const { return fixed[i] ? start[i] : vars[i].upper; }
  // The variables with MAX_cells rounded: equal keys give equal results.
  std::vector<double> canonical(const std::vector<double>& x) const {
    std::vector<double> k = x;
    k[kCellsIndex] = leeway::max_cells_from_log10(x[kCellsIndex]);
    return k;
  }
  Params params(size_t c, const std::vector<double>& x) const {
    return leeway::apply_variables(cases[c]->cell_params(), x);
  }
  // A uniformly random point of the box (free variables) that meets the LB < UB constraints.
  std::vector<double> random_point(std::mt19937_64& rng) const {
    for (int attempt = 0; attempt < 100000; ++attempt) {
      std::vector<double> x = start;
      for (size_t i = 0; i < size(); ++i)
        if (!fixed[i]) x[i] = lower(i) + (upper(i) - lower(i)) * leeway::detail::unit(rng);
      if (leeway::meets_bound_constraints(x)) return x;
    }
    throw InputError("the variables' ranges leave almost no room for d_t_lb + " + num(leeway::kMinBoundGap) +
                     " <= d_t_ub and d_g_lb + " + num(leeway::kMinBoundGap) +
                     " <= d_g_ub; widen them with --range");
  }
  // x with every free variable within its range (to 1e-12, then clamped) and LB + gap <= UB.
  // @throws InputError starting with `what` and ending with `hint` otherwise.
  std::vector<double> checked_point(std::vector<double> x, const std::string& what,
                                    const std::string& hint) const {
    for (size_t i = 0; i < size(); ++i) {
      if (fixed[i]) continue;
      if (x[i] < vars[i].lower - 1e-12 || x[i] > vars[i].upper + 1e-12)
        throw InputError(what + ": '" + vars[i].name + "' = " + num(x[i]) + " lies outside its range " +
                         num(vars[i].lower) + " .. " + num(vars[i].upper) + hint);
      x[i] = std::clamp(x[i], vars[i].lower, vars[i].upper);
    }
    if (!leeway::meets_bound_constraints(x))
      throw InputError(what + " violates d_t_lb + " + num(leeway::kMinBoundGap) + " <= d_t_ub or d_g_lb + " +
                       num(leeway::kMinBoundGap) + " <= d_g_ub" + hint);
    return x;
  }
  void write_report() const {
    if (!o.report.empty()) leeway::write_file_atomic(o.report, report.dump(2) + "\n");
  }
};

//! Checks every setting and loads every case, before anything is evaluated.
//! @throws InputError on a bad setting, case, variable, parameter file or output directory.
void load(Problem& pb);

}  // namespace leeway::tune_cli
