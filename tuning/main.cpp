// leeway-tune: searches the height-function parameters with NLopt to maximise the Confidence
// Factor per unit of time on a set of (cell, path) cases (issue #5). docs/tuning.md describes the
// objective, the algorithm, the noise handling and a full run. Units SI; times in ms unless noted.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <thread>

#include "cli_parse.hpp"
#include "leeway/confidence.hpp"
#include "leeway/error.hpp"
#include "leeway/tuning.hpp"
#include "tuner.hpp"

namespace {

using leeway::CaseEval;
using leeway::InputError;
using leeway::Objective;
using leeway::Params;
using leeway::TuningCase;
using nlohmann::json;

// SIGINT: the first stops the search (the best parameters are already written), the second skips
// the rest of the summary, a third kills the program (the default action is restored).
volatile std::sig_atomic_t g_interrupts = 0;
extern "C" void on_sigint(int) {
  g_interrupts = g_interrupts + 1;
  if (g_interrupts >= 2) std::signal(SIGINT, SIG_DFL);
}
bool interrupted() { return g_interrupts > 0; }

constexpr int kExitInterrupted = 130;  // the shell's code for a SIGINT
constexpr size_t kCellsIndex = leeway::kMaxCellsVariable;
constexpr int kCalibrationRandomPoints = 24;
constexpr double kRecheckGap = 0.02;  // J points between the rechecked evaluations

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Ranks from 0, ties sharing their average rank.
std::vector<double> ranks(const std::vector<double>& v) {
  std::vector<size_t> idx(v.size());
  for (size_t i = 0; i < idx.size(); ++i) idx[i] = i;
  std::sort(idx.begin(), idx.end(), [&](size_t a, size_t b) { return v[a] < v[b]; });
  std::vector<double> r(v.size());
  for (size_t i = 0; i < idx.size();) {
    size_t j = i;
    while (j + 1 < idx.size() && v[idx[j + 1]] == v[idx[i]]) ++j;
    for (size_t k = i; k <= j; ++k) r[idx[k]] = (static_cast<double>(i) + static_cast<double>(j)) / 2;
    i = j + 1;
  }
  return r;
}

// Spearman's rank correlation.
double spearman(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() < 2) return 1;
  const auto ra = ranks(a), rb = ranks(b);
  const double n = static_cast<double>(a.size());
  double ma = 0, mb = 0;
  for (size_t i = 0; i < ra.size(); ++i) ma += ra[i] / n, mb += rb[i] / n;
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < ra.size(); ++i) {
    sab += (ra[i] - ma) * (rb[i] - mb);
    saa += (ra[i] - ma) * (ra[i] - ma);
    sbb += (rb[i] - mb) * (rb[i] - mb);
  }
  return saa > 0 && sbb > 0 ? sab / std::sqrt(saa * sbb) : 1;
}

std::string num(double v, int precision = 6) {
  std::ostringstream os;
  os << std::setprecision(precision) << v;
  return os.str();
}

std::string fixed_num(double v, int decimals) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(decimals) << v;
  return os.str();
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  return "unknown CPU";
}

json case_eval_json(const CaseEval& e) {
  return {{"cf", e.cf},
          {"ci95", {e.ci_low, e.ci_high}},
          {"wall_ms", e.wall_ms},
          {"cpu_ms", e.cpu_ms},
          {"cost_ms", e.cost_ms},
          {"checks", e.checks},
          {"boxes", e.boxes},
          {"near", e.near},
          {"cells", e.cells},
          {"bisected", e.bisected},
          {"collapsed", e.collapsed},
          {"mean_width", e.mean_width},
          {"shortfall", e.shortfall},
          {"score", e.score}};
}

// "name=value" or "name=lo:hi".
std::pair<std::string, std::string> split_assignment(const std::string& text, const std::string& flag) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
    throw InputError(flag + " '" + text + "' must be NAME=" + (flag == "--fix" ? "VALUE" : "LO:HI"));
  return {text.substr(0, eq), text.substr(eq + 1)};
}

double parse_number(const std::string& text, const std::string& what) {
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size() && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  throw InputError(what + ": '" + text + "' is not a finite number");
}

void require(bool ok, const std::string& what) {
  if (!ok) throw InputError(what);
}

