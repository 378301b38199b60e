// The safety stage's two certificate bounds compared on the nine thesis paths at the default ("leeway"
// preset) parameters: the tight Taylor bound (the default) against the loose lever-arm reference
// (docs/algorithm.md, "Certified intervals"). Per path: the guide bounds (safety none) once, then
// make_safe with each bound on a copy of them, and each bound's certificate of the guide's own
// waypoint boxes. Prints a Markdown table of medians over repeated runs measured in this one process.
//
// Usage: leeway-bench-certify [--repeats N] [--cells dallara,baltico,dlr] [--json FILE]
//                             [--lever-max-leaves L] [--box-leaves B]
// Units: milliseconds for times, radians for widths (metres for slide joints; the nine paths have none).
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "apps/statistics.hpp"
#include "leeway/apps/tuning.hpp"
#include "leeway/core/cell_defaults.hpp"
#include "leeway/core/certify.hpp"
#include "leeway/core/error.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/path/nominal_path.hpp"
#include "lever_bound.hpp"

namespace {

using leeway::detail::median;
using nlohmann::json;

double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// The two bounds compared: the Taylor bound (null: the certifier's own) and the lever reference.
const leeway::LeverBound kLeverBound;
const char* bound_name(const leeway::SweepBound* b) { return b ? "lever" : "Taylor"; }

// Mean width over the waypoints of the joints with mask[i] set [rad or m].
double mean_width(const std::vector<leeway::WaypointBounds>& bounds, const std::vector<bool>& mask) {
  double sum = 0;
  long count = 0;
  for (const auto& w : bounds)
    for (Eigen::Index i = 0; i < w.q.size(); ++i)
      if (mask[static_cast<size_t>(i)]) {
        sum += w.upper[i] - w.lower[i];
        ++count;
      }
  return count > 0 ? sum / static_cast<double>(count) : 0.0;
}

// The certificate of the guide's own waypoint boxes: region_free on each [lower, upper].
struct BoxResult {
  bool certified = true;
  long leaves = 0;     //!< all waypoints (up to the first that failed)
  int failed = -1;     //!< the waypoint that was not certified
  std::string reason;  //!< "collision", "budget" or "depth"
  double ms = 0;
};

BoxResult certify_boxes(const leeway::Scene& scene, const std::vector<leeway::WaypointBounds>& guide,
                        const leeway::SweepBound* bound, long budget) {
  leeway::CertifyOptions options;
  options.margin = leeway::SafetyParams{}.margin;
  options.max_leaves = budget;
  options.bound = bound;
  const leeway::Certifier certifier(scene, options);
  leeway::CertifyContext ctx(scene);
  BoxResult r;
  const double t0 = now_ms();
  for (size_t k = 0; k < guide.size() && r.certified; ++k) {
    leeway::CertifyStats stats;
    leeway::CertifyFailure failure;
    if (!certifier.region_free(ctx, guide[k].lower, guide[k].upper, stats, &failure)) {
      r.certified = false;
      r.failed = static_cast<int>(k);
      r.reason = failure.centre_hits                        ? "collision"
                 : failure.budget && stats.leaves >= budget ? "budget"
                                                            : "depth";
    }
    r.leaves += stats.leaves;
  }
  r.ms = now_ms() - t0;
  return r;
}

std::string box_cell(const BoxResult& r) {
  if (r.certified) return std::to_string(r.leaves);
  return "not certified (" + r.reason + " at waypoint " + std::to_string(r.failed) + ", " +
         std::to_string(r.leaves) + " leaves)";
}

json box_json(const BoxResult& r, long budget) {
  return {{"certified", r.certified}, {"leaves", r.leaves}, {"failed_waypoint", r.failed},
          {"reason", r.reason},       {"budget", budget},   {"ms", r.ms}};
}

int online_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return CPU_COUNT(&set);
  return 0;
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(" \t", colon + 1));
    }
  return "unknown";
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  char buf[64];
  std::strftime(buf, sizeof(buf), "%Y-%m-%d %H:%M UTC", std::gmtime(&t));
  return buf;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

