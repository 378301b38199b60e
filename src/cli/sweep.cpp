#include "cli/sweep.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "cli/plot.hpp"
#include "leeway/apps/tuning.hpp"
#include "leeway/core/file_io.hpp"
#include "leeway/core/mjcf_source.hpp"
#include "leeway/core/pipeline.hpp"
#include "leeway/path/nominal_path.hpp"
#include "leeway/path/path_check.hpp"

namespace leeway::cli {

const char* const kThesisCells =
    "100,150,200,500,750,1000,1500,2000,3000,5000,7500,10000,12000,15000,20000,25000,30000,40000,50000,"
    "100000";

std::vector<int> parse_cells_list(const std::string& text) {
  // parse_vector skips empty items; in a list of cells "1,,2" is more likely a mistake.
  std::string item;
  int index = 0;
  for (const char c : text + ",") {
    if (c != ',') {
      if (!std::isspace(static_cast<unsigned char>(c))) item += c;
      continue;
    }
    ++index;
    if (item.empty())
      throw InputError("--max-cells '" + text + "': value " + std::to_string(index) + " is empty");
    item.clear();
  }
  std::vector<int> out;
  const Eigen::VectorXd v = parse_vector(text, "--max-cells");
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (v[i] != std::floor(v[i]) || v[i] < 1 || v[i] > kMaxCellsLimit)
      throw InputError("--max-cells value '" +
                       (std::abs(v[i]) < 1e15 && v[i] == std::floor(v[i])
                            ? std::to_string(static_cast<long long>(v[i]))
                            : format_number(v[i])) +
                       "' must be a whole number from 1 to 1000000");
    out.push_back(static_cast<int>(v[i]));
  }
  if (out.empty()) throw InputError("--max-cells lists no value");
  return out;
}

CLI::App* add_sweep(CLI::App& app, SweepArgs& args) {
  CLI::App* sub = app.add_subcommand(
      "sweep", "The thesis's table: for each MAX_cells, boxes, time [ms] and CF [%], as Markdown (and CSV)");
  sub->add_option("cell", args.cell, "MJCF file of the workcell")->required();
  add_checker_option(sub, args.checker);
  sub->add_option("--from", args.from,
                  "Start: a keyframe, site:NAME or xyz:X,Y,Z (planned as leeway bounds plans)")
      ->required();
  sub->add_option("--to", args.to, "Goal: a keyframe, site:NAME or xyz:X,Y,Z")->required();
  sub->add_option("--waypoints", args.waypoints, "Waypoints along the joint-linear path")
      ->capture_default_str();
  sub->add_flag("--no-plan", args.no_plan,
                "Exit 1 when the straight path between two keyframes collides instead of planning around it");
  sub->add_option("--max-cells", args.max_cells,
                  "Comma-separated MAX_cells values (default: the thesis's 20)");
  sub->add_option("--params", args.params, "Parameter file (JSON)")->check(file_name_check());
  add_preset_options(sub, args.preset, args.safety);
  add_joint_bounds_options(sub, args.joints);
  sub->add_option("--csv", args.csv, "Also write the table as CSV here")->check(file_name_check());
  sub->add_option("--plot", args.plot,
                  "Also plot boxes, time and CF against MAX_cells here (.svg or .png), beside the thesis's\n"
                  "published values when the case is one of its nine")
      ->check(file_name_check());
  sub->add_option("--windows", args.cf.windows, "CF windows")->capture_default_str();
  sub->add_option("--samples", args.cf.samples, "CF samples per window")->capture_default_str();
  sub->add_option("--seed", args.cf.seed, "CF random seed")
      ->check(seed_check_for(args.cf.seed))
      ->capture_default_str();
  sub->add_option("--threads", args.threads, "Worker threads")->capture_default_str();
  sub->final_callback([sub, &args] {
    args.windows_given = sub->count("--windows") > 0;
    args.samples_given = sub->count("--samples") > 0;
    args.seed_given = sub->count("--seed") > 0;
  });
  return sub;
}