// Everything the command line sets.
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
  double noise_radius = 0.05;
  std::uint64_t final_seed = 2;
  bool no_summary = false;
  leeway::CfParams cf;
  Objective objective;
};

// The loaded problem: cases, variables and their bounds, the start point, the time proxy.
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
        if (!fixed[i])
          x[i] = lower(i) + (upper(i) - lower(i)) * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
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

// Index of a tuned variable by name; "max_cells" names log10_max_cells, given in cells.
size_t variable_index(const std::vector<leeway::TunedVariable>& vars, const std::string& name,
                      const std::string& flag, bool& in_cells) {
  in_cells = name == "max_cells";
  const std::string key = in_cells ? "log10_max_cells" : name;
  for (size_t i = 0; i < vars.size(); ++i)
    if (vars[i].name == key) return i;
  std::string names;
  for (const auto& v : vars) names += (names.empty() ? "" : ", ") + v.name;
  throw InputError(flag + ": unknown variable '" + name + "'; variables: " + names + ", max_cells");
}

// Checks every setting and loads every case, before anything is evaluated.
void load(Problem& pb) {
  Options& o = pb.o;
  o.objective.worst_case = o.aggregate == "worst";
  o.objective.time = o.time == "wall"  ? Objective::Time::kWall
                     : o.time == "cpu" ? Objective::Time::kCpu
                                       : Objective::Time::kProxy;
  if (o.repeats == 0) o.repeats = o.objective.time == Objective::Time::kProxy ? 1 : 3;
  require(o.budget_evals >= 0, "--budget-evals " + std::to_string(o.budget_evals) + " must be >= 0");
  require(o.budget_seconds >= 0 && std::isfinite(o.budget_seconds), "--budget-seconds must be >= 0");
  require(o.noise_study > 0 || o.budget_evals > 0 || o.budget_seconds > 0,
          "give a budget: --budget-evals N or --budget-seconds S");
  require(o.repeats >= 1, "--repeats " + std::to_string(o.repeats) + " must be >= 1");
  require(o.final_repeats >= 1, "--final-repeats must be >= 1");
  require(o.threads >= 1, "--threads " + std::to_string(o.threads) + " must be >= 1");
  require(o.cf.windows >= 1 && o.cf.samples >= 1, "--cf-windows and --cf-samples must be >= 1");
  require(o.final_samples >= 1, "--final-samples must be >= 1");
  require(o.recheck >= 0 && o.noise_study >= 0, "--recheck and --noise-study must be >= 0");
  require(o.noise_study == 0 || !o.log.empty(), "--noise-study writes its rows to --log FILE: give one");
  require(o.noise_radius > 0 && o.noise_radius <= 1, "--noise-radius must be in (0, 1]");
  require(o.objective.lambda >= 0 && o.objective.mu >= 0 && o.objective.min_width >= 0,
          "--lambda, --mu and --min-width must be >= 0");
  require(o.step > 0 && o.step <= 1, "--step must be in (0, 1]");
  leeway::tune::parse_stages(o.algorithm, o.global_share);  // throws on an unknown stage

  if (!o.params.empty()) {
    std::ifstream in(o.params);
    if (!in) throw InputError(o.params + ": cannot open the parameter file");
    try {
      pb.base_json = json::parse(in);
    } catch (const json::exception& e) {
      throw InputError(o.params + ": malformed JSON: " + e.what());
    }
    leeway::params_from_json(pb.base_json, o.params).validate();
  }

  // Variables: bounds from --range, values from --fix.
  pb.vars = leeway::tuned_variables();
  const size_t nv = pb.vars.size();
  pb.fixed.assign(nv, false);
  std::vector<double> fixed_value(nv, 0);
  for (const auto& r : o.ranges) {
    const auto [name, value] = split_assignment(r, "--range");
    bool cells = false;
    const size_t i = variable_index(pb.vars, name, "--range", cells);
    const auto colon = value.find(':');
    require(colon != std::string::npos, "--range '" + r + "' must be NAME=LO:HI");
    double lo = parse_number(value.substr(0, colon), "--range " + name);
    double hi = parse_number(value.substr(colon + 1), "--range " + name);
    require(lo < hi, "--range '" + r + "': LO must be smaller than HI");
    if (cells) {
      require(lo >= 1 && hi <= 1e6, "--range max_cells must lie within 1 and 1000000");
      lo = std::log10(lo);
      hi = std::log10(hi);
    }
    pb.vars[i].lower = lo;
    pb.vars[i].upper = hi;
  }
  for (const auto& f : o.fixes) {
    const auto [name, value] = split_assignment(f, "--fix");
    bool cells = false;
    const size_t i = variable_index(pb.vars, name, "--fix", cells);
    double v = parse_number(value, "--fix " + name);
    if (cells) {
      require(v >= 1 && v <= 1e6 && v == std::floor(v),
              "--fix max_cells must be a whole number from 1 to 1000000");
      v = std::log10(v);
    }
    pb.fixed[i] = true;
    fixed_value[i] = v;
  }
  const int max_cells_hi = leeway::max_cells_from_log10(pb.fixed[kCellsIndex] ? fixed_value[kCellsIndex]
                                                                              : pb.vars[kCellsIndex].upper);

  // Cases: files, keyframes, limits and volume pools, all before the first evaluation.
  leeway::SceneOptions scene_opts;
  scene_opts.tool_site = o.tool;
  for (const auto& text : o.cases) {
    const auto spec = leeway::parse_case(text);
    pb.cases.push_back(
        std::make_unique<TuningCase>(spec, pb.base_json, o.waypoints, max_cells_hi, scene_opts));
    pb.labels.push_back(spec.label());
  }

  // The start: the first case's parameters (the thesis's unless --params set them).
  std::vector<double> start = leeway::variables_of(pb.cases.front()->cell_params());
  for (size_t i = 0; i < nv; ++i)
    if (pb.fixed[i]) start[i] = fixed_value[i];
  pb.start = pb.checked_point(start, "the start point", "; change --range, --fix or --params");
  for (size_t c = 0; c < pb.cases.size(); ++c) pb.params(c, pb.start).validate();

  // --noise-center: read and checked like the start, before anything is evaluated.
  if (!o.noise_center.empty()) {
    require(o.noise_study > 0, "--noise-center needs --noise-study K");
    std::vector<double> center =
        leeway::variables_of(leeway::read_params(o.noise_center, pb.cases.front()->cell_params()));
    for (size_t i = 0; i < nv; ++i)
      if (pb.fixed[i]) center[i] = fixed_value[i];
    pb.noise_center = pb.checked_point(center, "--noise-center " + o.noise_center, "");
  }

  // Output files: fail now rather than after the search.
  for (const auto& [file, flag] : {std::pair{o.out, "--out"}, {o.report, "--report"}, {o.log, "--log"}}) {
    if (file.empty()) continue;
    const auto dir = std::filesystem::absolute(file).parent_path();
    require(std::filesystem::is_directory(dir),
            std::string(flag) + " " + file + ": the directory " + dir.string() + " does not exist");
  }

  pb.report["command"] = pb.command;
  pb.report["machine"] = {{"cpu", cpu_model()}, {"hardware_threads", std::thread::hardware_concurrency()}};
  pb.report["cases"] = pb.labels;
  pb.report["objective"] = {{"lambda", o.objective.lambda},
                            {"mu", o.objective.mu},
                            {"min_width", o.objective.min_width},
                            {"aggregate", o.aggregate},
                            {"time", o.time},
                            {"repeats", o.repeats},
                            {"cf_windows", o.cf.windows},
                            {"cf_samples", o.cf.samples},
                            {"cf_seed", o.cf.seed}};
  json jv = json::array();
  for (size_t i = 0; i < nv; ++i)
    jv.push_back({{"name", pb.vars[i].name},
                  {"lower", pb.lower(i)},
                  {"upper", pb.upper(i)},
                  {"thesis", pb.vars[i].thesis},
                  {"start", pb.start[i]},
                  {"fixed", static_cast<bool>(pb.fixed[i])},
                  {"unit", pb.vars[i].unit}});
  pb.report["variables"] = jv;
}

