#include "problem.hpp"

#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>
#include <thread>

#include "cli/support.hpp"
#include "core/json_io.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/mjcf_source.hpp"
#include "tuner.hpp"

namespace leeway::tune_cli {
namespace {

volatile std::sig_atomic_t g_interrupts = 0;
extern "C" void on_sigint(int) {
  g_interrupts = g_interrupts + 1;
  if (g_interrupts >= 2) std::signal(SIGINT, SIG_DFL);
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

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  return "unknown CPU";
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

}  // namespace

void install_sigint_handler() { std::signal(SIGINT, on_sigint); }
bool interrupted() { return g_interrupts > 0; }
int interrupt_count() { return g_interrupts; }

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
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

std::string num(double v, int precision) {
  std::ostringstream os;
  os << std::setprecision(precision) << v;
  return os.str();
}

std::string fixed_num(double v, int decimals) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(decimals) << v;
  return os.str();
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

void require(bool ok, const std::string& what) {
  if (!ok) throw InputError(what);
}

namespace {

// The options' own checks (no file read yet); sets the derived objective settings.
void check_options(Options& o) {
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
  leeway::cli::require_threads(o.threads);
  require(o.cf.windows >= 1 && o.cf.samples >= 1, "--cf-windows and --cf-samples must be >= 1");
  leeway::cli::require_memory(o.cf.windows * leeway::cli::kBytesPerWindow,
                              "--cf-windows " + std::to_string(o.cf.windows));
  leeway::cli::require_memory(o.waypoints * leeway::cli::kBytesPerWaypoint,
                              "--waypoints " + std::to_string(o.waypoints));
  require(o.final_samples >= 1, "--final-samples must be >= 1");
  require(o.recheck >= 0 && o.noise_study >= 0, "--recheck and --noise-study must be >= 0");
  require(o.noise_study == 0 || !o.log.empty(), "--noise-study writes its rows to --log FILE: give one");
  require(o.noise_radius > 0 && o.noise_radius <= 1, "--noise-radius must be in (0, 1]");
  require(o.objective.lambda >= 0 && o.objective.mu >= 0 && o.objective.min_width >= 0,
          "--lambda, --mu and --min-width must be >= 0");
  require(o.step > 0 && o.step <= 1, "--step must be in (0, 1]");
  leeway::tune::parse_stages(o.algorithm, o.global_share);  // throws on an unknown stage
}

// --range and --fix on pb.vars: bounds changed in place, pb.fixed set, the fixed values returned in
// `fixed_value` (log10 for max_cells).
void apply_ranges_and_fixes(Problem& pb, std::vector<double>& fixed_value) {
  const Options& o = pb.o;
  const size_t nv = pb.vars.size();
  pb.fixed.assign(nv, false);
  fixed_value.assign(nv, 0);
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
      require(lo >= 1 && hi <= leeway::kMaxCellsLimit, "--range max_cells must lie within 1 and 1000000");
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
      require(v >= 1 && v <= leeway::kMaxCellsLimit && v == std::floor(v),
              "--fix max_cells must be a whole number from 1 to 1000000");
      v = std::log10(v);
    }
    pb.fixed[i] = true;
    fixed_value[i] = v;
  }
}

}  // namespace

void load(Problem& pb) {
  Options& o = pb.o;
  check_options(o);

  if (!o.params.empty()) {
    pb.base_json = leeway::detail::read_json_file(o.params, "parameter file");
    leeway::params_from_json(pb.base_json, o.params).validate();
  }

  // Variables: bounds from --range, values from --fix.
  pb.vars = leeway::tuned_variables();
  const size_t nv = pb.vars.size();
  std::vector<double> fixed_value;
  apply_ranges_and_fixes(pb, fixed_value);
  const int max_cells_hi = leeway::max_cells_from_log10(pb.fixed[kCellsIndex] ? fixed_value[kCellsIndex]
                                                                              : pb.vars[kCellsIndex].upper);

  // Cases: files, keyframes, limits and volume pools, all before the first evaluation.
  leeway::SceneOptions scene_opts;
  scene_opts.tool_site = o.tool;
  std::set<std::string> seen_cases;
  for (const auto& text : o.cases) {
    const auto spec = leeway::parse_case(text);
    // A case given twice would only weigh twice (and load its cell and volume pool twice).
    require(seen_cases.insert(spec.label()).second, "--case '" + text + "' is given twice");
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

  // Output files: fail now rather than after the search. None may replace a file the run reads (a
  // case's cell with its includes and meshes, the parameter files), nor another output.
  std::vector<std::string> inputs = {o.params, o.noise_center};
  for (const auto& text : o.cases) {
    const std::vector<std::string> cell = leeway::model_input_files(leeway::parse_case(text).cell);
    inputs.insert(inputs.end(), cell.begin(), cell.end());
  }
  leeway::require_outputs({{o.out, "--out", {}}, {o.report, "--report", {}}, {o.log, "--log", {}}}, inputs);

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

}  // namespace leeway::tune_cli