// The defaults of the safety stage: certified, margin 1 mm, 16384 leaves per segment test.
const leeway::SafetyParams kSafety;
// The bounds compared, in row order: Taylor first, its make_safe boxes are the free boxes both bounds
// are then asked to certify.
const std::vector<const leeway::SweepBound*> kBounds = {nullptr, &kLeverBound};
// The three keyframe paths of each cell.
const std::vector<std::pair<std::string, std::string>> kPaths = {
    {"home", "patch"}, {"patch", "mould"}, {"mould", "home"}};

double median_or_zero(const std::vector<double>& v) { return v.empty() ? 0.0 : median(v); }

// The command line.
struct Options {
  std::string command;  //!< argv joined by spaces, echoed in the table and the JSON
  int repeats = 3;
  std::string cells_list = "dallara,baltico,dlr";
  std::string json_file;  //!< empty: no JSON written
  long lever_max_leaves = kSafety.max_leaves;
  long box_leaves = 1000000;
};

// Reads argv into o; on a bad command line says why on stderr and returns false.
bool parse_options(int argc, char** argv, Options& o) {
  o.command = argv[0];
  for (int i = 1; i < argc; ++i) o.command += std::string(" ") + argv[i];
  for (int i = 1; i < argc; i += 2) {
    const std::string k = argv[i];
    if (i + 1 >= argc) {
      std::cerr << "option " << k << " needs a value\n";
      return false;
    }
    const std::string v = argv[i + 1];
    if (k == "--repeats")
      o.repeats = std::atoi(v.c_str());
    else if (k == "--cells")
      o.cells_list = v;
    else if (k == "--json")
      o.json_file = v;
    else if (k == "--lever-max-leaves")
      o.lever_max_leaves = std::atol(v.c_str());
    else if (k == "--box-leaves")
      o.box_leaves = std::atol(v.c_str());
    else {
      std::cerr << "unknown option " << k << "\n";
      return false;
    }
  }
  if (o.repeats < 1 || o.lever_max_leaves < 1 || o.box_leaves < 1) {
    std::cerr << "--repeats, --lever-max-leaves and --box-leaves must be >= 1\n";
    return false;
  }
  return true;
}

// The JSON document's run description, with an empty "rows" array for the rows to come.
json run_json(const Options& o) {
  json out;
  out["command"] = o.command;
  out["units"] = "ms for times, rad for widths";
  out["repeats"] = o.repeats;
  out["preset"] = "leeway";
  out["safety"] = {{"mode", "certified"},
                   {"margin", kSafety.margin},
                   {"max_leaves", kSafety.max_leaves},
                   {"lever_max_leaves", o.lever_max_leaves}};
  out["box_leaves"] = o.box_leaves;
  out["machine"] = {{"nproc", online_cpus()}, {"cpu", cpu_model()}, {"date", utc_now()}};
  out["rows"] = json::array();
  return out;
}

// The command, the description of the table and its header.
void print_header(const Options& o) {
  std::printf("# command: %s\n\n", o.command.c_str());
  std::printf(
      "Certificate bounds on the nine thesis paths (keyframes, 2 waypoints), preset leeway, %d repeat(s), "
      "medians. Guide: compute_bounds with safety none (its whole run timed). Taylor / lever: make_safe "
      "on a copy of the guide, certified, margin %.3g m, max_leaves %d per segment test%s. Widths: mean "
      "upper - lower over the waypoints, of the three bisected hinge joints (B3) and of all joints; ratio "
      "= certified / guide. Boxes: region_free with the row's bound on each waypoint box [lower, upper], "
      "budget %ld leaves per box, leaves summed over the waypoints; guide boxes are the guide's own, "
      "Taylor-safe boxes those the Taylor make_safe of the same path left (free, so both bounds can be "
      "compared on them). \"collision\": an exact check found a configuration of the box within the "
      "margin of an obstacle, which no certificate can pass.\n\n",
      o.repeats, kSafety.margin, kSafety.max_leaves,
      o.lever_max_leaves == kSafety.max_leaves
          ? " (both bounds)"
          : (" (lever: its own max_leaves " + std::to_string(o.lever_max_leaves) + ")").c_str(),
      o.box_leaves);
  std::printf(
      "| cell | path | bound | certified | leaves | time ms | B3 width rad | all width rad | B3 ratio |"
      " all ratio | guide boxes: leaves | Taylor-safe boxes: leaves |\n");
  std::printf("|---|---|---|---|---:|---:|---:|---:|---:|---:|---|---|\n");
  std::fflush(stdout);
}