// The time proxy, fitted once on this machine to process CPU times (medians of 3 runs; CPU time is
// what a single-threaded run costs, undisturbed by other processes on a shared machine): the start
// at 5 MAX_cells spread log-evenly over the range on the first case, plus random points of the
// search box spread over the cases, so that checks, boxes and cells vary independently.
bool calibrate(Problem& pb) {
  const double lo = pb.lower(kCellsIndex);
  const double hi = std::min(pb.upper(kCellsIndex), std::log10(20000.0));
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
      leeway::width_stats(c.scene(), run.bounds, o.objective.min_width, e);
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

// The search, the tuned file, the before/after summary and the ranking check.
int tune(Problem& pb, std::ostream* log) {
  const Options& o = pb.o;
  const Objective& objective = o.objective;
  const size_t nv = pb.size();
  const double t0 = now_s();

  std::map<std::vector<double>, std::vector<CaseEval>> details;  // by canonical variables
  auto evaluate = [&](const std::vector<double>& x) -> std::optional<double> {
    std::vector<CaseEval> evals;
    for (size_t k = 0; k < pb.cases.size(); ++k) {
      if (interrupted()) return std::nullopt;
      evals.push_back(leeway::evaluate_case(*pb.cases[k], pb.params(k, x), o.cf, o.repeats, o.threads,
                                            pb.model, objective));
    }
    const double j = leeway::aggregate_score(evals, objective);
    details[pb.canonical(x)] = evals;
    return j;
  };

  if (log) {
    *log << "eval,stage,feasible,cached";
    for (const auto& v : pb.vars) *log << "," << v.name;
    *log << ",max_cells,cf_mean,cf_min,wall_ms,cpu_ms,cost_ms,collapsed,bisected,mean_width,shortfall,"
            "objective,"
            "best,elapsed_s";
    for (const auto& l : pb.labels)
      *log << ",cf:" << l << ",wall_ms:" << l << ",cpu_ms:" << l << ",cost_ms:" << l << ",collapsed:" << l
           << ",mean_width:" << l << ",score:" << l;
    *log << "\n" << std::flush;
  }

  auto write_tuned = [&](const std::vector<double>& x) {
    leeway::write_file_atomic(o.out, leeway::tuned_params_json(pb.base_json, pb.params(0, x)).dump(2) + "\n");
  };
  std::vector<leeway::tune::Record> records;
  int written = 0;
  double written_objective = 0;
  auto on_record = [&](const leeway::tune::Record& r) {
    records.push_back(r);
    const int cells = leeway::max_cells_from_log10(r.x[kCellsIndex]);
    const std::vector<CaseEval>* ev = nullptr;
    if (r.feasible) {
      const auto it = details.find(pb.canonical(r.x));
      if (it != details.end()) ev = &it->second;
    }
    // Means over the cases (the CF's minimum too), intervals summed.
    double cf_mean = 0, cf_min = 1, wall = 0, cpu = 0, cost = 0, width = 0, shortfall = 0;
    int collapsed = 0, bisected = 0;
    if (ev) {
      const double n = static_cast<double>(ev->size());
      for (const auto& e : *ev) {
        cf_mean += e.cf / n;
        cf_min = std::min(cf_min, e.cf);
        wall += e.wall_ms / n;
        cpu += e.cpu_ms / n;
        cost += e.cost_ms / n;
        collapsed += e.collapsed;
        bisected += e.bisected;
        width += e.mean_width * e.bisected;
        shortfall += e.shortfall / n;
      }
      width /= std::max(1, bisected);
    }
    if (log) {
      *log << r.number << "," << r.stage << "," << (r.feasible ? 1 : 0) << "," << (r.cached ? 1 : 0);
      for (double v : r.x) *log << "," << num(v, 10);
      *log << "," << cells;
      if (ev)
        *log << "," << num(100 * cf_mean, 10) << "," << num(100 * cf_min, 10) << "," << num(wall) << ","
             << num(cpu) << "," << num(cost) << "," << collapsed << "," << bisected << "," << num(width)
             << "," << num(shortfall);
      else
        *log << ",,,,,,,,,";
      *log << "," << num(r.objective, 10) << "," << num(r.best, 10) << "," << num(r.elapsed_s);
      for (size_t k = 0; k < pb.labels.size(); ++k) {
        if (ev) {
          const auto& e = (*ev)[k];
          *log << "," << num(100 * e.cf, 10) << "," << num(e.wall_ms) << "," << num(e.cpu_ms) << ","
               << num(e.cost_ms) << "," << e.collapsed << "," << num(e.mean_width) << "," << num(e.score, 10);
        } else {
          *log << ",,,,,,,";
        }
      }
      *log << "\n" << std::flush;
    }
    // Progress: evaluation number, objective, best so far, elapsed time.
    std::cerr << "[" << r.number << (o.budget_evals > 0 ? "/" + std::to_string(o.budget_evals) : "") << "] "
              << std::left << std::setw(7) << r.stage << std::right << " J " << fixed_num(r.objective, 4)
              << "  best " << fixed_num(r.best, 4);
    if (ev)
      std::cerr << "  CF " << fixed_num(100 * cf_mean, 3) << " %  time "
                << fixed_num(objective.time == Objective::Time::kWall  ? wall
                             : objective.time == Objective::Time::kCpu ? cpu
                                                                       : cost,
                             1)
                << " ms  MAX_cells " << cells << "  collapsed " << collapsed << "/" << bisected;
    else if (!r.feasible)
      std::cerr << "  (violates LB < UB: not run)";
    std::cerr << "  " << fixed_num(r.elapsed_s, 1) << " s" << (r.cached ? "  (cached)" : "") << "\n";
    // The best parameters so far are on disk at every moment: an interrupt (or a kill) keeps them.
    if (r.feasible && (written == 0 || r.objective > written_objective)) {
      write_tuned(r.x);
      written = r.number;
      written_objective = r.objective;
    }
  };

  leeway::tune::Space space;
  for (size_t i = 0; i < nv; ++i) {
    space.names.push_back(pb.vars[i].name);
    space.lower.push_back(pb.lower(i));
    space.upper.push_back(pb.upper(i));
  }
  space.start = pb.start;
  space.fixed = pb.fixed;
  space.constraints = leeway::bound_constraints;
  space.constraint_count = 2;
  space.canonical = [&pb](const std::vector<double>& x) { return pb.canonical(x); };
  leeway::tune::Settings settings;
  settings.stages = leeway::tune::parse_stages(o.algorithm, o.global_share);
  settings.budget_evals = o.budget_evals;
  settings.budget_seconds = o.budget_seconds;
  settings.seed = o.seed;
  settings.step = o.step;
  settings.population = o.population;
  // A point that violates LB < UB is not run: it scores below any real evaluation (100 CF - lambda T
  // - mu S >= -lambda T - mu), so that no algorithm mistakes it for progress.
  settings.infeasible_value = -1000 - objective.mu;

  std::cerr << "tuning " << pb.cases.size() << " case(s) with " << o.algorithm << ": J = 100 CF - "
            << num(objective.lambda) << " T[s] - " << num(objective.mu) << " S (min width "
            << num(objective.min_width) << " rad), " << o.aggregate << " over the cases, time " << o.time
            << "\n";
  const auto outcome = leeway::tune::search(space, settings, evaluate, interrupted, on_record);
  const double search_s = now_s() - t0;
  if (outcome.evaluations == 0) {
    std::cerr << "leeway-tune: interrupted before the first evaluation; nothing written\n";
    return kExitInterrupted;
  }
  write_tuned(outcome.best_x);
  const Params best = pb.params(0, outcome.best_x);
  std::cout << "stopped: " << outcome.stop << "; " << outcome.evaluations << " evaluations in "
            << fixed_num(search_s, 1) << " s\n";
  std::cout << "best J " << num(outcome.best, 8) << " at evaluation " << outcome.best_number << " (start "
            << num(records.front().objective, 8) << "); wrote " << o.out << "\n";
  std::cout << "tuned parameters [thesis]:\n";
  for (size_t i = 0; i < nv; ++i) {
    if (i == kCellsIndex)
      std::cout << "  max_cells     " << best.height_map.max_cells << "  ["
                << leeway::max_cells_from_log10(pb.vars[i].thesis) << "]";
    else
      std::cout << "  " << std::left << std::setw(12) << pb.vars[i].name << std::right << "  "
                << num(outcome.best_x[i], 5) << " " << pb.vars[i].unit << "  [" << num(pb.vars[i].thesis)
                << "]";
    std::cout << (pb.fixed[i] ? "  (fixed)" : "") << "\n";
  }

  // The proxy against the measured CPU and wall times of every run of the search.
  {
    std::vector<double> cost, wall, cpu, rel;
    for (const auto& [k, evs] : details)
      for (const auto& e : evs) {
        cost.push_back(e.cost_ms);
        wall.push_back(e.wall_ms);
        cpu.push_back(e.cpu_ms);
        if (e.cpu_ms > 0) rel.push_back(std::abs(e.cost_ms - e.cpu_ms) / e.cpu_ms);
      }
    const double rho_cpu = spearman(cost, cpu), rho_wall = spearman(cost, wall), err = leeway::median(rel);
    std::cout << "time proxy over the search's " << cost.size() << " runs: Spearman " << num(rho_cpu, 4)
              << " with CPU time, " << num(rho_wall, 4) << " with wall time; median relative error "
              << num(100 * err, 3) << " % (CPU)\n";
    pb.report["proxy_check"] = {{"runs", cost.size()},
                                {"spearman_cpu", rho_cpu},
                                {"spearman_wall", rho_wall},
                                {"median_rel_error_cpu", err}};
  }
  pb.report["search"] = {{"algorithm", o.algorithm},
                         {"global_share", o.global_share},
                         {"seed", o.seed},
                         {"budget_evals", o.budget_evals},
                         {"budget_seconds", o.budget_seconds},
                         {"evaluations", outcome.evaluations},
                         {"stop", outcome.stop},
                         {"seconds", search_s},
                         {"best_evaluation", outcome.best_number},
                         {"best_objective", outcome.best},
                         {"start_objective", records.front().objective},
                         {"best_x", outcome.best_x}};
  pb.report["tuned_params"] = leeway::tuned_params_json(pb.base_json, best);
  pb.write_report();

  const bool stopped_by_user = interrupted();
  if (o.no_summary || g_interrupts >= 2) return stopped_by_user ? kExitInterrupted : leeway::kExitOk;
  if (stopped_by_user) std::cerr << "summary of the best so far (Ctrl-C again to skip it)\n";

  // Before / after: the start parameters at the tuned MAX_cells (and at their own), and the tuned
  // ones, with the summary's CF (fresh seed, more samples) and medians of measured times.
  leeway::CfParams cf_final = o.cf;
  cf_final.samples = o.final_samples;
  cf_final.seed = o.final_seed;
  // By case and canonical variables: the ranking check's first point is the tuned one, evaluated here.
  std::map<std::pair<size_t, std::vector<double>>, CaseEval> final_evals;
  auto final_eval = [&](size_t k, const std::vector<double>& x) {
    const auto key = std::make_pair(k, pb.canonical(x));
    auto it = final_evals.find(key);
    if (it == final_evals.end())
      it = final_evals
               .emplace(key, leeway::evaluate_case(*pb.cases[k], pb.params(k, x), cf_final, o.final_repeats,
                                                   o.threads, pb.model, objective))
               .first;
    return it->second;
  };
  const int tuned_cells = best.height_map.max_cells;
  const int start_cells = leeway::max_cells_from_log10(pb.start[kCellsIndex]);
  std::vector<std::pair<std::string, std::vector<double>>> configs;
  std::vector<double> start_at_tuned = pb.start;
  start_at_tuned[kCellsIndex] = outcome.best_x[kCellsIndex];
  configs.emplace_back("start@" + std::to_string(tuned_cells), start_at_tuned);
  if (start_cells != tuned_cells) configs.emplace_back("start@" + std::to_string(start_cells), pb.start);
  configs.emplace_back("tuned", outcome.best_x);
  std::cout
      << "\nbefore / after (CF " << cf_final.windows << " x " << o.final_samples << " samples, seed "
      << o.final_seed << "; times: medians of " << o.final_repeats << " runs, wall (CPU) [proxy] ms):\n"
      << "| case | parameters | MAX_cells | boxes | CF [%] | time [ms] | collapsed | mean width [rad] | J |\n"
      << "|---|---|---:|---:|---:|---|---:|---:|---:|\n";
  json summary = json::array();
  std::map<std::string, std::vector<CaseEval>> per_config;
  for (size_t k = 0; k < pb.cases.size() && g_interrupts < 2; ++k) {
    json jc = {{"case", pb.labels[k]}, {"configs", json::array()}};
    for (const auto& [name, x] : configs) {
      if (g_interrupts >= 2) break;
      const Params p = pb.params(k, x);
      const CaseEval e = final_eval(k, x);
      per_config[name].push_back(e);
      std::cout << "| " << pb.labels[k] << " | " << name << " | " << p.height_map.max_cells << " | "
                << e.boxes << " | " << fixed_num(100 * e.cf, 4) << " | " << fixed_num(e.wall_ms, 1) << " ("
                << fixed_num(e.cpu_ms, 1) << ") [" << fixed_num(e.cost_ms, 1) << "] | " << e.collapsed << "/"
                << e.bisected << " | " << fixed_num(e.mean_width, 3) << " | " << fixed_num(e.score, 3)
                << " |\n"
                << std::flush;
      json je = case_eval_json(e);
      je["name"] = name;
      je["max_cells"] = p.height_map.max_cells;
      jc["configs"].push_back(je);
    }
    summary.push_back(jc);
  }
  pb.report["summary"] = summary;
  pb.report["summary_settings"] = {{"cf_windows", cf_final.windows},
                                   {"cf_samples", o.final_samples},
                                   {"cf_seed", o.final_seed},
                                   {"repeats", o.final_repeats}};
  json totals = json::object();
  for (const auto& [name, evs] : per_config)
    if (evs.size() == pb.cases.size()) {
      totals[name] = leeway::aggregate_score(evs, objective);
      std::cout << "J (" << o.aggregate << " over the cases) " << name << ": "
                << num(totals[name].get<double>(), 8) << "\n";
    }
  pb.report["summary_objective"] = totals;
  pb.write_report();

  // Ranking check: K of the best evaluations re-scored with the summary's CF and measured times
  // instead of the proxy.
  if (o.recheck > 0 && g_interrupts < 2) {
    std::vector<std::pair<double, std::vector<double>>> top;
    for (const auto& r : records)
      if (r.feasible) top.emplace_back(r.objective, r.x);
    std::stable_sort(top.begin(), top.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    // A ladder: the best, then each next one at least kRecheckGap below the previous, so that the
    // order being checked is more than the proxy's microseconds (and no point comes twice: equal
    // parameters score equally).
    std::vector<std::pair<double, std::vector<double>>> ladder;
    for (const auto& t : top)
      if (ladder.size() < static_cast<size_t>(o.recheck) &&
          (ladder.empty() || t.first <= ladder.back().first - kRecheckGap))
        ladder.push_back(t);
    top = ladder;
    json points = json::array();
    std::vector<double> a, b_wall, b_cpu;
    for (size_t i = 0; i < top.size() && g_interrupts < 2; ++i) {
      std::vector<CaseEval> evs;
      for (size_t k = 0; k < pb.cases.size(); ++k) evs.push_back(final_eval(k, top[i].second));
      Objective by_wall = objective, by_cpu = objective;
      by_wall.time = Objective::Time::kWall;
      by_cpu.time = Objective::Time::kCpu;
      auto rescore = [&](const Objective& ob) {
        for (auto& e : evs) leeway::score_case(e, ob);
        return leeway::aggregate_score(evs, ob);
      };
      const double jw = rescore(by_wall), jc = rescore(by_cpu);
      a.push_back(top[i].first);
      b_wall.push_back(jw);
      b_cpu.push_back(jc);
      points.push_back({{"search_objective", top[i].first},
                        {"wall_objective", jw},
                        {"cpu_objective", jc},
                        {"x", top[i].second}});
      std::cout << "recheck " << i + 1 << ": search J " << fixed_num(top[i].first, 4)
                << ", summary CF with wall time " << fixed_num(jw, 4) << ", with CPU time "
                << fixed_num(jc, 4) << "\n";
    }
    if (a.size() == top.size()) {
      pb.report["recheck"] = {
          {"points", points}, {"spearman_wall", spearman(a, b_wall)}, {"spearman_cpu", spearman(a, b_cpu)}};
      std::cout << "recheck rank correlation with the search's ranking (Spearman): wall "
                << num(spearman(a, b_wall), 4) << ", CPU " << num(spearman(a, b_cpu), 4) << "\n";
      pb.write_report();
    }
  }
  std::cout << "total " << fixed_num(now_s() - t0, 1) << " s\n";
  return stopped_by_user ? kExitInterrupted : leeway::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "leeway-tune: search the height-function parameters with NLopt to maximise CF per unit of time\n"
      "over (cell, path) cases; writes a parameter file for `leeway bounds --params` (docs/tuning.md).\n"
      "Exit 0 done, 2 bad input (nothing evaluated), 3 internal error, 130 interrupted (best so far "
      "written)."};
  Problem pb;
  Options& o = pb.o;
  o.cf.samples = 1000;
  app.add_option("--case", o.cases, "A case CELL.xml:FROM:TO (repeat for more)")->required();
  app.add_option(
      "--budget-evals", o.budget_evals,
      "Stop after this many evaluations (0: no limit; default 150, no limit with --budget-seconds)");
  app.add_option("--budget-seconds", o.budget_seconds,
                 "Stop the search after this wall time [s] (0: no limit)")
      ->capture_default_str();
  app.add_option("--seed", o.seed, "Seed of the stochastic algorithms, the calibration and --noise-study")
      ->capture_default_str();
  app.add_option("--out", o.out, "Tuned parameter file (for leeway bounds --params)")->capture_default_str();
  app.add_option("--log", o.log, "CSV log of every evaluation");
  app.add_option("--report", o.report, "JSON report: settings, time proxy, before/after summary");
  app.add_option("--params", o.params, "Base parameter file: its keys apply to every case before tuning");
  app.add_option("--algorithm", o.algorithm,
                 "Stages joined by '+', e.g. direct+cobyla; stages: " + leeway::tune::stage_names())
      ->capture_default_str();
  app.add_option("--global-share", o.global_share, "Share of the budgets for the global stages")
      ->capture_default_str();
  app.add_option("--step", o.step, "Local stages' initial step, as a fraction of each variable's range")
      ->capture_default_str();
  app.add_option("--population", o.population,
                 "Population of isres, crs2, esch (0: 2 x (free variables + 1))")
      ->capture_default_str();
  app.add_option("--aggregate", o.aggregate, "Aggregate the cases' scores by their mean or the worst")
      ->check(CLI::IsMember({"mean", "worst"}))
      ->capture_default_str();
  app.add_option("--lambda", o.objective.lambda, "Objective: CF percentage points per second of time")
      ->capture_default_str();
  app.add_option("--mu", o.objective.mu, "Objective: CF percentage points for a path of narrow intervals")
      ->capture_default_str();
  app.add_option("--min-width", o.objective.min_width,
                 "Objective: bisected intervals narrower [rad] fall short")
      ->capture_default_str();
  app.add_option("--time", o.time, "Time in the objective: calibrated proxy, or measured wall or CPU time")
      ->check(CLI::IsMember({"proxy", "wall", "cpu"}))
      ->capture_default_str();
  app.add_option("--repeats", o.repeats,
                 "Runs per evaluation whose median is the time (default: 1 proxy, 3 else)");
  app.add_option("--cf-windows", o.cf.windows, "CF windows")->capture_default_str();
  app.add_option("--cf-samples", o.cf.samples, "CF samples per window during the search")
      ->capture_default_str();
  app.add_option("--cf-seed", o.cf.seed, "CF seed during the search (the same for every evaluation)")
      ->capture_default_str();
  app.add_option("--final-samples", o.final_samples, "CF samples per window in the summary")
      ->capture_default_str();
  app.add_option("--final-seed", o.final_seed, "CF seed in the summary (not --cf-seed: fresh samples)")
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
                 "Instead of tuning: evaluate the start and K-1 random points repeatedly into --log");
  app.add_option("--noise-center", o.noise_center,
                 "--noise-study around this parameter file's point instead of over the whole box");
  app.add_option("--noise-radius", o.noise_radius, "--noise-center's moves, as a fraction of each range")
      ->capture_default_str();
  app.add_option("--tool", o.tool, "Name of the robot's tool site")->capture_default_str();

  return leeway::detail::run_reporting_errors("leeway-tune", [&]() -> int {
    if (const auto code = leeway::detail::parse_cli(app, argc, argv)) return *code;
    if (app.count("--budget-evals") == 0 && o.budget_seconds > 0) o.budget_evals = 0;
    leeway::install_mujoco_handlers();
    pb.command = "leeway-tune";
    for (int i = 1; i < argc; ++i) pb.command += std::string(" ") + argv[i];
    load(pb);
    std::ofstream log;
    if (!o.log.empty()) {
      log.open(o.log);
      require(static_cast<bool>(log), "--log " + o.log + ": cannot write");
    }
    std::signal(SIGINT, on_sigint);
    if (!calibrate(pb)) {
      std::cerr << "leeway-tune: interrupted before the first evaluation; nothing written\n";
      return kExitInterrupted;
    }
    if (o.noise_study > 0) return noise_study(pb, log);
    return tune(pb, log.is_open() ? &log : nullptr);
  });
}
