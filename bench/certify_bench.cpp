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

}  // namespace

int main(int argc, char** argv) {
  int repeats = 3;
  std::string cells_list = "dallara,baltico,dlr", json_file;
  const leeway::SafetyParams safety;  // the defaults: certified, margin 1 mm, 16384 leaves per test
  long lever_max_leaves = safety.max_leaves, box_leaves = 1000000;
  std::string command = argv[0];
  for (int i = 1; i < argc; ++i) command += std::string(" ") + argv[i];
  for (int i = 1; i < argc; i += 2) {
    const std::string k = argv[i];
    if (i + 1 >= argc) {
      std::cerr << "option " << k << " needs a value\n";
      return 2;
    }
    const std::string v = argv[i + 1];
    if (k == "--repeats")
      repeats = std::atoi(v.c_str());
    else if (k == "--cells")
      cells_list = v;
    else if (k == "--json")
      json_file = v;
    else if (k == "--lever-max-leaves")
      lever_max_leaves = std::atol(v.c_str());
    else if (k == "--box-leaves")
      box_leaves = std::atol(v.c_str());
    else {
      std::cerr << "unknown option " << k << "\n";
      return 2;
    }
  }
  if (repeats < 1 || lever_max_leaves < 1 || box_leaves < 1) {
    std::cerr << "--repeats, --lever-max-leaves and --box-leaves must be >= 1\n";
    return 2;
  }
  const std::vector<std::pair<std::string, std::string>> paths = {
      {"home", "patch"}, {"patch", "mould"}, {"mould", "home"}};
  const std::vector<const leeway::SweepBound*> kinds = {nullptr, &kLeverBound};
  const double start = now_ms();
  json out;
  out["command"] = command;
  out["units"] = "ms for times, rad for widths";
  out["repeats"] = repeats;
  out["preset"] = "leeway";
  out["safety"] = {{"mode", "certified"},
                   {"margin", safety.margin},
                   {"max_leaves", safety.max_leaves},
                   {"lever_max_leaves", lever_max_leaves}};
  out["box_leaves"] = box_leaves;
  out["machine"] = {{"nproc", online_cpus()}, {"cpu", cpu_model()}, {"date", utc_now()}};
  out["rows"] = json::array();
  std::vector<double> leaf_ratio, time_ratio, box_ratio;
  // Per bound (Taylor, lever): paths make_safe certified, guide and Taylor-safe box sets certified,
  // and the B3 width ratios.
  int certified_paths[2] = {0, 0}, guide_boxes_ok[2] = {0, 0}, safe_boxes_ok[2] = {0, 0};
  std::vector<double> b3_ratio[2];
  try {
    std::printf("# command: %s\n\n", command.c_str());
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
        repeats, safety.margin, safety.max_leaves,
        lever_max_leaves == safety.max_leaves
            ? " (both bounds)"
            : (" (lever: its own max_leaves " + std::to_string(lever_max_leaves) + ")").c_str(),
        box_leaves);
    std::printf(
        "| cell | path | bound | certified | leaves | time ms | B3 width rad | all width rad | B3 ratio |"
        " all ratio | guide boxes: leaves | Taylor-safe boxes: leaves |\n");
    std::printf("|---|---|---|---|---:|---:|---:|---:|---:|---:|---|---|\n");
    std::fflush(stdout);
    for (const auto& cell : split(cells_list)) {
      const std::string file = std::string(LEEWAY_MJCF_DIR) + "/workcells/" + cell + ".xml";
      const leeway::Scene scene = leeway::Scene::load(file);
      leeway::Params p = leeway::preset_params("leeway");
      leeway::apply_cell_defaults(scene, p);
      p.safety.mode = leeway::SafetyMode::kNone;
      leeway::VolumeModel world(scene,
                                p.height_map.max_cells + static_cast<int>(scene.obstacle_geoms().size()));
      const auto bound_kinds = leeway::bound_kinds(scene, p.bounds);
      std::vector<bool> bisected, all(static_cast<size_t>(scene.dof()), true);
      for (const auto k : bound_kinds) bisected.push_back(k == leeway::BoundKind::kBisected);
      for (const auto& [from, to] : paths) {
        const std::string label = from + " -> " + to;
        const auto path = leeway::keyframe_path(scene, from, to, 2);
        std::vector<double> guide_ms;
        std::vector<leeway::WaypointBounds> guide;
        for (int r = 0; r < repeats; ++r) {
          const double t0 = now_ms();
          auto run = leeway::compute_bounds(scene, world, path, p, 1);
          guide_ms.push_back(now_ms() - t0);
          guide = std::move(run.bounds);
        }
        const double g3 = mean_width(guide, bisected), gall = mean_width(guide, all);
        std::printf("| %s | %s | guide (none) | - | - | %.1f | %.4f | %.4f | 1 | 1 | - | - |\n", cell.c_str(),
                    label.c_str(), median(guide_ms), g3, gall);
        std::fflush(stdout);
        json row_guide = {{"cell", cell},           {"path", label},       {"bound", "guide"},
                          {"ms", median(guide_ms)}, {"ms_runs", guide_ms}, {"width_b3", g3},
                          {"width_all", gall}};
        out["rows"].push_back(row_guide);
        // make_safe with each bound (Taylor first: its certified waypoint boxes are the free boxes
        // both bounds are then asked to certify).
        std::vector<leeway::SafetyReport> reports(kinds.size());
        std::vector<std::vector<leeway::WaypointBounds>> safe(kinds.size());
        std::vector<std::vector<double>> runs(kinds.size());
        std::vector<int> max_leaves(kinds.size());
        for (size_t b = 0; b < kinds.size(); ++b) {
          leeway::SafetyParams sp = safety;
          if (kinds[b] == &kLeverBound) sp.max_leaves = static_cast<int>(lever_max_leaves);
          max_leaves[b] = sp.max_leaves;
          for (int r = 0; r < repeats; ++r) {
            safe[b] = guide;
            const double t0 = now_ms();
            reports[b] = leeway::make_safe(scene, safe[b], sp, 1, kinds[b]);
            runs[b].push_back(now_ms() - t0);
          }
        }
        long leaves[2] = {0, 0}, box[2] = {-1, -1};
        double ms[2] = {0, 0};
        for (size_t b = 0; b < kinds.size(); ++b) {
          const leeway::SafetyReport& report = reports[b];
          const BoxResult boxes = certify_boxes(scene, guide, kinds[b], box_leaves);
          const BoxResult free_boxes = certify_boxes(scene, safe[0], kinds[b], box_leaves);
          const double w3 = mean_width(safe[b], bisected), wall = mean_width(safe[b], all);
          const double r3 = g3 > 0 ? w3 / g3 : 0.0, rall = gall > 0 ? wall / gall : 0.0;
          leaves[b] = report.stats.leaves;
          ms[b] = median(runs[b]);
          box[b] = free_boxes.certified ? free_boxes.leaves : -1;
          certified_paths[b] += report.all_passed ? 1 : 0;
          guide_boxes_ok[b] += boxes.certified ? 1 : 0;
          safe_boxes_ok[b] += free_boxes.certified ? 1 : 0;
          b3_ratio[b].push_back(r3);
          std::printf("| %s | %s | %s | %s | %ld | %.1f | %.4f | %.4f | %.3f | %.3f | %s | %s |\n",
                      cell.c_str(), label.c_str(), bound_name(kinds[b]), report.all_passed ? "yes" : "no",
                      report.stats.leaves, ms[b], w3, wall, r3, rall, box_cell(boxes).c_str(),
                      box_cell(free_boxes).c_str());
          std::fflush(stdout);
          json segs = json::array();
          for (const auto& s : report.segments)
            segs.push_back({{"passed", s.passed},
                            {"leaves", s.leaves},
                            {"max_depth", s.max_depth},
                            {"shrink_steps", s.shrink_steps}});
          json lower = json::array(), upper = json::array();
          for (const auto& w : safe[b]) {
            lower.push_back(std::vector<double>(w.lower.data(), w.lower.data() + w.lower.size()));
            upper.push_back(std::vector<double>(w.upper.data(), w.upper.data() + w.upper.size()));
          }
          out["rows"].push_back({{"cell", cell},
                                 {"path", label},
                                 {"bound", bound_name(kinds[b])},
                                 {"max_leaves", max_leaves[b]},
                                 {"certified", report.all_passed},
                                 {"leaves", report.stats.leaves},
                                 {"max_depth", report.stats.max_depth},
                                 {"pair_tests", report.stats.pair_tests},
                                 {"segments", segs},
                                 {"ms", ms[b]},
                                 {"ms_runs", runs[b]},
                                 {"width_b3", w3},
                                 {"width_all", wall},
                                 {"ratio_b3", r3},
                                 {"ratio_all", rall},
                                 {"lower", lower},
                                 {"upper", upper},
                                 {"guide_boxes", box_json(boxes, box_leaves)},
                                 {"taylor_safe_boxes", box_json(free_boxes, box_leaves)}});
        }
        if (leaves[1] > 0)
          leaf_ratio.push_back(static_cast<double>(leaves[0]) / static_cast<double>(leaves[1]));
        if (ms[1] > 0) time_ratio.push_back(ms[0] / ms[1]);
        if (box[0] > 0 && box[1] > 0)
          box_ratio.push_back(static_cast<double>(box[0]) / static_cast<double>(box[1]));
      }
    }
  } catch (const leeway::InputError& e) {
    std::cerr << "leeway-bench-certify: error: " << e.what() << "\n";
    return 2;
  }
  const double total_s = (now_ms() - start) / 1000;
  auto med = [](const std::vector<double>& v) { return v.empty() ? 0.0 : median(v); };
  const size_t n = b3_ratio[0].size();
  std::printf(
      "\nSummary over %zu paths (Taylor vs lever): make_safe certified %d vs %d, median B3 ratio %.3f vs "
      "%.3f; "
      "median Taylor / lever ratio of make_safe leaves %.3g and time %.3g; guide boxes certified %d vs %d; "
      "Taylor-safe boxes certified %d vs %d, median Taylor / lever leaves %s. Machine: %d CPUs (nproc), %s; "
      "%s; bench wall time %.0f s.\n",
      n, certified_paths[0], certified_paths[1], med(b3_ratio[0]), med(b3_ratio[1]), med(leaf_ratio),
      med(time_ratio), guide_boxes_ok[0], guide_boxes_ok[1], safe_boxes_ok[0], safe_boxes_ok[1],
      box_ratio.empty() ? "n/a (the lever bound certified none within the budget)"
                        : std::to_string(med(box_ratio)).c_str(),
      online_cpus(), cpu_model().c_str(), utc_now().c_str(), total_s);
  out["summary"] = {
      {"paths", n},
      {"certified_paths", {{"Taylor", certified_paths[0]}, {"lever", certified_paths[1]}}},
      {"median_ratio_b3", {{"Taylor", med(b3_ratio[0])}, {"lever", med(b3_ratio[1])}}},
      {"guide_boxes_certified", {{"Taylor", guide_boxes_ok[0]}, {"lever", guide_boxes_ok[1]}}},
      {"taylor_safe_boxes_certified", {{"Taylor", safe_boxes_ok[0]}, {"lever", safe_boxes_ok[1]}}},
      {"median_taylor_over_lever_leaves", med(leaf_ratio)},
      {"median_taylor_over_lever_ms", med(time_ratio)},
      {"median_taylor_over_lever_taylor_safe_box_leaves",
       box_ratio.empty() ? json(nullptr) : json(med(box_ratio))},
      {"box_paths_both_certified", box_ratio.size()},
      {"bench_seconds", total_s}};
  if (!json_file.empty()) {
    try {
      leeway::write_file_atomic(json_file, out.dump(2) + "\n");
    } catch (const leeway::InputError& e) {
      std::cerr << "leeway-bench-certify: error: " << e.what() << "\n";
      return 2;
    }
  }
  return 0;
}