// The counts and ratios over all paths that the summary reports; [b] is per bound (Taylor, lever).
struct Tally {
  std::vector<double> leaf_ratio, time_ratio, box_ratio;  //!< Taylor / lever, per path
  int certified_paths[2] = {0, 0};                        //!< paths make_safe certified
  int guide_boxes_ok[2] = {0, 0};                         //!< paths whose guide boxes were certified
  int safe_boxes_ok[2] = {0, 0};                          //!< paths whose Taylor-safe boxes were certified
  std::vector<double> b3_ratio[2];                        //!< B3 width ratio, per path
};

// One work cell as the paths use it: the scene, the guide's parameters (safety none), its volume
// model and the joint masks the widths are averaged over.
struct CellSetup {
  const std::string& name;
  const leeway::Scene& scene;
  const leeway::Params& params;
  leeway::VolumeModel& world;
  const std::vector<bool>& bisected;
  const std::vector<bool>& all;
};

// The guide (safety none) of one path, computed `repeats` times: the last run's bounds and every
// run's time [ms].
struct Guide {
  std::vector<leeway::WaypointBounds> bounds;
  std::vector<double> ms;
  double width_b3 = 0, width_all = 0;  //!< mean widths of the last run's bounds
};

Guide run_guide(const CellSetup& c, const std::vector<Eigen::VectorXd>& path, int repeats) {
  Guide g;
  for (int r = 0; r < repeats; ++r) {
    const double t0 = now_ms();
    auto run = leeway::compute_bounds(c.scene, c.world, path, c.params, 1);
    g.ms.push_back(now_ms() - t0);
    g.bounds = std::move(run.bounds);
  }
  g.width_b3 = mean_width(g.bounds, c.bisected);
  g.width_all = mean_width(g.bounds, c.all);
  return g;
}

// make_safe with each bound of kBounds on a copy of the guide, `repeats` times: per bound the last
// run's report and bounds, every run's time [ms] and the leaf budget it was given.
struct SafeRuns {
  std::vector<leeway::SafetyReport> reports;
  std::vector<std::vector<leeway::WaypointBounds>> safe;
  std::vector<std::vector<double>> runs;
  std::vector<int> max_leaves;
};

SafeRuns run_make_safe(const leeway::Scene& scene, const std::vector<leeway::WaypointBounds>& guide,
                       const Options& o) {
  SafeRuns s;
  s.reports.resize(kBounds.size());
  s.safe.resize(kBounds.size());
  s.runs.resize(kBounds.size());
  s.max_leaves.resize(kBounds.size());
  for (size_t b = 0; b < kBounds.size(); ++b) {
    leeway::SafetyParams sp = kSafety;
    if (kBounds[b] == &kLeverBound) sp.max_leaves = static_cast<int>(o.lever_max_leaves);
    s.max_leaves[b] = sp.max_leaves;
    for (int r = 0; r < o.repeats; ++r) {
      s.safe[b] = guide;
      const double t0 = now_ms();
      s.reports[b] = leeway::make_safe(scene, s.safe[b], sp, 1, kBounds[b]);
      s.runs[b].push_back(now_ms() - t0);
    }
  }
  return s;
}

// What the Taylor / lever ratios of a path need from one bound's row.
struct BoundTotals {
  long leaves = 0;  //!< make_safe leaves
  double ms = 0;    //!< make_safe median time
  long box = -1;    //!< Taylor-safe box leaves, -1 when not certified
};