int run_sweep(const SweepArgs& args) {
  const auto scene = Scene::load(args.cell, scene_options(kDefaultTool, args.checker));
  Params base = load_params(scene, args.preset, args.params, args.safety);
  apply_joint_bounds_options(scene, args.joints, base);
  // CF settings: the parameter file's cf section unless given on the command line.
  CfParams cf = args.cf;
  if (!args.windows_given) cf.windows = base.cf.windows;
  if (!args.samples_given) cf.samples = base.cf.samples;
  if (!args.seed_given) cf.seed = base.cf.seed;
  const std::vector<int> cells = parse_cells_list(args.max_cells);
  if (args.waypoints >= 2)
    require_memory(args.waypoints * kBytesPerWaypoint, "--waypoints " + std::to_string(args.waypoints));
  if (cf.windows >= 1)
    require_memory(cf.windows * kBytesPerWindow, "CF windows " + std::to_string(cf.windows));
  std::vector<std::string> inputs = model_input_files(args.cell);
  inputs.push_back(args.params);
  require_outputs({{args.plot, "--plot", {".svg", ".png"}}, {args.csv, "--csv", {}}}, inputs);
  // Rows are written as they finish (standard output and --csv, flushed), so that an interrupted
  // sweep keeps the rows it finished; the CSV is locked now, its old content kept until the first row.
  StreamingOutput csv_file;
  if (!args.csv.empty()) csv_file = StreamingOutput(args.csv, "--csv");
  require_threads(args.threads);
  // As leeway bounds: the nominal path is checked first, and a colliding straight path is planned
  // around (default planner options).
  PathRequest request;
  request.from = args.from;
  request.to = args.to;
  request.waypoints = args.waypoints;
  request.plan_around = !args.no_plan;
  const NominalPath nominal = resolve_nominal_path(scene, request);
  if (!report_refusal(nominal)) return kExitFindings;
  if (!nominal.replaced.empty()) std::cerr << nominal.replaced << "\n";
  const std::vector<Eigen::VectorXd>& path = nominal.waypoints;
  for (int c : cells) {
    Params p = base;
    p.height_map.max_cells = c;
    p.validate();
  }
  VolumeModel world(scene, VolumeModel::capacity_for(scene, *std::max_element(cells.begin(), cells.end())));
  if (csv_file.is_open()) csv_file.truncate();
  std::ostringstream no_csv;
  std::ostream& csv = csv_file.is_open() ? csv_file.stream() : no_csv;
  auto flush_csv = [&] { csv.flush(); };  // a failed write throws, naming the file
  std::ostream& md = std::cout;
  md << "| Max CBox | CBox | Computational Time [ms] | Confidence Factor [%] | 95 % CI [%] |"
        " worst window [%] | collapsed | mean width j1-j3 [rad] |\n"
     << "|---:|---:|---:|---:|---|---:|---:|---:|\n";
  md.flush();
  if (csv_file.is_open()) {
    csv << "max_cells,boxes,time_ms,volume_ms,bounds_ms,checks,cf,ci_low,ci_high,worst_window_cf,collapsed,"
           "mean_width\n";
    flush_csv();
  }
  SweepSeries plotted{"leeway", {}};
  for (int c : cells) {
    Params p = base;
    p.height_map.max_cells = c;
    const auto run = compute_bounds(scene, world, path, p, args.threads);
    const auto r = confidence_factor(scene, run.bounds, cf, args.threads);
    // Collapsed intervals and the mean width of the bisected joints' intervals.
    CaseEval stats;
    width_stats(scene, p.bounds, run.bounds, 0.0, stats);
    const int collapsed = stats.collapsed, bisected = stats.bisected;
    const double width = stats.mean_width;
    md << std::fixed << "| " << c << " | " << run.volume.boxes.size() << " | " << std::setprecision(1)
       << run.ms_total() << " | " << std::setprecision(4) << 100 * r.cf << " | " << 100 * r.ci_low << " .. "
       << 100 * r.ci_high << " | " << 100 * r.worst_window_cf << " | " << collapsed << "/" << bisected
       << " | " << std::setprecision(3) << width << " |\n";
    md.flush();
    if (csv_file.is_open()) {
      csv << c << "," << run.volume.boxes.size() << "," << std::setprecision(3) << run.ms_total() << ","
          << run.ms_volume << "," << run.ms_bounds << "," << run.checks << "," << std::setprecision(6) << r.cf
          << "," << r.ci_low << "," << r.ci_high << "," << r.worst_window_cf << "," << collapsed << ","
          << width << "\n";
      flush_csv();
    }
    plotted.points.push_back({c, static_cast<double>(run.volume.boxes.size()), run.ms_total(), 100 * r.cf});
    std::cerr << "max_cells " << c << " done\n";
  }
  if (!args.plot.empty()) write_sweep_plot(args.plot, args.cell, args.from, args.to, args.preset, plotted);
  return kExitOk;
}

}  // namespace leeway::cli