// One bound's row of a path: certifies the guide's boxes and the Taylor-safe boxes with the bound,
// prints the table row, appends the JSON row to rows and counts the path in the tally.
BoundTotals bound_row(const CellSetup& c, const std::string& label, const Guide& guide, const SafeRuns& s,
                      size_t b, const Options& o, Tally& t, json& rows) {
  const double g3 = guide.width_b3, gall = guide.width_all;
  const leeway::SafetyReport& report = s.reports[b];
  const BoxResult boxes = certify_boxes(c.scene, guide.bounds, kBounds[b], o.box_leaves);
  const BoxResult free_boxes = certify_boxes(c.scene, s.safe[0], kBounds[b], o.box_leaves);
  const double w3 = mean_width(s.safe[b], c.bisected), wall = mean_width(s.safe[b], c.all);
  const double r3 = g3 > 0 ? w3 / g3 : 0.0, rall = gall > 0 ? wall / gall : 0.0;
  BoundTotals totals;
  totals.leaves = report.stats.leaves;
  totals.ms = median(s.runs[b]);
  totals.box = free_boxes.certified ? free_boxes.leaves : -1;
  t.certified_paths[b] += report.all_passed ? 1 : 0;
  t.guide_boxes_ok[b] += boxes.certified ? 1 : 0;
  t.safe_boxes_ok[b] += free_boxes.certified ? 1 : 0;
  t.b3_ratio[b].push_back(r3);
  std::printf("| %s | %s | %s | %s | %ld | %.1f | %.4f | %.4f | %.3f | %.3f | %s | %s |\n", c.name.c_str(),
              label.c_str(), bound_name(kBounds[b]), report.all_passed ? "yes" : "no", report.stats.leaves,
              totals.ms, w3, wall, r3, rall, box_cell(boxes).c_str(), box_cell(free_boxes).c_str());
  std::fflush(stdout);
  json segs = json::array();
  for (const auto& seg : report.segments)
    segs.push_back({{"passed", seg.passed},
                    {"leaves", seg.leaves},
                    {"max_depth", seg.max_depth},
                    {"shrink_steps", seg.shrink_steps}});
  json lower = json::array(), upper = json::array();
  for (const auto& w : s.safe[b]) {
    lower.push_back(std::vector<double>(w.lower.data(), w.lower.data() + w.lower.size()));
    upper.push_back(std::vector<double>(w.upper.data(), w.upper.data() + w.upper.size()));
  }
  rows.push_back({{"cell", c.name},
                  {"path", label},
                  {"bound", bound_name(kBounds[b])},
                  {"max_leaves", s.max_leaves[b]},
                  {"certified", report.all_passed},
                  {"leaves", report.stats.leaves},
                  {"max_depth", report.stats.max_depth},
                  {"pair_tests", report.stats.pair_tests},
                  {"segments", segs},
                  {"ms", totals.ms},
                  {"ms_runs", s.runs[b]},
                  {"width_b3", w3},
                  {"width_all", wall},
                  {"ratio_b3", r3},
                  {"ratio_all", rall},
                  {"lower", lower},
                  {"upper", upper},
                  {"guide_boxes", box_json(boxes, o.box_leaves)},
                  {"taylor_safe_boxes", box_json(free_boxes, o.box_leaves)}});
  return totals;
}

// One path of a cell: the guide row, then make_safe and the box certificates with each bound, one
// row per bound; adds the path's Taylor / lever ratios to the tally.
void bench_path(const CellSetup& c, const std::string& from, const std::string& to, const Options& o,
                Tally& t, json& rows) {
  const std::string label = from + " -> " + to;
  const auto path = leeway::keyframe_path(c.scene, from, to, 2);
  const Guide guide = run_guide(c, path, o.repeats);
  const double g3 = guide.width_b3, gall = guide.width_all;
  std::printf("| %s | %s | guide (none) | - | - | %.1f | %.4f | %.4f | 1 | 1 | - | - |\n", c.name.c_str(),
              label.c_str(), median(guide.ms), g3, gall);
  std::fflush(stdout);
  json row_guide = {{"cell", c.name},      {"path", label},  {"bound", "guide"}, {"ms", median(guide.ms)},
                    {"ms_runs", guide.ms}, {"width_b3", g3}, {"width_all", gall}};
  rows.push_back(row_guide);
  const SafeRuns safe = run_make_safe(c.scene, guide.bounds, o);
  BoundTotals totals[2];
  for (size_t b = 0; b < kBounds.size(); ++b) totals[b] = bound_row(c, label, guide, safe, b, o, t, rows);
  if (totals[1].leaves > 0)
    t.leaf_ratio.push_back(static_cast<double>(totals[0].leaves) / static_cast<double>(totals[1].leaves));
  if (totals[1].ms > 0) t.time_ratio.push_back(totals[0].ms / totals[1].ms);
  if (totals[0].box > 0 && totals[1].box > 0)
    t.box_ratio.push_back(static_cast<double>(totals[0].box) / static_cast<double>(totals[1].box));
}

// Loads one work cell and benches its paths.
void bench_cell(const std::string& cell, const Options& o, Tally& t, json& rows) {
  const std::string file = std::string(LEEWAY_MJCF_DIR) + "/workcells/" + cell + ".xml";
  const leeway::Scene scene = leeway::Scene::load(file);
  leeway::Params p = leeway::preset_params("leeway");
  leeway::apply_cell_defaults(scene, p);
  p.safety.mode = leeway::SafetyMode::kNone;
  leeway::VolumeModel world(scene, p.height_map.max_cells + static_cast<int>(scene.obstacle_geoms().size()));
  const auto bound_kinds = leeway::bound_kinds(scene, p.bounds);
  std::vector<bool> bisected, all(static_cast<size_t>(scene.dof()), true);
  for (const auto k : bound_kinds) bisected.push_back(k == leeway::BoundKind::kBisected);
  const CellSetup setup{cell, scene, p, world, bisected, all};
  for (const auto& [from, to] : kPaths) bench_path(setup, from, to, o, t, rows);
}

// The summary line after the table: counts and median ratios over all paths, and the machine.
void print_summary(const Tally& t, double total_s) {
  std::printf(
      "\nSummary over %zu paths (Taylor vs lever): make_safe certified %d vs %d, median B3 ratio %.3f vs "
      "%.3f; "
      "median Taylor / lever ratio of make_safe leaves %.3g and time %.3g; guide boxes certified %d vs %d; "
      "Taylor-safe boxes certified %d vs %d, median Taylor / lever leaves %s. Machine: %d CPUs (nproc), %s; "
      "%s; bench wall time %.0f s.\n",
      t.b3_ratio[0].size(), t.certified_paths[0], t.certified_paths[1], median_or_zero(t.b3_ratio[0]),
      median_or_zero(t.b3_ratio[1]), median_or_zero(t.leaf_ratio), median_or_zero(t.time_ratio),
      t.guide_boxes_ok[0], t.guide_boxes_ok[1], t.safe_boxes_ok[0], t.safe_boxes_ok[1],
      t.box_ratio.empty() ? "n/a (the lever bound certified none within the budget)"
                          : std::to_string(median_or_zero(t.box_ratio)).c_str(),
      online_cpus(), cpu_model().c_str(), utc_now().c_str(), total_s);
}

// The same summary for the JSON document.
json summary_json(const Tally& t, double total_s) {
  return {{"paths", t.b3_ratio[0].size()},
          {"certified_paths", {{"Taylor", t.certified_paths[0]}, {"lever", t.certified_paths[1]}}},
          {"median_ratio_b3",
           {{"Taylor", median_or_zero(t.b3_ratio[0])}, {"lever", median_or_zero(t.b3_ratio[1])}}},
          {"guide_boxes_certified", {{"Taylor", t.guide_boxes_ok[0]}, {"lever", t.guide_boxes_ok[1]}}},
          {"taylor_safe_boxes_certified", {{"Taylor", t.safe_boxes_ok[0]}, {"lever", t.safe_boxes_ok[1]}}},
          {"median_taylor_over_lever_leaves", median_or_zero(t.leaf_ratio)},
          {"median_taylor_over_lever_ms", median_or_zero(t.time_ratio)},
          {"median_taylor_over_lever_taylor_safe_box_leaves",
           t.box_ratio.empty() ? json(nullptr) : json(median_or_zero(t.box_ratio))},
          {"box_paths_both_certified", t.box_ratio.size()},
          {"bench_seconds", total_s}};
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse_options(argc, argv, o)) return 2;
  const double start = now_ms();
  json out = run_json(o);
  Tally tally;
  try {
    print_header(o);
    for (const auto& cell : split(o.cells_list)) bench_cell(cell, o, tally, out["rows"]);
  } catch (const leeway::InputError& e) {
    std::cerr << "leeway-bench-certify: error: " << e.what() << "\n";
    return 2;
  }
  const double total_s = (now_ms() - start) / 1000;
  print_summary(tally, total_s);
  out["summary"] = summary_json(tally, total_s);
  if (!o.json_file.empty()) {
    try {
      leeway::write_file_atomic(o.json_file, out.dump(2) + "\n");
    } catch (const leeway::InputError& e) {
      std::cerr << "leeway-bench-certify: error: " << e.what() << "\n";
      return 2;
    }
  }
  return 0;
}
